"""The texture footprint (kernels/scene.cl) from the orthographic and equirectangular cameras' ray differentials
(kernels/camera.cl, camera_neighbour_rays) against geometry done here. The rectangle's uv is u = (x + 1)/2,
v = (1 − y)/2 in its frame, so a world step s along its face moves uv by s/2."""

import math

import numpy as np
from tests.textures.lookup import HARNESS
from tests.textures.test_footprint import _device_footprints

import spectrace
from spectrace.scene.model import Camera, Scene


def _quad_scene(camera: Camera, width: int, height: int, distance: float) -> Scene:
    """The rectangle facing the camera (which looks along −z from the origin) `distance` away."""
    quad = spectrace.shape("rectangle", spectrace.diffuse(0.5), transform=[{"translate": [0.0, 0.0, -distance]}])
    return Scene(camera=camera, width=width, height=height, shapes=[quad])


def _points(distance: float, spread: float) -> np.ndarray:
    rng = np.random.default_rng(5)
    points = np.zeros((100, 3))
    points[:, :2] = rng.uniform(-spread, spread, (100, 2))
    points[:, 2] = -distance
    return points


def test_orthographic_footprint_is_the_pixel_whatever_the_distance(kernel_runner):
    """A pixel spans view_width / width world units at any distance: du = that / 2 per pixel, a footprint of
    view_width / width."""
    camera = Camera(origin=(0.0, 0.0, 0.0), target=(0.0, 0.0, -1.0), type="orthographic", view_width=3.0)
    runner = kernel_runner(HARNESS)
    for distance in (2.0, 20.0):
        got = _device_footprints(runner, _quad_scene(camera, 64, 48, distance), _points(distance, 0.9))
        np.testing.assert_allclose(got, 3.0 / 64, rtol=1e-4)


def test_equirectangular_footprint_is_the_pixel_angle_times_distance(kernel_runner):
    """On a 64 x 32 film a pixel spans 2π/64 = π/32 radians either way; near the image centre, where the rectangle
    faces the camera, a point at distance r sees a pixel span r·π/32 along the face (to first order in the angle off
    the axis): du = that / 2, a footprint of r·π/32 (within 2 % over points up to 0.15 off the axis at distance 4)."""
    camera = Camera(origin=(0.0, 0.0, 0.0), target=(0.0, 0.0, -1.0), type="equirectangular")
    points = _points(4.0, 0.15)
    got = _device_footprints(kernel_runner(HARNESS), _quad_scene(camera, 64, 32, 4.0), points)
    expected = np.linalg.norm(points, axis=1) * math.pi / 32
    np.testing.assert_allclose(got, expected, rtol=0.02)
