"""The path tracer against closed-form radiometry.

Inside a closed enclosure whose walls all emit radiance Le and reflect diffusely with albedo ρ, the radiance is
the same everywhere and in every direction: L = Le + ρ L. Truncated to max_depth path segments it is
L_d = Le (1 − ρ^d) / (1 − ρ), and unbounded (Russian roulette) Le / (1 − ρ). This exercises emission, next-event
estimation, MIS, BSDF sampling and Russian roulette together; any bias in one of them shows.
"""

import numpy as np
import pytest

from spectrace.engine.renderer import Renderer
from spectrace.geometry import primitives
from spectrace.geometry.transforms import apply_transform, transform_matrix
from spectrace.scene.model import AreaEmitter, Camera, DiffuseMaterial, Scene, Shape
from spectrace.spectral.grid import GRID_NM
from spectrace.spectral.spectrum import Spectrum
from stats_toolkit import assert_within_standard_errors, mean_and_standard_error

EMITTED = 0.5
ALBEDO = 0.6


def _constant(value: float) -> Spectrum:
    return Spectrum(np.full(len(GRID_NM), value), name=f"constant {value}")


def _furnace_box(max_depth: int, seed: int = 3) -> Scene:
    box = apply_transform(primitives.cube(), transform_matrix([{"scale": [1.0, 0.7, 1.3]}], where="test"))
    shape = Shape(
        mesh=box, material=DiffuseMaterial(_constant(ALBEDO)), emitter=AreaEmitter(_constant(EMITTED), two_sided=True)
    )
    camera = Camera(origin=(0.1, -0.2, 0.3), target=(0.5, 0.1, -1.0), fov_degrees=100.0)
    return Scene(camera=camera, width=32, height=32, shapes=[shape], max_depth=max_depth, rr_depth=3, spp=16, seed=seed)


def _measured_y(scene: Scene, device) -> tuple[float, float]:
    return mean_and_standard_error(Renderer(scene, device).render().xyz[..., 1].ravel())


@pytest.mark.parametrize("max_depth", [1, 2, 3, 6])
def test_enclosure_radiance_truncated(device, max_depth):
    expected = EMITTED * (1 - ALBEDO**max_depth) / (1 - ALBEDO)
    mean, standard_error = _measured_y(_furnace_box(max_depth), device)
    assert standard_error < 0.01 * expected
    assert_within_standard_errors(mean, expected, standard_error)


def test_enclosure_radiance_unbounded_with_russian_roulette(device):
    expected = EMITTED / (1 - ALBEDO)
    mean, standard_error = _measured_y(_furnace_box(-1), device)
    assert standard_error < 0.01 * expected
    assert_within_standard_errors(mean, expected, standard_error)
