"""Illuminant metamerism of display light: two displays matched to show the same colour can light a room
differently, because their spectra differ. Per ColorChecker patch, the ΔE2000 between the patch lit by display A
showing a triple and lit by display B showing the triple that matches it (same CIE 1931 XYZ)."""

from collections.abc import Callable
from dataclasses import dataclass

import colour
import numpy as np

from spectrace.displays.match import MatchResult, match_colour
from spectrace.displays.viewing import ViewingConditions
from spectrace.errors import SpectraceError
from spectrace.spectral.display import Display
from spectrace.spectral.observers import photometric_xyz
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
            "patches": [
                {
                    "patch": p.patch,
                    "lab_under_source": p.lab_under_source.tolist(),
                    "lab_under_target": p.lab_under_target.tolist(),
                    "delta_e_2000": p.delta_e_2000,
                }
                for p in self.patches
            ],
            "mean_delta_e_2000": self.mean_delta_e,
            "max_delta_e_2000": self.max_delta_e,
        }


def patch_metamerism(
    source: Display, rgb, target: Display, viewing: ViewingConditions | None = None
) -> MetamerismReport:
    """Each ColorChecker patch lit by `source` showing `rgb` vs lit by `target` showing the matching triple.
    CIELAB uses the light itself as the white (a perfect reflector under it), the same for both halves, since the
    matched lights have the same XYZ."""
    match = match_colour(source, rgb, target, viewing)
    light_source = match.source.emission_from_drive(match.source_drive)
    light_target = match.target.emission_from_drive(match.target_drive)
    white = photometric_xyz(light_source)
    if not white[1] > 0:  # CIELAB needs the light as its white
        raise SpectraceError(
            f"the triple {tuple(float(v) for v in rgb)} on {source.name} gives no light to see the patches by",
            where="--rgb",
        )
    white_xy = colour.XYZ_to_xy(white)
    patches = []
    for name in colorchecker_patch_names():
        reflectance = colorchecker_reflectance(name).values
        lab_a = colour.XYZ_to_Lab(photometric_xyz(reflectance * light_source) / white[1], white_xy)
        lab_b = colour.XYZ_to_Lab(photometric_xyz(reflectance * light_target) / white[1], white_xy)
        patches.append(PatchDifference(name, lab_a, lab_b, float(colour.delta_E(lab_a, lab_b, method="CIE 2000"))))
    return MetamerismReport(match, patches)


@dataclass
class RenderedPatch:
    patch: str
    lab_left: np.ndarray
    lab_right: np.ndarray
    delta_e_2000: float
    delta_e_standard_error: float


def measure_scene_patches(
    scene,
    device=None,
    streams: int = 32,
    samples_per_item: int = 32,
    progress: Callable[[int, int], None] | None = None,
) -> list[RenderedPatch]:
    """The renderer's view of a two-half metamerism scene: for every shape pair named "left <patch>" / "right
    <patch>" (as in scenes/display_lcd_vs_led.toml), the radiance from the camera toward the patch's centre, by a
    radiance meter (380-780 nm every 5 nm), as CIELAB relative to the left half's brightest neutral patch (one fixed
    white for both halves, as one photograph would have) and the ΔE2000 between the halves. The ΔE's standard error
    comes from re-evaluating it on the meter readings perturbed by their standard errors. Each reading takes
    `streams` x `samples_per_item` samples: the standard errors fall as one over its square root. `progress(readings
    done, readings)` after each reading."""
    from spectrace.api import measure_radiance
    from spectrace.device import Device, open_device

    device = device if isinstance(device, Device) else open_device(device)  # once, not once per reading
    wavelengths = np.arange(380.0, 781.0, 5.0)
    origin = np.asarray(scene.camera.origin, float)
    shapes = {shape.name: shape for shape in scene.shapes}
    names = [name[len("left ") :] for name in shapes if name.startswith("left ") and f"right {name[5:]}" in shapes]
    names = [n for n in names if n in colorchecker_patch_names()]
    readings = {}
    pairs = [(side, name) for side in ("left", "right") for name in names]
    for done, (side, name) in enumerate(pairs, start=1):
        centre = shapes[f"{side} {name}"].mesh.vertices.mean(axis=0)
        reading = measure_radiance(
            scene,
            origin,
            centre - origin,
            wavelengths,
            streams=streams,
            samples_per_item=samples_per_item,
            device=device,
        )
        readings[side, name] = (reading.spectral, reading.spectral_standard_error)
        if progress is not None:
            progress(done, len(pairs))
    white_name = max((n for n in names if n.startswith("white")), default=names[0])
    white = photometric_xyz(np.interp(_grid(), wavelengths, readings["left", white_name][0]))
    rng = np.random.default_rng(0)

    def lab(values):
        xyz = photometric_xyz(np.interp(_grid(), wavelengths, values))
        return colour.XYZ_to_Lab(xyz / white[1], colour.XYZ_to_xy(white))

    results = []
    for name in names:
        (left, left_se), (right, right_se) = readings["left", name], readings["right", name]
        delta = float(colour.delta_E(lab(left), lab(right), method="CIE 2000"))
        trials = [
            colour.delta_E(
                lab(left + rng.normal(0, 1, left.shape) * left_se),
                lab(right + rng.normal(0, 1, right.shape) * right_se),
                method="CIE 2000",
            )
            for _ in range(16)
        ]
        results.append(RenderedPatch(name, lab(left), lab(right), delta, float(np.std(trials, ddof=1))))
    return results


def _grid() -> np.ndarray:
    from spectrace.spectral.grid import GRID_NM

    return GRID_NM
