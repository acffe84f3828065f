"""Displays seen through an ideal linear polariser (polarised sunglasses, a camera's filter) turned through a range
of angles: each display's luminance and chromaticity per angle, and the CIEDE2000 between them.

The analyser passes `transmitted_fraction` of each display's light (for an ideal one Malus's law cos²(θ − φ) for
light polarised at φ, ½ for unpolarised or circular light; a real one's principal transmittances k1, k2 can be given;
see `spectrace.spectral.display_polarization`); it is neutral, so the
chromaticity stays that of the display's colour and only the luminance changes. CIELAB is relative to the viewing
conditions' white without the polariser, as for a viewer adapted to the room rather than to the filter.
"""

from __future__ import annotations

from dataclasses import dataclass
from itertools import combinations

import numpy as np

from spectrace.displays.compare import display_colour
from spectrace.displays.viewing import ViewingConditions, delta_e_2000
from spectrace.errors import SpectraceError
from spectrace.spectral import xyz_to_xy
from spectrace.spectral.display import Display
from spectrace.spectral.display_polarization import check_principal_transmittances, transmitted_fraction
from spectrace.spectral.display_transfer import checked_rgb
from spectrace.spectral.observers import Observer

DEFAULT_ANGLES_DEG = tuple(float(angle) for angle in range(0, 181, 15))


@dataclass(frozen=True)
class SeenThrough:
    display: str
    polarization: str
    angle_deg: float
    fraction: float  # of the display's light the polariser passes
    xyz_cd_m2: np.ndarray  # CIE 1931, after the polariser

    @property
    def luminance_cd_m2(self) -> float:
        return float(self.xyz_cd_m2[1])

    @property
    def xy(self) -> np.ndarray:
        with np.errstate(invalid="ignore", divide="ignore"):
            return xyz_to_xy(self.xyz_cd_m2)


@dataclass(frozen=True)
class PolarizerComparison:
    rgb: np.ndarray
    viewing: ViewingConditions
    angles_deg: tuple[float, ...]
    transmittances: tuple[float, float]  # the polariser's k1, k2
    rows: list[list[SeenThrough]]  # one list per angle, one entry per display
    pair_delta_e: list[dict[tuple[str, str], float]]  # per angle, CIEDE2000 (1931 2°) of every pair

    def to_json(self) -> dict:
        return {
            "rgb": self.rgb.tolist(),
            "viewing": self.viewing.to_json(),
            "polarizer_transmittances": list(self.transmittances),
            "angles": [
                {
                    "angle_deg": angle,
                    "displays": [
                        {
                            "name": seen.display,
                            "polarization": seen.polarization,
                            "fraction": seen.fraction,
                            "luminance_cd_m2": seen.luminance_cd_m2,
                            "xy": seen.xy.tolist(),
                        }
                        for seen in row
                    ],
                    "pairs": [
                        {"first": first, "second": second, "delta_e_2000": value}
                        for (first, second), value in pairs.items()
                    ],
                }
                for angle, row, pairs in zip(self.angles_deg, self.rows, self.pair_delta_e)
            ],
        }


def through_polarizer(
    displays: list[Display],
    angles_deg: tuple[float, ...] = DEFAULT_ANGLES_DEG,
    rgb: np.ndarray | tuple[float, float, float] = (1.0, 1.0, 1.0),
    viewing: ViewingConditions | None = None,
    transmittances: tuple[float, float] = (1.0, 0.0),
) -> PolarizerComparison:
    """Each display showing `rgb`, seen through a linear polariser at each angle (degrees), of principal
    transmittances `transmittances` = (k1, k2): ideal by default."""
    rgb = checked_rgb(rgb)
    check_principal_transmittances(*transmittances, where="--transmittances")
    viewing = viewing or ViewingConditions()
    for display in displays:
        if not display.polarization.known:
            raise SpectraceError(
                f"the polarisation of {display.name}'s light is unknown; give it as "
                f"'{display.name}=linear <axis>', '=circular' or '=unpolarized'",
                where="--polarization",
            )
    colours = [display_colour(display, rgb, viewing) for display in displays]
    rows, pairs = [], []
    for angle in angles_deg:
        row = [
            SeenThrough(
                display=colour.display.name,
                polarization=colour.display.polarization.text(),
                angle_deg=float(angle),
                fraction=float(transmitted_fraction(colour.display.polarization, angle, *transmittances)),
                xyz_cd_m2=float(transmitted_fraction(colour.display.polarization, angle, *transmittances))
                * colour.xyz_cd_m2,
            )
            for colour in colours
        ]
        labs = [viewing.lab(seen.xyz_cd_m2, Observer.CIE_1931_2) for seen in row]
        pairs.append(
            {
                (row[i].display, row[j].display): float(delta_e_2000(labs[i], labs[j]))
                for i, j in combinations(range(len(row)), 2)
            }
        )
        rows.append(row)
    return PolarizerComparison(rgb, viewing, tuple(float(a) for a in angles_deg), transmittances, rows, pairs)
