"""The unit normal each triangle carries in the w of its three vertices (render/scene_buffers.py), which the kernels
read as the geometric normal: it must be the normal of the winding, recomputed here from the vertices in float64."""

import numpy as np

import spectrace
from spectrace.engine.scene_buffers import build_scene_buffers
from spectrace.resources import scenes_dir
from spectrace.scene import load_scene


def _check(buffers):
    v = buffers.triangle_vertices.reshape(-1, 3, 4)[: buffers.triangle_count].astype(np.float64)
    n = np.cross(v[:, 1, :3] - v[:, 0, :3], v[:, 2, :3] - v[:, 0, :3])
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    stored = v[:, :, 3]
    # The stored normal comes from the float64 vertices, this one from their float32 rounding: small triangles differ
    # in the sixth digit.
    np.testing.assert_allclose(stored, n, atol=2e-5)
    np.testing.assert_allclose(np.linalg.norm(stored, axis=1), 1.0, atol=1e-6)


def test_bundled_scenes_carry_their_winding_normals():
    for name in ("cornell_box", "material_showcase", "subsurface"):
        _check(build_scene_buffers(load_scene(scenes_dir() / f"{name}.toml")))


def test_a_flipped_winding_flips_the_normal():
    floor = spectrace.shape(
        "rectangle", spectrace.diffuse((0.5, 0.5, 0.5)), transform=[{"rotate": {"axis": [1, 0, 0], "angle": -90}}]
    )
    flipped = spectrace.shape(
        "rectangle",
        spectrace.diffuse((0.5, 0.5, 0.5)),
        transform=[{"rotate": {"axis": [1, 0, 0], "angle": 90}}, {"translate": [0, 1, 0]}],
    )
    scene = spectrace.Scene(
        camera=spectrace.Camera(origin=(0.0, 1.0, -3.0), target=(0.0, 0.0, 0.0)),
        shapes=[floor, flipped],
        width=4,
        height=4,
    )
    buffers = build_scene_buffers(scene)
    _check(buffers)
    normals_y = buffers.triangle_vertices.reshape(-1, 3, 4)[: buffers.triangle_count, 1, 3]
    assert sorted(np.sign(normals_y).tolist()) == [-1.0, -1.0, 1.0, 1.0]
