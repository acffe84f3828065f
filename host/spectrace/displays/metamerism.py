"""Illuminant metamerism of display light: two displays matched to show the same colour can light a room
differently, because their spectra differ. Per ColorChecker patch, the ΔE2000 between the patch lit by display A
showing a triple and lit by display B showing the triple that matches it (same CIE 1931 XYZ)."""

from dataclasses import dataclass

import colour
import numpy as np

from spectrace.displays.display import Display
from spectrace.displays.match import MatchResult, match_colour
from spectrace.displays.observers import photometric_xyz
from spectrace.displays.viewing import ViewingConditions
from spectrace.spectral.spectrum_io import colorchecker_patch_names, colorchecker_reflectance


@dataclass
class PatchDifference:
    patch: str
    lab_under_source: np.ndarray
    lab_under_target: np.ndarray
    delta_e_2000: float


@dataclass
class MetamerismReport:
    match: MatchResult
    patches: list[PatchDifference]

    @property
    def mean_delta_e(self) -> float:
        return float(np.mean([p.delta_e_2000 for p in self.patches]))

    @property
    def max_delta_e(self) -> float:
        return float(np.max([p.delta_e_2000 for p in self.patches]))

    def to_json(self) -> dict:
        return {
            "source": self.match.source.name,
            "target": self.match.target.name,
            "source_drive": self.match.source_drive.tolist(),
            "target_drive": self.match.target_drive.tolist(),
            "screens_delta_e_2000": float(self.match.delta_e_2000[list(self.match.delta_e_2000)[0]]),
            "patches": [{"patch": p.patch, "lab_under_source": p.lab_under_source.tolist(),
                         "lab_under_target": p.lab_under_target.tolist(), "delta_e_2000": p.delta_e_2000}
                        for p in self.patches],
            "mean_delta_e_2000": self.mean_delta_e,
            "max_delta_e_2000": self.max_delta_e,
        }


def patch_metamerism(source: Display, rgb, target: Display, viewing: ViewingConditions | None = None
                     ) -> MetamerismReport:
    """Each ColorChecker patch lit by `source` showing `rgb` vs lit by `target` showing the matching triple.
    CIELAB uses the light itself as the white (a perfect reflector under it), the same for both halves, since the
    matched lights have the same XYZ."""
    match = match_colour(source, rgb, target, viewing)
    light_source = match.source.emission_from_drive(match.source_drive)
    light_target = match.target.emission_from_drive(match.target_drive)
    white = photometric_xyz(light_source)
    white_xy = colour.XYZ_to_xy(white)
    patches = []
    for name in colorchecker_patch_names():
        reflectance = colorchecker_reflectance(name).values
        lab_a = colour.XYZ_to_Lab(photometric_xyz(reflectance * light_source) / white[1], white_xy)
        lab_b = colour.XYZ_to_Lab(photometric_xyz(reflectance * light_target) / white[1], white_xy)
        patches.append(PatchDifference(name, lab_a, lab_b, float(colour.delta_E(lab_a, lab_b, method="CIE 2000"))))
    return MetamerismReport(match, patches)
