"""The same RGB triple on several displays: each one's colour, and the CIEDE2000 difference of every pair under
each observer (a pair that agrees for the 1931 observer can disagree for another: observer metamerism)."""

from __future__ import annotations

from dataclasses import dataclass
from itertools import combinations

import numpy as np

from spectrace.displays.viewing import ViewingConditions, delta_e_2000, encoded_srgb_for_screen
from spectrace.spectral import xyz_to_xy
from spectrace.spectral.display import Display
from spectrace.spectral.display_transfer import checked_rgb
from spectrace.spectral.observers import ALL_OBSERVERS, Observer

# Linear sRGB this far outside [0, 1] still counts as inside the gamut (rounding of the matrices).
SRGB_GAMUT_TOLERANCE = 1e-6


@dataclass(frozen=True)
class DisplayColour:
    """One display's output for the triple; XYZ are photometric (683 lm/W), CIE 1931 Y in cd/m²."""

    display: Display  # as viewed: on the comparison's luminance scale
    drive: np.ndarray  # linear drive of the primaries
    xyz_cd_m2: np.ndarray  # CIE 1931
    lab: dict[Observer, np.ndarray]  # per observer, relative to the reference white
    linear_srgb: np.ndarray  # unclipped, sRGB white = the reference white

    @property
    def xy(self) -> np.ndarray:
        """NaN for black, which has no chromaticity."""
        with np.errstate(invalid="ignore", divide="ignore"):
            return xyz_to_xy(self.xyz_cd_m2)

    @property
    def luminance_cd_m2(self) -> float:
        return float(self.xyz_cd_m2[1])

    @property
    def srgb_in_gamut(self) -> bool:
        low, high = -SRGB_GAMUT_TOLERANCE, 1 + SRGB_GAMUT_TOLERANCE
        return bool(np.all((self.linear_srgb >= low) & (self.linear_srgb <= high)))

    @property
    def srgb(self) -> np.ndarray:
        """sRGB-encoded, clipped to [0, 1]: the patch to show on an sRGB screen."""
        return encoded_srgb_for_screen(self.linear_srgb)

    def to_json(self) -> dict:
        return {
            "name": self.display.name,
            "technology": self.display.technology,
            "radiance_scale": self.display.radiance_scale,
            "transfer": self.display.transfer.value,
            "drive": self.drive.tolist(),
            "xyz_cd_m2": self.xyz_cd_m2.tolist(),
            "xy": self.xy.tolist(),
            "luminance_cd_m2": self.luminance_cd_m2,
            "srgb": self.srgb.tolist(),
            "linear_srgb": self.linear_srgb.tolist(),
            "srgb_in_gamut": self.srgb_in_gamut,
            "lab": {observer.value: lab.tolist() for observer, lab in self.lab.items()},
        }


@dataclass(frozen=True)
class PairDifference:
    first: str
    second: str
    delta_e_2000: dict[Observer, float]

    def to_json(self) -> dict:
        return {
            "first": self.first,
            "second": self.second,
            "delta_e_2000": {observer.value: value for observer, value in self.delta_e_2000.items()},
        }


@dataclass(frozen=True)
class Comparison:
    rgb: np.ndarray
    viewing: ViewingConditions
    colours: list[DisplayColour]
    pairs: list[PairDifference]

    def to_json(self) -> dict:
        return {
            "rgb": self.rgb.tolist(),
            "viewing": self.viewing.to_json(),
            "observers": {observer.value: observer.label for observer in ALL_OBSERVERS},
            "displays": [colour.to_json() for colour in self.colours],
            "pairs": [pair.to_json() for pair in self.pairs],
        }


def display_colour(display: Display, rgb: np.ndarray, viewing: ViewingConditions) -> DisplayColour:
    """The triple on one display, with the display first put on the viewing conditions' luminance scale."""
    viewed = viewing.as_viewed(display)
    drive = viewed.drive(rgb)
    xyz_by_observer = {observer: viewed.primaries_matrix(observer) @ drive for observer in ALL_OBSERVERS}
    xyz_cie1931 = xyz_by_observer[Observer.CIE_1931_2]
    return DisplayColour(
        display=viewed,
        drive=drive,
        xyz_cd_m2=xyz_cie1931,
        lab={observer: viewing.lab(xyz, observer) for observer, xyz in xyz_by_observer.items()},
        linear_srgb=viewing.linear_srgb(xyz_cie1931),
    )


def compare_displays(
    displays: list[Display], rgb: np.ndarray | tuple[float, float, float], viewing: ViewingConditions | None = None
) -> Comparison:
    """Each display's colour for `rgb` (read with each display's transfer) and ΔE2000 of every pair."""
    rgb = checked_rgb(rgb)
    viewing = viewing or ViewingConditions()
    colours = [display_colour(display, rgb, viewing) for display in displays]
    pairs = [
        PairDifference(
            first=a.display.name,
            second=b.display.name,
            delta_e_2000={
                observer: float(delta_e_2000(a.lab[observer], b.lab[observer])) for observer in ALL_OBSERVERS
            },
        )
        for a, b in combinations(colours, 2)
    ]
    return Comparison(rgb=rgb, viewing=viewing, colours=colours, pairs=pairs)
