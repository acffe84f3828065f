"""Light paths that follow a light's image (kernels/distribution_2d.cl): a projector and a goniometric light whose
images are sparse (a few bright texels on black) lighting the floor; the light tracer and BDPT agree with the path
tracer (next-event estimation only) within 5 standard errors per 8 × 8-pixel block (tests/replica_agreement.py),
from 2 (projector) and 4 (goniometric) samples a pixel per replica of light paths: the light tracer's image has about
10 times less standard deviation than with light paths drawn uniformly, which carry light only when they leave
through a bright texel."""

from pathlib import Path

import numpy as np
import pytest
from tests.render.test_light_tracer import _floor_scene

import spectrace
from replica_agreement import assert_replicas_agree, spectrace_replicas
from spectrace.engine.renderer import Renderer

PROJECTOR_IMAGE = np.zeros((6, 8, 3))
PROJECTOR_IMAGE[1, 2] = (0.9, 0.3, 0.1)
PROJECTOR_IMAGE[4, 5] = (0.2, 0.8, 0.6)
PROJECTOR_IMAGE[3, 7] = (0.5, 0.5, 0.9)
GONIO_IMAGE = np.zeros((8, 8))
# Samples a pixel per replica: the path tracer's reference needs more than the light paths drawn by the image.
PATH_SPP = {"projector": 16, "goniometric": 4}
LIGHT_PATH_SPP = {"projector": 2, "goniometric": 4}
GONIO_IMAGE[3, 4], GONIO_IMAGE[4, 3], GONIO_IMAGE[2, 3], GONIO_IMAGE[0, 6] = 4.0, 2.0, 1.0, 3.0


def _light(kind: str):
    if kind == "projector":
        image = spectrace.bitmap(PROJECTOR_IMAGE, filter="nearest")
        return spectrace.projector_light(
            (0.0, -0.5, 1.2), (0.3, -0.2, 0.0), 50.0, intensity=20.0, image=image, profile="intensity"
        )
    return spectrace.goniometric_light((0.1, -0.3, 1.0), intensity=2.0, image=GONIO_IMAGE, up=(0.3, 0.2, -1.0))


def _scene(tmp_path: Path, integrator: str, kind: str):
    scene = spectrace.load_scene(_floor_scene(tmp_path, integrator)).with_overrides(seed=7)
    return scene.with_overrides(lights=[_light(kind)])


@pytest.mark.slow
@pytest.mark.parametrize(
    ("kind", "integrator"),
    [("projector", "light"), ("projector", "bdpt"), ("goniometric", "light"), ("goniometric", "bdpt")],
)
def test_light_paths_through_a_sparse_image_agree_with_the_path_tracer(device, tmp_path, kind, integrator):
    path = spectrace_replicas(Renderer(_scene(tmp_path, "path", kind), device), 8, PATH_SPP[kind])
    other = spectrace_replicas(Renderer(_scene(tmp_path, integrator, kind), device), 8, LIGHT_PATH_SPP[kind])
    assert path.mean() > 0.005
    assert_replicas_agree(other, path, block=8, what=f"{kind}, {integrator}")


def test_a_projectors_edits_reuse_its_sampling_table():
    """Editing a projector's other keys in a live session finds its image's table in the texel buffer (which keeps
    its size) and renders the bits of the scene built edited."""
    from spectrace.session import Session

    image = spectrace.bitmap(PROJECTOR_IMAGE, filter="nearest")

    def build(power: float) -> spectrace.Scene:
        return spectrace.Scene(
            camera=spectrace.Camera(origin=(0.3, -0.2, 3.0), target=(0.3, -0.2, 0.0), fov_degrees=50.0),
            width=16,
            height=16,
            shapes=[spectrace.shape("rectangle", spectrace.diffuse(0.5), transform=[{"scale": 4}])],
            lights=[spectrace.projector_light((0.0, -0.5, 1.2), (0.3, -0.2, 0.0), 50.0, power_w=power, image=image)],
            integrator="light",
            max_depth=2,
        )

    with Session(build(5.0), pass_spp=1) as session:
        texels = len(session.renderer.buffers.texels)
        for power in (8.0, 13.0, 21.0):
            assert not session.update({"lights.0.power": power}).rebuilt
            assert len(session.renderer.buffers.texels) == texels
        session.step()
        edited = session.image().xyz
    np.testing.assert_array_equal(edited, spectrace.render(build(21.0), spp=1, progress=False).xyz)
