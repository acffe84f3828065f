"""Built-in shapes (areas, outward normals), transform order and errors, and mesh loading."""

import math

import numpy as np
import pytest
import trimesh

from spectrace.errors import SpectraceError
from spectrace.geometry.mesh import TriangleMesh, load_mesh
from spectrace.geometry.primitives import cube, rectangle, sphere
from spectrace.geometry.transforms import apply_transform, transform_matrix

WHERE = "scene.toml: shapes[3].transform"


def _unit_normals(mesh):
    v0, v1, v2 = (mesh.vertices[mesh.faces[:, k]] for k in range(3))
    normals = np.cross(v1 - v0, v2 - v0)
    return normals / np.linalg.norm(normals, axis=1, keepdims=True)


def _centroids(mesh):
    return mesh.vertices[mesh.faces].mean(axis=1)


def _signed_volume(mesh):
    """Divergence theorem: positive for a closed surface whose winding faces outward."""
    v0, v1, v2 = (mesh.vertices[mesh.faces[:, k]] for k in range(3))
    return float(np.einsum("ij,ij->", v0, np.cross(v1, v2)) / 6.0)


def _transform_point(matrix, point):
    return (matrix @ np.append(point, 1.0))[:3]


# ---------------------------------------------------------------------------------------------------------------
# Primitives


def test_rectangle_is_the_square_facing_plus_z():
    mesh = rectangle()
    assert mesh.faces.shape == (2, 3)
    assert mesh.area() == pytest.approx(4.0)
    np.testing.assert_allclose(_unit_normals(mesh), [[0, 0, 1], [0, 0, 1]])
    np.testing.assert_array_equal(mesh.vertices[:, 2], 0.0)
    np.testing.assert_array_equal(np.abs(mesh.vertices[:, :2]), 1.0)


def test_cube_has_area_24_and_outward_faces():
    mesh = cube()
    assert mesh.faces.shape == (12, 3)
    assert mesh.area() == pytest.approx(24.0)
    np.testing.assert_allclose(mesh.triangle_areas(), 2.0)
    normals, centroids = _unit_normals(mesh), _centroids(mesh)
    # Each face's normal is the axis on which its centroid sits at +-1, pointing the same way.
    expected = np.where(np.abs(centroids) == 1.0, centroids, 0.0)
    np.testing.assert_allclose(normals, expected, atol=1e-15)
    assert _signed_volume(mesh) == pytest.approx(8.0)


def test_cube_faces_have_their_own_corners_spanning_the_whole_image():
    """24 vertices, four per face (so its texture seams stay sharp), no normals (flat shading), the same surface as
    the 8-corner cube once merged (watertight, outward). Each face maps the image once: its corners' uv are the four
    corners of the unit square, each uv an affine function of position across the face (which Mitsuba's cube it is:
    tests/interop/test_mitsuba_textures.py)."""
    mesh = cube()
    assert mesh.vertices.shape == (24, 3) and mesh.uvs is not None and mesh.uvs.shape == (24, 2)
    assert mesh.normals is None
    merged = trimesh.Trimesh(mesh.vertices, mesh.faces, process=False)
    merged.merge_vertices()
    assert len(merged.vertices) == 8 and merged.is_watertight and merged.is_winding_consistent
    normals = _unit_normals(mesh)
    for pair in range(6):
        triangles = mesh.faces[2 * pair : 2 * pair + 2]
        np.testing.assert_array_equal(normals[2 * pair], normals[2 * pair + 1])
        corners = np.unique(triangles)
        assert len(corners) == 4
        assert sorted(map(tuple, mesh.uvs[corners])) == [(0, 0), (0, 1), (1, 0), (1, 1)]
        # An affine map of position fits all four corners' uv exactly (a square's image is a square, not skewed).
        positions = np.column_stack([mesh.vertices[corners], np.ones(4)])
        fit = np.linalg.lstsq(positions, mesh.uvs[corners], rcond=None)[0]
        np.testing.assert_allclose(positions @ fit, mesh.uvs[corners], atol=1e-12)


def test_sphere_area_within_the_inscribed_bound_and_outward():
    mesh = sphere()
    assert len(mesh.faces) >= 20 * 4**4  # and the few cut at the texture seam
    assert np.all(np.linalg.norm(mesh.vertices, axis=1) <= 1.0 + 1e-12)
    normals = _unit_normals(mesh)
    # The distance of each face's plane from the centre. Projecting a flat face radially onto the unit sphere
    # scales its area by at most 1/d², so 4π d_min² <= area; a convex body inside the sphere has area <= 4π.
    plane_distance = np.einsum("ij,ij->i", normals, mesh.vertices[mesh.faces[:, 0]])
    assert np.all(plane_distance > 0), "every face must point away from the centre"
    assert 4 * math.pi * plane_distance.min() ** 2 <= mesh.area() < 4 * math.pi
    assert mesh.area() == pytest.approx(4 * math.pi, rel=5e-3)
    assert 0 < _signed_volume(mesh) < 4 / 3 * math.pi
    assert sphere(subdivisions=2).area() < sphere(subdivisions=3).area() < mesh.area()


def _mitsuba_sphere_uv(points: np.ndarray) -> np.ndarray:
    """Mitsuba 3's sphere parameterisation (its docs and its sphere's surface interaction): u = φ / 2π with
    φ = atan2(y, x) in [0, 2π), v = θ / π with θ the polar angle from +z."""
    d = points / np.linalg.norm(points, axis=-1, keepdims=True)
    return np.stack(
        [np.mod(np.arctan2(d[..., 1], d[..., 0]), 2 * np.pi) / (2 * np.pi), np.arccos(d[..., 2]) / np.pi], -1
    )


@pytest.mark.parametrize("subdivisions", [1, 4])
def test_sphere_uvs_are_mitsubas_and_no_triangle_wraps(subdivisions):
    """The sphere is the icosphere's surface (same area and volume, watertight once its seam copies are merged) with
    Mitsuba's uv at every corner: u = 1 standing for 0 only on the seam (y = 0, x > 0), and a pole's u free. No
    triangle spans more than its own width in u (none runs back across the image), and inside each triangle the
    interpolated uv stays within the tessellation's error of Mitsuba's at the same point's direction."""
    mesh = sphere(subdivisions)
    icosphere = trimesh.creation.icosphere(subdivisions=subdivisions)
    merged = trimesh.Trimesh(mesh.vertices, mesh.faces, process=False)
    merged.merge_vertices()
    assert merged.is_watertight and merged.is_winding_consistent
    assert merged.area == pytest.approx(icosphere.area, rel=1e-12)
    assert merged.volume == pytest.approx(icosphere.volume, rel=1e-12)
    corners = mesh.vertices[mesh.faces]
    uv = mesh.uvs[mesh.faces]
    expected = _mitsuba_sphere_uv(corners)
    pole = np.hypot(corners[..., 0], corners[..., 1]) < 1e-9
    seam = (np.abs(corners[..., 1]) < 1e-12) & (corners[..., 0] > 0)
    np.testing.assert_allclose(uv[..., 1], expected[..., 1], atol=1e-12)
    u_error = np.abs(uv[..., 0] - expected[..., 0])
    assert np.all(u_error[~pole & ~seam] < 1e-12)
    assert np.all(np.minimum(u_error, np.abs(u_error - 1.0))[seam & ~pole] < 1e-12)
    assert np.ptp(uv[..., 0], axis=1).max() < 0.25
    assert uv[..., 0].min() >= 0.0 and uv[..., 0].max() <= 1.0
    # Centroids away from the poles (where u is singular), against Mitsuba's uv of their direction.
    centroid = corners.mean(axis=1)
    away = np.abs(centroid[:, 2]) < 0.9 * np.linalg.norm(centroid, axis=1)
    difference = uv.mean(axis=1)[away] - _mitsuba_sphere_uv(centroid[away])
    difference[:, 0] -= np.round(difference[:, 0])
    assert np.abs(difference).max() < 0.1 / 2**subdivisions


@pytest.mark.parametrize("subdivisions", [-1, 9, 2.5, True])
def test_sphere_rejects_bad_subdivisions(subdivisions):
    with pytest.raises(SpectraceError, match="subdivisions"):
        sphere(subdivisions=subdivisions)


# ---------------------------------------------------------------------------------------------------------------
# Transforms


def test_steps_apply_in_list_order():
    point = np.array([1.0, 2.0, 3.0])
    translate_then_scale = transform_matrix([{"translate": [1, 0, 0]}, {"scale": 2}], WHERE)
    scale_then_translate = transform_matrix([{"scale": 2}, {"translate": [1, 0, 0]}], WHERE)
    # (1,2,3) + (1,0,0) = (2,2,3), then x2 = (4,4,6);  (1,2,3) x2 = (2,4,6), then + (1,0,0) = (3,4,6).
    np.testing.assert_allclose(_transform_point(translate_then_scale, point), [4, 4, 6])
    np.testing.assert_allclose(_transform_point(scale_then_translate, point), [3, 4, 6])


def test_rotation_is_right_handed_in_degrees():
    quarter_turn = transform_matrix([{"rotate": {"axis": [0, 0, 5], "angle": 90}}], WHERE)
    np.testing.assert_allclose(_transform_point(quarter_turn, [1, 0, 0]), [0, 1, 0], atol=1e-15)
    np.testing.assert_allclose(_transform_point(quarter_turn, [0, 1, 0]), [-1, 0, 0], atol=1e-15)
    np.testing.assert_allclose(_transform_point(quarter_turn, [0, 0, 2]), [0, 0, 2], atol=1e-15)
    about_x = transform_matrix([{"rotate": {"axis": [1, 0, 0], "angle": 90}}], WHERE)
    np.testing.assert_allclose(_transform_point(about_x, [0, 1, 0]), [0, 0, 1], atol=1e-15)
    # 120° about the diagonal cycles the axes x -> y -> z.
    cycle = transform_matrix([{"rotate": {"axis": [1, 1, 1], "angle": 120}}], WHERE)
    np.testing.assert_allclose(_transform_point(cycle, [1, 0, 0]), [0, 1, 0], atol=1e-12)


def test_matrix_step_is_row_major_on_column_vectors_and_scale_takes_a_vector():
    matrix = transform_matrix(
        [{"matrix": [[1, 0, 0, 5], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]}, {"scale": [1, 2, 3]}], WHERE
    )
    np.testing.assert_allclose(_transform_point(matrix, [1, 1, 1]), [6, 2, 3])
    np.testing.assert_array_equal(transform_matrix([], WHERE), np.eye(4))


def test_mirroring_keeps_normals_outward():
    for mirror in ([{"scale": [-1, 1, 1]}], [{"scale": [2, -1, -3]}, {"scale": [1, 1, -1]}]):
        mesh = apply_transform(cube(), transform_matrix(mirror, WHERE))
        assert np.all(np.einsum("ij,ij->i", _unit_normals(mesh), _centroids(mesh)) > 0)
        assert _signed_volume(mesh) > 0
    steps = [{"translate": [5, 0, 0]}, {"scale": -2}]
    shifted = apply_transform(sphere(subdivisions=1), transform_matrix(steps, WHERE))
    assert _signed_volume(shifted) > 0
    bounds = shifted.vertices.min(axis=0), shifted.vertices.max(axis=0)  # its seam's copies would weigh in a mean
    np.testing.assert_allclose((bounds[0] + bounds[1]) / 2, [-10, 0, 0], atol=1e-12)
    np.testing.assert_allclose(bounds[1] - bounds[0], 4.0, rtol=1e-12)


def test_apply_transform_leaves_the_input_alone():
    original = cube()
    before = original.vertices.copy(), original.faces.copy()
    apply_transform(original, transform_matrix([{"scale": -3}], WHERE))
    np.testing.assert_array_equal(original.vertices, before[0])
    np.testing.assert_array_equal(original.faces, before[1])


@pytest.mark.parametrize(
    ("steps", "where"),
    [
        ([{"translate": [0, 0, 1]}, {"spin": 3}], f"{WHERE}[1]"),
        ([{"translate": [0, 0, 1], "scale": 2}], f"{WHERE}[0]"),
        (["scale"], f"{WHERE}[0]"),
        ([{"translate": [0, 1]}], f"{WHERE}[0].translate"),
        ([{"translate": [0, "1", 2]}], f"{WHERE}[0].translate[1]"),
        ([{"scale": 0}], f"{WHERE}[0].scale"),
        ([{"scale": True}], f"{WHERE}[0].scale"),
        ([{"scale": [1, float("nan"), 1]}], f"{WHERE}[0].scale[1]"),
        ([{"scale": 1}, {"rotate": {"axis": [0, 0, 0], "angle": 30}}], f"{WHERE}[1].rotate.axis"),
        ([{"rotate": {"axis": [0, 0, 1]}}], f"{WHERE}[0].rotate"),
        ([{"rotate": {"axis": [0, 0, 1], "angle": "90"}}], f"{WHERE}[0].rotate.angle"),
        ([{"matrix": [[1, 0, 0], [0, 1, 0], [0, 0, 1]]}], f"{WHERE}[0].matrix"),
        ([{"matrix": [[1, 0, 0, 0], [0, 1, 0, 0], [1, 1, 0, 0], [0, 0, 0, 1]]}], f"{WHERE}[0].matrix"),
        ([{"matrix": [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 1, 1]]}], f"{WHERE}[0].matrix[3]"),
    ],
)
def test_errors_name_their_key_path(steps, where):
    with pytest.raises(SpectraceError) as caught:
        transform_matrix(steps, WHERE)
    assert caught.value.where == where
    assert "\n" not in str(caught.value)


def test_a_non_list_transform_is_an_error():
    with pytest.raises(SpectraceError) as caught:
        transform_matrix({"scale": 2}, WHERE)
    assert caught.value.where == WHERE


# ---------------------------------------------------------------------------------------------------------------
# Loading


def _random_mesh(seed):
    rng = np.random.default_rng(seed)
    vertices = rng.uniform(-1, 1, (40, 3))
    faces = np.array([rng.choice(40, 3, replace=False) for _ in range(60)])
    return vertices, faces


@pytest.mark.parametrize("extension", ["obj", "ply"])
def test_load_round_trip_keeps_vertices_and_winding(tmp_path, extension):
    vertices, faces = _random_mesh(4)
    path = tmp_path / f"mesh.{extension}"
    trimesh.Trimesh(vertices, faces, process=False).export(path)
    mesh = load_mesh(path, where="scene.toml: shapes[0].file")
    assert isinstance(mesh, TriangleMesh)
    assert mesh.vertices.dtype == np.float64 and mesh.faces.dtype == np.int64
    np.testing.assert_allclose(mesh.vertices, vertices, rtol=1e-7, atol=1e-7)
    np.testing.assert_array_equal(mesh.faces, faces)


def test_a_file_with_several_meshes_is_merged(tmp_path):
    box = trimesh.creation.box()
    ball = trimesh.creation.icosphere(subdivisions=1)
    ball.apply_translation([3, 0, 0])
    path = tmp_path / "two.glb"
    trimesh.Scene([box, ball]).export(path)
    mesh = load_mesh(path, where="w")
    assert len(mesh.faces) == len(box.faces) + len(ball.faces)
    assert mesh.area() == pytest.approx(box.area + ball.area)


def test_missing_file_names_the_key(tmp_path):
    with pytest.raises(SpectraceError, match="does not exist") as caught:
        load_mesh(tmp_path / "nowhere.obj", where="scene.toml: shapes[2].file")
    assert caught.value.where == "scene.toml: shapes[2].file"


@pytest.mark.parametrize(
    ("name", "content", "message"),
    [
        ("garbage.obj", "v 1 2\nthis is not an obj\n", "cannot read|no triangles"),
        ("empty.obj", "", "no triangles"),
        ("points.obj", "v 0 0 0\nv 1 0 0\n", "no triangles"),
        ("nan.obj", "v nan 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "NaN"),
        ("inf.obj", "v 0 0 0\nv inf 0 0\nv 0 1 0\nf 1 2 3\n", "NaN or infinite"),
        ("mesh.unknownformat", "solid", "cannot read"),
    ],
)
def test_unusable_files_raise_one_line_errors(tmp_path, name, content, message):
    path = tmp_path / name
    path.write_text(content)
    with pytest.raises(SpectraceError, match=message) as caught:
        load_mesh(path, where="scene.toml: shapes[1].file")
    assert caught.value.where == "scene.toml: shapes[1].file"
    assert "\n" not in str(caught.value)


def test_an_obj_file_that_goes_to_trimesh_is_read_from_disk_once(tmp_path, monkeypatch):
    """A textured OBJ (which the plain reader declines) is scanned for index 0 and vt, and parsed by trimesh: from
    one read of the file. Its seam vertex still splits into one vertex per texture coordinate."""
    import builtins
    import io

    path = tmp_path / "seam.obj"
    path.write_text(
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0.5 0.5\nf 1/1 2/2 3/3\nf 1/4 3/3 4/1\n"
    )
    opened = []
    for module, name in ((builtins, "open"), (io, "open")):
        original = getattr(module, name)

        def counting(file, *args, _original=original, **kwargs):
            if str(file) == str(path):
                opened.append(file)
            return _original(file, *args, **kwargs)

        monkeypatch.setattr(module, name, counting)
    mesh = load_mesh(path, where="test")
    assert len(opened) == 1
    assert len(mesh.faces) == 2 and len(mesh.vertices) == 5  # vertex 1 has two texture coordinates
