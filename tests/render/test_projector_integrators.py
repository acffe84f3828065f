"""A projector through every integrator that starts paths at lights: the floor under a projector tilted off the
camera's axis, a 3 × 2 image of different colours landing on it; the light tracer and BDPT (whose light paths leave
through the image's rectangle, kernels/light_projector.cl) agree with the path tracer (next-event estimation only)
within 5 standard errors per 8 × 8-pixel block (tests/replica_agreement.py)."""

from pathlib import Path

import numpy as np
import pytest
from tests.render.test_light_tracer import _floor_scene

import spectrace
from replica_agreement import assert_replicas_agree, spectrace_replicas
from spectrace.engine.renderer import Renderer

PIXELS = np.array(
    [[[0.9, 0.2, 0.1], [0.1, 0.8, 0.2], [0.5, 0.5, 0.1]], [[0.2, 0.3, 0.9], [0.7, 0.7, 0.7], [0.1, 0.6, 0.8]]]
)


def _projector_scene(tmp_path: Path, integrator: str, profile: str):
    scene = spectrace.load_scene(_floor_scene(tmp_path, integrator)).with_overrides(seed=5)
    projector = spectrace.projector_light(
        (0.0, -0.5, 1.2), (0.3, -0.2, 0.0), 50.0, intensity=3.0, image=spectrace.bitmap(PIXELS), profile=profile
    )
    return scene.with_overrides(lights=[projector])


@pytest.mark.parametrize(("integrator", "profile"), [("light", "irradiance"), ("bdpt", "intensity")])
def test_light_paths_through_the_image_agree_with_the_path_tracer(device, tmp_path, integrator, profile):
    path = spectrace_replicas(Renderer(_projector_scene(tmp_path, "path", profile), device), 8, 8)
    other = spectrace_replicas(Renderer(_projector_scene(tmp_path, integrator, profile), device), 8, 8)
    assert path.mean() > 0.01
    assert_replicas_agree(other, path, block=8, what=f"{integrator}, {profile} profile")
