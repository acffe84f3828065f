"""The camera's far clip (Mitsuba 3's far_clip): nothing beyond the clip plane along the view axis is seen. A wall
5 m in front of the eye, perpendicular to the view axis and wider than the view, lit by a point light, under a
uniform environment: with the plane at 5.2 m every camera ray meets the wall (along the axis it is 5 m away, though
the corner rays travel 5.7 m), so the image is the unclipped one bit for bit; with the plane at 4.8 m the wall is
gone, for camera rays and for light reaching the film alike, and the image is the environment's alone (BDPT, which
takes no environment, renders black)."""

import numpy as np
import pytest

import spectrace
from spectrace.engine.renderer import Renderer
from spectrace.errors import SpectraceError
from spectrace.scene.model import Scene


def _image(device, integrator: str, far_clip: float | None, with_wall: bool = True) -> np.ndarray:
    camera = spectrace.Camera(origin=(0.0, 0.0, 5.0), target=(0.0, 0.0, 0.0), fov_degrees=60.0, far_clip=far_clip)
    wall = spectrace.shape("rectangle", spectrace.diffuse(0.5), transform=[{"scale": 20.0}])
    scene = Scene(
        camera=camera,
        width=8,
        height=8,
        shapes=[wall] if with_wall else [],
        # BDPT takes no lights at infinity: its clipped image is black.
        lights=[spectrace.point_light((0.0, 1.0, 3.0), intensity=200.0)]
        + ([spectrace.constant_environment(0.1)] if integrator != "bdpt" else []),
        integrator=integrator,
        max_depth=3,
        spp=4,
    )
    renderer = Renderer(scene, device)
    renderer.render(spp=4)
    return renderer.image().xyz


@pytest.mark.parametrize("integrator", ["path", "direct", "light", "bdpt"])
def test_the_far_clip_hides_what_lies_beyond_it_along_the_view_axis(device, integrator):
    unclipped = _image(device, integrator, None)
    environment = _image(device, integrator, None, with_wall=False)
    assert unclipped[..., 1].mean() > 5.0 * environment[..., 1].mean()  # the lit wall is seen
    assert (environment[..., 1].mean() > 0.0) == (integrator != "bdpt")
    np.testing.assert_array_equal(_image(device, integrator, 5.2), unclipped)
    np.testing.assert_allclose(_image(device, integrator, 4.8), environment, rtol=1e-5)


def test_a_far_clip_not_beyond_the_near_clip_is_refused(device):
    camera = spectrace.Camera(origin=(0.0, 0.0, 5.0), target=(0.0, 0.0, 0.0), near_clip=2.0, far_clip=2.0)
    scene = Scene(camera=camera, width=4, height=4, shapes=[], lights=[spectrace.constant_environment(1.0)])
    with pytest.raises(SpectraceError, match="far_clip"):
        spectrace.render(scene, device=device)
