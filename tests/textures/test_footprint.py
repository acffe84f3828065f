"""The texture footprint estimated from the camera (kernels/scene.cl, camera_footprint) against geometry done here:
the rays through a point and through the points one pixel over, met with the surface, and the surface's own uv
mapping (the rectangle's u = (x + 1)/2, v = (1 − y)/2 in its frame)."""

import numpy as np
import pytest
from tests.textures.lookup import HARNESS

import spectrace
from spectrace.engine.scene_buffers import build_scene_buffers, render_params
from spectrace.geometry.transforms import transform_matrix
from spectrace.scene.model import Camera, Scene

WIDTH, HEIGHT = 64, 48


def _device_footprints(runner, scene: Scene, points: np.ndarray) -> np.ndarray:
    buffers = build_scene_buffers(scene)
    query = np.zeros((len(points), 4), np.float32)
    query[:, :3] = points
    query[:, 3] = 0  # the rectangle's two triangles share one plane and one affine uv map
    out = np.zeros(len(points), np.float32)
    args = [
        runner.buffer(render_params(scene, buffers, 0, 1)),
        runner.buffer(buffers.triangle_vertices),
        runner.buffer(buffers.triangle_uvs),
        runner.buffer(query),
        runner.buffer(out, True),
    ]
    runner.run("footprint_at", len(points), args, {4: out})
    return out.astype(np.float64)


def _scene(transform) -> Scene:
    camera = Camera(origin=(0.3, 0.2, 4.0), target=(0.0, 0.0, 0.0), fov_degrees=40.0)
    quad = spectrace.shape("rectangle", spectrace.diffuse(0.5), transform=transform)
    return Scene(camera=camera, width=WIDTH, height=HEIGHT, shapes=[quad])


def _reference(scene: Scene, matrix: np.ndarray, local_points: np.ndarray) -> np.ndarray:
    """2 max |d(u, v)/d(x, y)| from intersecting the neighbouring pixels' rays with the quad's plane."""
    origin, forward, right, up = scene.camera.basis(WIDTH / HEIGHT)
    inverse = np.linalg.inv(matrix)
    normal = matrix[:3, :3] @ np.array([0.0, 0.0, 1.0])
    centre = matrix[:3, 3]

    def uv_of(world):
        local = (inverse[:3, :3] @ world.T).T + inverse[:3, 3]
        return np.stack([(local[:, 0] + 1) / 2, (1 - local[:, 1]) / 2], axis=1)

    world = (matrix[:3, :3] @ local_points.T).T + centre
    direction = (world - origin) / ((world - origin) @ forward)[:, None]
    result = []
    for step in (right * 2 / WIDTH, up * 2 / HEIGHT):
        shifted = direction + step
        t = ((centre - origin) @ normal) / (shifted @ normal)
        result.append(uv_of(origin + shifted * t[:, None]) - uv_of(world))
    return 2 * np.max(np.abs(np.concatenate(result, axis=1)), axis=1)


@pytest.mark.parametrize(
    "steps",
    [[{"scale": 1.0}], [{"scale": [1.5, 0.7, 1.0]}, {"rotate": {"axis": [1, 0.3, 0], "angle": 55}}]],
    ids=["facing", "tilted"],
)
def test_camera_footprint_matches_ray_geometry(kernel_runner, steps):
    scene = _scene(steps)
    matrix = transform_matrix(steps, where="test")
    rng = np.random.default_rng(3)
    local = np.zeros((200, 3))
    local[:, :2] = rng.uniform(-0.9, 0.9, (200, 2))
    world = (matrix[:3, :3] @ local.T).T + matrix[:3, 3]
    got = _device_footprints(kernel_runner(HARNESS), scene, world)
    expected = _reference(scene, matrix, local)
    np.testing.assert_allclose(got, expected, rtol=2e-4)
    if steps == [{"scale": 1.0}]:
        # Nearly facing the camera at a distance of about 4, one pixel spans 2·4·tan(20°)/64 world units and half
        # that in u, so the footprint (twice the larger derivative) is about 2·4·tan(20°)/64; the slight obliquity of
        # the view and the spread of depths over the quad keep it within 5 %.
        assert np.all(np.abs(got - 2 * 4.0 * np.tan(np.radians(20.0)) / WIDTH) < 0.05 * got)
