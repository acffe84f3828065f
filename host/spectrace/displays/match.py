"""Which RGB on display B emits the colour a triple emits on display A (for the CIE 1931 observer).

Both displays are first put on the same luminance scale (`ViewingConditions`). The target is display A's CIE 1931
XYZ; B's emission is linear in its drive, XYZ = M_B d, so the exact match is d = M_B^-1 XYZ. When that d leaves
[0, 1]^3 the colour is outside B's gamut (or brighter than B's white) and the closest drive is the one that
minimises CIEDE2000 over [0, 1]^3 (bounded quasi-Newton from a few starts). The residual ΔE2000 is then reported
for every observer: a match exact for the 1931 observer is, with different primaries, a metameric pair, and other
observers can see the two emissions differ.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import lsq_linear, minimize

from spectrace.displays.viewing import ViewingConditions, delta_e_2000
from spectrace.spectral.display import Display
from spectrace.spectral.display_transfer import checked_rgb, encode_drive
from spectrace.spectral.observers import ALL_OBSERVERS, Observer

MATCH_OBSERVER = Observer.CIE_1931_2
# A solved drive this far outside [0, 1] is rounding, still in gamut.
GAMUT_TOLERANCE = 1e-9


@dataclass(frozen=True)
class MatchResult:
    source: Display  # as viewed
    target: Display  # as viewed
    rgb: np.ndarray  # the triple on the source, as given
    source_drive: np.ndarray
    exact_drive: np.ndarray  # M_B^-1 XYZ, unconstrained: outside [0, 1]^3 when out of gamut
    target_drive: np.ndarray  # in [0, 1]^3
    in_gamut: bool
    source_xyz_cd_m2: np.ndarray  # CIE 1931
    target_xyz_cd_m2: np.ndarray  # CIE 1931, of the returned drive
    delta_e_2000: dict[Observer, float]

    @property
    def target_rgb(self) -> np.ndarray:
        """The matched triple on the target, encoded with the target's transfer (as the input was)."""
        return encode_drive(self.target_drive, self.target.transfer)

    def to_json(self) -> dict:
        return {
            "from": self.source.name,
            "to": self.target.name,
            "rgb": self.rgb.tolist(),
            "transfer": {"from": self.source.transfer.value, "to": self.target.transfer.value},
            "from_drive": self.source_drive.tolist(),
            "to_rgb": self.target_rgb.tolist(),
            "to_drive": self.target_drive.tolist(),
            "exact_drive": self.exact_drive.tolist(),
            "in_gamut": self.in_gamut,
            "from_xyz_cd_m2": self.source_xyz_cd_m2.tolist(),
            "to_xyz_cd_m2": self.target_xyz_cd_m2.tolist(),
            "delta_e_2000": {observer.value: value for observer, value in self.delta_e_2000.items()},
        }


def _closest_drive_in_gamut(target: Display, xyz_goal: np.ndarray, viewing: ViewingConditions) -> np.ndarray:
    """The drive in [0, 1]^3 whose CIE 1931 colour is closest (CIEDE2000) to `xyz_goal`."""
    matrix = target.primaries_matrix(MATCH_OBSERVER)
    lab_goal = viewing.lab(xyz_goal, MATCH_OBSERVER)

    def difference(drive: np.ndarray) -> float:
        return float(delta_e_2000(viewing.lab(matrix @ drive, MATCH_OBSERVER), lab_goal))

    scale = viewing.white_luminance_cd_m2
    starts = [
        np.clip(np.linalg.solve(matrix, xyz_goal), 0.0, 1.0),
        lsq_linear(matrix / scale, xyz_goal / scale, bounds=(0.0, 1.0)).x,
        np.full(3, 0.5),
    ]
    best = min(
        (
            minimize(difference, start, method="L-BFGS-B", bounds=[(0.0, 1.0)] * 3, options={"ftol": 1e-12})
            for start in starts
        ),
        key=lambda result: result.fun,
    )
    return np.clip(best.x, 0.0, 1.0)


def match_colour(
    source: Display,
    rgb: np.ndarray | tuple[float, float, float],
    target: Display,
    viewing: ViewingConditions | None = None,
) -> MatchResult:
    """The drive on `target` whose emission has the CIE 1931 XYZ of `rgb` on `source`, or the closest in gamut."""
    rgb = checked_rgb(rgb)
    viewing = viewing or ViewingConditions()
    source_viewed, target_viewed = viewing.as_viewed(source), viewing.as_viewed(target)
    source_drive = source_viewed.drive(rgb)
    xyz_goal = source_viewed.primaries_matrix(MATCH_OBSERVER) @ source_drive

    exact_drive = np.linalg.solve(target_viewed.primaries_matrix(MATCH_OBSERVER), xyz_goal)
    in_gamut = bool(np.all((exact_drive >= -GAMUT_TOLERANCE) & (exact_drive <= 1 + GAMUT_TOLERANCE)))
    if in_gamut:
        target_drive = np.clip(exact_drive, 0.0, 1.0)
    else:
        target_drive = _closest_drive_in_gamut(target_viewed, xyz_goal, viewing)

    differences = {}
    for observer in ALL_OBSERVERS:
        lab_source = viewing.lab(source_viewed.primaries_matrix(observer) @ source_drive, observer)
        lab_target = viewing.lab(target_viewed.primaries_matrix(observer) @ target_drive, observer)
        differences[observer] = float(delta_e_2000(lab_source, lab_target))
    return MatchResult(
        source=source_viewed,
        target=target_viewed,
        rgb=rgb,
        source_drive=source_drive,
        exact_drive=exact_drive,
        target_drive=target_drive,
        in_gamut=in_gamut,
        source_xyz_cd_m2=xyz_goal,
        target_xyz_cd_m2=target_viewed.primaries_matrix(MATCH_OBSERVER) @ target_drive,
        delta_e_2000=differences,
    )
