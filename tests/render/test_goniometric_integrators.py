"""A goniometric light through every integrator that starts paths at lights: the floor under a goniometric light
whose 4 x 4 equal-area image has a bright texel toward it; the light tracer and BDPT (whose light paths leave in
directions uniform over the sphere, weighted by the image, kernels/light_goniometric.cl) agree with the path tracer
(next-event estimation only) within 5 standard errors per 8 × 8-pixel block (tests/replica_agreement.py)."""

from pathlib import Path

import numpy as np
import pytest
from tests.render.test_light_tracer import _floor_scene

import spectrace
from replica_agreement import assert_replicas_agree, spectrace_replicas
from spectrace.engine.renderer import Renderer

IMAGE = np.array([[0.2, 0.5, 1.0, 0.3], [0.8, 4.0, 0.6, 0.1], [0.4, 0.9, 2.5, 0.7], [0.3, 0.6, 0.2, 1.2]])


def _scene(tmp_path: Path, integrator: str):
    scene = spectrace.load_scene(_floor_scene(tmp_path, integrator)).with_overrides(seed=5)
    light = spectrace.goniometric_light((0.1, -0.3, 1.0), intensity=2.0, image=IMAGE, up=(0.3, 0.2, -1.0))
    return scene.with_overrides(lights=[light])


@pytest.mark.parametrize("integrator", ["light", "bdpt"])
def test_light_paths_agree_with_the_path_tracer(device, tmp_path, integrator):
    path = spectrace_replicas(Renderer(_scene(tmp_path, "path"), device), 8, 12)
    other = spectrace_replicas(Renderer(_scene(tmp_path, integrator), device), 8, 12)
    assert path.mean() > 0.01
    assert_replicas_agree(other, path, block=8, what=integrator)
