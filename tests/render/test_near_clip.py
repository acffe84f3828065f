"""The camera's near clip (Mitsuba 3's near_clip): nothing nearer than the clip plane along the view axis is seen.
An opaque black disk 1.5 m in front of the eye fills the view of a uniform environment: with the clip plane beyond
it the image is the environment's, as if the disk were not there; with the plane before it, black."""

import numpy as np

import spectrace
from spectrace.engine.renderer import Renderer
from spectrace.scene.model import Scene


def _image(device, near_clip: float, with_disk: bool) -> np.ndarray:
    camera = spectrace.Camera(origin=(0.0, 0.0, 5.0), target=(0.0, 0.0, 0.0), fov_degrees=40.0, near_clip=near_clip)
    disk = spectrace.shape("disk", spectrace.diffuse(0.0), transform=[{"scale": 10.0}, {"translate": [0, 0, 3.5]}])
    scene = Scene(
        camera=camera,
        width=8,
        height=8,
        shapes=[disk] if with_disk else [],
        lights=[spectrace.constant_environment(2.0)],
        spp=4,
    )
    renderer = Renderer(scene, device)
    renderer.render(spp=4)
    return renderer.image().xyz


def test_the_near_clip_hides_what_lies_before_it(device):
    unoccluded = _image(device, 0.0, with_disk=False)
    assert unoccluded[..., 1].min() > 0.1
    assert np.all(_image(device, 0.0, with_disk=True) == 0.0)
    assert np.all(_image(device, 1.0, with_disk=True) == 0.0)  # the disk lies 1.5 m out, beyond this plane
    np.testing.assert_allclose(_image(device, 2.0, with_disk=True), unoccluded, rtol=1e-6)
