"""Vertex normals: read from mesh files (OBJ vn, PLY, glTF), made for the sphere, computed on request, carried
through transforms, chosen by a shape's face_normals key, and laid out for the device per triangle."""

import numpy as np
import pytest
import trimesh

import spectrace
from cli_runner import run_spectrace
from scene_text import CAMERA_FILM_GREY
from spectrace.engine.memory import scene_arrays
from spectrace.engine.scene_buffers import build_scene_buffers
from spectrace.errors import SpectraceError
from spectrace.geometry import primitives
from spectrace.geometry.mesh import _mesh_through_trimesh, _plain_triangle_obj, load_mesh
from spectrace.geometry.transforms import apply_transform, transform_matrix
from spectrace.scene import load_scene

# A unit square in z = 0 split into two triangles; corner 2 (1, 1, 0) is shared and carries a different normal
# in each triangle (a crease), so the reader must split it.
SQUARE_OBJ = """\
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
vn 0 0 1
vn 0.6 0 0.8
vn 0 0.6 0.8
f 1//1 2//2 3//2
f 1//1 3//3 4//3
"""
# The normal each triangle's corners must get, in face order.
SQUARE_CORNERS = {
    ((0, 0, 0), (1, 0, 0), (1, 1, 0)): [(0, 0, 1), (0.6, 0, 0.8), (0.6, 0, 0.8)],
    ((0, 0, 0), (1, 1, 0), (0, 1, 0)): [(0, 0, 1), (0, 0.6, 0.8), (0, 0.6, 0.8)],
}


def _corners_by_triangle(mesh) -> dict:
    v0, v1, v2 = mesh.triangles()
    normals = mesh.triangle_normals()
    return {
        tuple(tuple(float(x) for x in p) for p in (a, b, c)): normals[i].round(12).tolist()
        for i, (a, b, c) in enumerate(zip(v0, v1, v2))
    }


def test_obj_vn_reads_each_corners_normal_and_splits_a_crease(tmp_path):
    path = tmp_path / "square.obj"
    path.write_text(SQUARE_OBJ)
    assert _plain_triangle_obj(path) is not None  # the reader of small plain files takes it
    for mesh in (load_mesh(path, where="w"), _mesh_through_trimesh(path, where="w")):
        corners = _corners_by_triangle(mesh)
        assert corners.keys() == SQUARE_CORNERS.keys()
        for triangle, expected in SQUARE_CORNERS.items():
            np.testing.assert_allclose(corners[triangle], expected, atol=1e-12)


@pytest.mark.parametrize("extension", ["ply", "glb"])
def test_ply_and_gltf_normals_come_through_trimesh(tmp_path, extension):
    ball = trimesh.creation.icosphere(subdivisions=1)
    stored = ball.vertices / np.linalg.norm(ball.vertices, axis=1, keepdims=True)
    ball = trimesh.Trimesh(ball.vertices, ball.faces, vertex_normals=stored, process=False)
    path = tmp_path / f"ball.{extension}"
    if extension == "ply":
        path.write_bytes(trimesh.exchange.ply.export_ply(ball, vertex_normal=True))
    else:
        # a node transform that scales and turns: the normals must follow by the inverse transpose
        matrix = trimesh.transformations.rotation_matrix(0.7, [1, 0, 0]) @ np.diag([2.0, 1.0, 1.0, 1.0])
        scene = trimesh.Scene()
        scene.add_geometry(ball, transform=matrix)
        scene.export(path, include_normals=True)
    mesh = load_mesh(path, where="w")
    assert mesh.normals is not None
    # The surface is the image of the unit sphere; its normal at a point p is L⁻ᵀ L⁻¹ p (the gradient of |L⁻¹p|²).
    linear = np.eye(3) if extension == "ply" else matrix[:3, :3]
    inverse = np.linalg.inv(linear)
    expected = mesh.vertices @ inverse.T @ inverse
    expected /= np.linalg.norm(expected, axis=1, keepdims=True)
    np.testing.assert_allclose(mesh.normals, expected, atol=2e-6)


def test_a_file_without_normals_gets_none_unless_asked(tmp_path):
    ball = trimesh.creation.icosphere(subdivisions=2)
    path = tmp_path / "ball.obj"
    path.write_text(
        "".join(f"v {x:.17g} {y:.17g} {z:.17g}\n" for x, y, z in ball.vertices)
        + "".join(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in ball.faces)
    )
    assert load_mesh(path, where="w").normals is None
    text = CAMERA_FILM_GREY + '[[shapes]]\ntype = "mesh"\nfile = "ball.obj"\nmaterial = "grey"\n'
    scene_path = tmp_path / "scene.toml"
    for key, smooth in (("", False), ("face_normals = true\n", False), ("face_normals = false\n", True)):
        scene_path.write_text(text + key)
        mesh = load_scene(scene_path).shapes[0].mesh
        assert (mesh.normals is not None) == smooth
        if smooth:
            # angle-weighted face normals of a finely cut sphere: close to the radial direction
            radial = mesh.vertices / np.linalg.norm(mesh.vertices, axis=1, keepdims=True)
            assert np.min(np.einsum("ij,ij->i", mesh.normals, radial)) > np.cos(np.radians(1.0))


def test_face_normals_true_drops_a_files_normals_and_the_spheres(tmp_path):
    (tmp_path / "square.obj").write_text(SQUARE_OBJ)
    shapes = '[[shapes]]\ntype = "mesh"\nfile = "square.obj"\nmaterial = "grey"\n{}'
    shapes += '[[shapes]]\ntype = "sphere"\nmaterial = "grey"\n{}[[shapes]]\ntype = "cube"\nmaterial = "grey"\n'
    path = tmp_path / "scene.toml"
    path.write_text(CAMERA_FILM_GREY + shapes.format("", ""))
    square, sphere, cube = (s.mesh for s in load_scene(path).shapes)
    assert square.normals is not None and sphere.normals is not None and cube.normals is None
    path.write_text(CAMERA_FILM_GREY + shapes.format("face_normals = true\n", "face_normals = true\n"))
    assert all(s.mesh.normals is None for s in load_scene(path).shapes)


def test_face_normals_must_be_a_boolean(tmp_path):
    path = tmp_path / "scene.toml"
    path.write_text(CAMERA_FILM_GREY + '[[shapes]]\ntype = "sphere"\nmaterial = "grey"\nface_normals = "yes"\n')
    with pytest.raises(SpectraceError) as caught:
        load_scene(path)
    assert "shapes[0].face_normals" in str(caught.value.where) + str(caught.value)


@pytest.mark.parametrize("bad", ["nan 0 1", "0 inf 1"])
def test_a_non_finite_normal_is_one_line_naming_the_file_and_key(tmp_path, bad):
    mesh_path = tmp_path / "bad.obj"
    mesh_path.write_text(SQUARE_OBJ.replace("vn 0 0 1", f"vn {bad}"))
    with pytest.raises(SpectraceError, match="vertex normals with NaN or infinite") as caught:
        load_mesh(mesh_path, where="scene.toml: shapes[0].file")
    assert caught.value.where == "scene.toml: shapes[0].file" and "bad.obj" in str(caught.value)


@pytest.mark.subprocess
def test_the_command_line_reports_a_bad_normal_in_one_line(tmp_path):
    (tmp_path / "bad.obj").write_text(SQUARE_OBJ.replace("vn 0 0 1", "vn nan 0 1"))
    scene = tmp_path / "scene.toml"
    scene.write_text(CAMERA_FILM_GREY + '[[shapes]]\ntype = "mesh"\nfile = "bad.obj"\nmaterial = "grey"\n')
    out = tmp_path / "out.png"
    result = run_spectrace("render", str(scene), "-o", str(out))
    assert result.returncode != 0 and not out.exists()
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and "shapes[0].file" in lines[0] and "bad.obj" in lines[0], result.stderr


def test_a_zero_normal_stands_for_the_face_normal():
    mesh = primitives.rectangle().with_normals(np.array([[0, 0, 0], [0, 0, 2.0], [0.6, 0, 0.8], [0, 0, 0]]))
    corners = mesh.triangle_normals()
    np.testing.assert_allclose(corners[0], [[0, 0, 1], [0, 0, 1], [0.6, 0, 0.8]])
    np.testing.assert_allclose(corners[1], [[0, 0, 1], [0.6, 0, 0.8], [0, 0, 1]])


def test_transforms_turn_normals_by_the_inverse_transpose():
    """An ellipsoid made from the unit sphere by a non-uniform scale, a rotation and a shear: each vertex normal
    must be the ellipsoid's, the gradient of |A⁻¹ (p − c)|², not the sphere's normal moved like a point."""
    steps = [
        {"scale": [2.0, 0.5, 1.0]},
        {"rotate": {"axis": [1.0, 1.0, 0.0], "angle": 40.0}},
        {"matrix": [[1, 0.4, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]},
        {"translate": [1.0, 2.0, 3.0]},
    ]
    matrix = transform_matrix(steps, where="test")
    mesh = apply_transform(primitives.sphere(subdivisions=2), matrix)
    inverse = np.linalg.inv(matrix[:3, :3])
    expected = (mesh.vertices - matrix[:3, 3]) @ inverse.T @ inverse
    expected /= np.linalg.norm(expected, axis=1, keepdims=True)
    np.testing.assert_allclose(mesh.normals, expected, atol=1e-12)
    mirrored = apply_transform(primitives.sphere(subdivisions=1), np.diag([-1.0, 1.0, 1.0, 1.0]))
    radial = mirrored.vertices / np.linalg.norm(mirrored.vertices, axis=1, keepdims=True)  # the seam's are inside
    np.testing.assert_allclose(mirrored.normals, radial, atol=1e-12)  # still outward


def test_device_buffers_hold_normals_only_for_smooth_triangles():
    grey = spectrace.diffuse(0.5)
    camera = spectrace.Camera(origin=(0.0, 0.0, 5.0), target=(0.0, 0.0, 0.0))
    flat = spectrace.Scene(camera=camera, width=4, height=4, shapes=[spectrace.shape("cube", grey)])
    buffers = build_scene_buffers(flat)
    assert np.all(buffers.triangle_info["normals"] == -1) and buffers.triangle_normals.shape == (3, 4)

    ball = spectrace.shape("sphere", grey, transform=[{"translate": [3.0, 0.0, 0.0]}], tessellated=True)
    scene = spectrace.Scene(camera=camera, width=4, height=4, shapes=[spectrace.shape("cube", grey), ball])
    buffers = build_scene_buffers(scene)
    info = buffers.triangle_info[: buffers.triangle_count]
    smooth = info["normals"] >= 0
    assert smooth.sum() == len(ball.mesh.faces) and sorted(info["normals"][smooth]) == list(range(smooth.sum()))
    # Each smooth triangle's corners (BVH leaf order) carry the radial direction of the sphere at that corner.
    corners = buffers.triangle_vertices.reshape(-1, 3, 4)[: buffers.triangle_count][smooth, :, :3]
    normals = buffers.triangle_normals.reshape(-1, 3, 4)[info["normals"][smooth]]
    radial = corners - np.array([3.0, 0.0, 0.0])
    radial /= np.linalg.norm(radial, axis=-1, keepdims=True)
    np.testing.assert_allclose(normals[..., :3], radial, atol=1e-6)
    assert np.all(normals[..., 3] == 0)
    assert scene_arrays(buffers)["triangle normals"].nbytes == len(ball.mesh.faces) * 3 * 16
