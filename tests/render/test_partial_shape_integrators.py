"""A partial sphere light (cut in height and azimuth, kernels/shape_partial.cl) over a floor through every
integrator that starts paths at lights: the light tracer and BDPT (light paths leaving points uniform over the part
that is left) agree with the path tracer (next-event estimation by area over that part, MIS with the floor's own
samples) within 5 standard errors per 8 × 8-pixel block (tests/replica_agreement.py). The camera sees the floor
only, lit through the cut-outs' edges."""

from pathlib import Path

import pytest
from tests.render.test_light_tracer import _floor_scene

import spectrace
from replica_agreement import assert_replicas_agree, spectrace_replicas
from spectrace.engine.renderer import Renderer


def _scene(tmp_path: Path, integrator: str):
    scene = spectrace.load_scene(_floor_scene(tmp_path, integrator)).with_overrides(seed=7)
    bulb = spectrace.shape(
        "sphere",
        spectrace.diffuse(0.0),
        emitter=spectrace.area_emitter(4.0),
        center=(0.2, -0.1, 1.0),
        radius=0.4,
        z_min=-0.3,
        z_max=0.2,
        phi_max=240,
    )
    return scene.with_overrides(lights=[], shapes=[*scene.shapes, bulb])


@pytest.mark.parametrize("integrator", ["light", "bdpt"])
def test_light_paths_from_a_partial_sphere_agree_with_the_path_tracer(device, tmp_path, integrator):
    path = spectrace_replicas(Renderer(_scene(tmp_path, "path"), device), 16, 16)
    other = spectrace_replicas(Renderer(_scene(tmp_path, integrator), device), 16, 16)
    assert path.mean() > 0.01
    assert_replicas_agree(other, path, block=8, what=integrator)
