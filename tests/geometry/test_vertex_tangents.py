"""Per-vertex tangents (glTF's TANGENT: xyz along +u, w the handedness) through every copy of a mesh. The check is
geometric: the bitangent cross(normal, tangent) · w is a direction in the surface, so a map of the surface must
carry it as it carries any tangent vector (the linear part L, up to length), and the tangent itself to L t; a
flip keeps both directions."""

from __future__ import annotations

import numpy as np
import pytest

from spectrace.engine.vertex_tangents import smooth_rows
from spectrace.geometry.mesh import TriangleMesh, load_mesh
from spectrace.geometry.transforms import apply_transform
from spectrace.interop.pbrt.meshes import MeshData, write_ply

RNG = np.random.default_rng(7)


def _mesh() -> TriangleMesh:
    """Two triangles in z = 0 facing +z, tangents not along either edge, one vertex left-handed."""
    vertices = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]])
    faces = np.array([[0, 1, 2], [0, 2, 3]])
    normals = np.tile([0.0, 0.0, 1.0], (4, 1))
    angle = RNG.uniform(0.0, 2.0 * np.pi, 4)
    tangents = np.column_stack([np.cos(angle), np.sin(angle), np.zeros(4), [1.0, 1.0, -1.0, 1.0]])
    uvs = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    return TriangleMesh(vertices, faces, uvs=uvs, normals=normals, tangents=tangents)


def _bitangents(mesh: TriangleMesh) -> np.ndarray:
    assert mesh.normals is not None and mesh.tangents is not None
    return np.cross(mesh.normals, mesh.tangents[:, :3]) * mesh.tangents[:, 3:]


def _unit(rows: np.ndarray) -> np.ndarray:
    return rows / np.linalg.norm(rows, axis=-1, keepdims=True)


MAPS = {
    "rotation": np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]),
    "mirror_x": np.diag([-1.0, 1.0, 1.0]),
    "mirror_z": np.diag([1.0, 1.0, -1.0]),
    "shear_scale": np.array([[2.0, 0.5, 0.0], [0.0, 0.5, 0.0], [0.3, 0.0, 3.0]]),
}


@pytest.mark.parametrize("name", MAPS)
def test_a_transform_carries_the_tangent_frame_with_the_surface(name):
    linear = MAPS[name]
    matrix = np.eye(4)
    matrix[:3, :3] = linear
    matrix[:3, 3] = [0.5, -2.0, 1.0]
    mesh = _mesh()
    moved = apply_transform(mesh, matrix)
    assert moved.tangents is not None
    np.testing.assert_allclose(moved.tangents[:, :3], mesh.tangents[:, :3] @ linear.T)
    # The frame as a renderer builds it: the tangent made orthogonal to the (inverse-transpose) normal.
    normals = moved.normals
    t = moved.tangents[:, :3] - normals * np.sum(normals * moved.tangents[:, :3], axis=1, keepdims=True)
    built = np.cross(normals, _unit(t)) * moved.tangents[:, 3:]
    carried = _bitangents(mesh) @ linear.T
    # Same side of the carried tangent direction (a shear tilts it; it must not turn it over).
    assert np.all(np.sum(built * carried, axis=1) > 0.0)
    if name != "shear_scale":  # orthogonal maps keep it exactly
        np.testing.assert_allclose(built, _unit(carried), atol=1e-12)


def test_flipping_keeps_the_tangent_and_bitangent_directions():
    mesh = _mesh()
    flipped = mesh.flipped()
    np.testing.assert_array_equal(flipped.tangents[:, :3], mesh.tangents[:, :3])
    np.testing.assert_allclose(_bitangents(flipped), _bitangents(mesh))
    np.testing.assert_allclose(flipped.normals, -mesh.normals)


def test_corner_tangents_follow_the_corners_the_renderer_takes():
    """A triangle wound against its normals has corners 1 and 2 swapped by corners(); its tangents go with them."""
    mesh = _mesh()
    reversed_winding = TriangleMesh(
        mesh.vertices, mesh.faces[:, ::-1].copy(), uvs=mesh.uvs, normals=mesh.normals, tangents=mesh.tangents
    )
    v0, _, _, uvs, _ = reversed_winding.corners()
    tangents = reversed_winding.corner_tangents()
    for k in range(len(v0)):
        for corner in range(3):
            vertex = np.flatnonzero((mesh.uvs == uvs[k, corner]).all(axis=1))[0]
            np.testing.assert_array_equal(tangents[k, corner], mesh.tangents[vertex])


def test_without_normals_tangents_have_no_use():
    mesh = _mesh()
    assert mesh.with_normals(None).tangents is None
    assert TriangleMesh(mesh.vertices, mesh.faces, tangents=mesh.tangents).corner_tangents() is None


def test_a_ply_round_trip_keeps_the_tangents(tmp_path):
    """The PLY an import writes carries them (tx, ty, tz, tw beside nx, ny, nz), and the reader gives them back."""
    mesh = _mesh()
    path = tmp_path / "tangents.ply"
    write_ply(path, MeshData(mesh.vertices, mesh.faces, mesh.normals, mesh.uvs, mesh.tangents))
    read = load_mesh(path, where="test")
    np.testing.assert_allclose(read.tangents, mesh.tangents.astype(np.float32))
    np.testing.assert_allclose(read.normals, mesh.normals)
    plain = tmp_path / "plain.ply"
    write_ply(plain, MeshData(mesh.vertices, mesh.faces, mesh.normals, mesh.uvs))
    assert load_mesh(plain, where="test").tangents is None


def test_packing_gives_a_tangent_triangle_two_slots_and_others_one():
    normals = np.tile([0.0, 0.0, 1.0], (4, 3, 1))
    tangents = np.zeros((4, 3, 4))
    tangents[1] = [1.0, 0.0, 0.0, -1.0]
    tangents[3] = [0.0, 1.0, 0.0, 1.0]
    smooth = np.array([True, True, False, True])
    slots, rows = smooth_rows(normals, tangents, smooth)
    np.testing.assert_array_equal(slots, [0, 1, -1, 3])
    assert rows.shape == (5, 3, 4)
    np.testing.assert_array_equal(rows[[0, 1, 3], 0, 3], [0.0, -1.0, 1.0])
    np.testing.assert_array_equal(rows[2], tangents[1])
    np.testing.assert_array_equal(rows[4], tangents[3])
    plain_slots, plain_rows = smooth_rows(normals, None, smooth)
    np.testing.assert_array_equal(plain_slots, [0, 1, -1, 2])
    assert not plain_rows[..., 3].any()


def test_only_a_scene_with_file_tangents_builds_their_kernel_code():
    """SCENE_HAS_FILE_TANGENTS follows the meshes: a shape with tangents (placed by itself, or as an instanced
    object's) turns it on; the same mesh without them leaves the buffers and defines as they were."""
    import spectrace
    from spectrace.engine.scene_buffers import build_scene_buffers
    from spectrace.engine.scene_features import scene_feature_defines

    def scene(mesh: TriangleMesh, instanced: bool) -> spectrace.Scene:
        shape = spectrace.shape(mesh, spectrace.diffuse(0.5))
        camera = spectrace.Camera(origin=(0.5, 0.5, 3.0), target=(0.5, 0.5, 0.0))
        if not instanced:
            return spectrace.Scene(camera=camera, shapes=[shape], width=8, height=8)
        obj = spectrace.instanced_object([shape], name="tile")
        instances = [spectrace.instance(obj), spectrace.instance(obj, transform=[{"scale": [-1, 1, 1]}])]
        return spectrace.Scene(camera=camera, shapes=[], instances=instances, width=8, height=8)

    mesh = _mesh()
    for instanced in (False, True):
        with_tangents = build_scene_buffers(scene(mesh, instanced))
        plain = TriangleMesh(mesh.vertices, mesh.faces, uvs=mesh.uvs, normals=mesh.normals)
        without = build_scene_buffers(scene(plain, instanced))
        assert scene_feature_defines(with_tangents)["SCENE_HAS_FILE_TANGENTS"] == 1
        assert scene_feature_defines(without)["SCENE_HAS_FILE_TANGENTS"] == 0
        assert not without.triangle_normals[:, 3].any()
        # Two triangles of one slot each without, two slots each with them.
        assert len(with_tangents.triangle_normals) == 2 * len(without.triangle_normals)
