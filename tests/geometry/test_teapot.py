"""The Utah teapot built from Newell's patches: its body is (nearly) a surface of revolution, so the exact normals there
must lie in the plane through the axis and point away from it; the triangles wind outward; and the surface
converges (its area settles as the tessellation is refined)."""

import numpy as np

from spectrace.geometry.teapot import BODY_PATCHES, newell_teapot


def _face_normals(vertices, faces):
    normals = np.cross(vertices[faces[:, 1]] - vertices[faces[:, 0]], vertices[faces[:, 2]] - vertices[faces[:, 0]])
    return normals, np.linalg.norm(normals, axis=1)


def test_body_normals_are_those_of_a_surface_of_revolution():
    vertices, _, _, normals = newell_teapot(6)
    per_patch = 7 * 7
    body = slice(4 * per_patch, BODY_PATCHES * per_patch)  # upper and lower body (the rim curls back inward)
    p, n = vertices[body], normals[body]
    radial = p[:, :2] / np.linalg.norm(p[:, :2], axis=1, keepdims=True)
    tangent_around = np.stack([-radial[:, 1], radial[:, 0]], axis=1)
    # Newell drew each quarter turn as a cubic with handles at 0.56 of the radius, not an exact circle, so the
    # normal leans around the axis by up to about half a degree; a wrong derivative would lean it by far more.
    assert np.max(np.abs(np.sum(n[:, :2] * tangent_around, axis=1))) < 0.01
    assert np.all(np.sum(n[:, :2] * radial, axis=1) > 0.0)  # outward
    assert np.allclose(np.linalg.norm(normals, axis=1), 1.0)


def test_triangles_wind_like_the_vertex_normals():
    vertices, faces, uvs, normals = newell_teapot(8)
    face_normals, areas = _face_normals(vertices, faces)
    real = areas > 1e-12  # triangles at a collapsed patch edge have no area
    cosines = np.sum(face_normals[real] / areas[real, None] * normals[faces[real]].mean(axis=1), axis=1)
    assert np.all(cosines > 0.0)
    assert uvs.min() == 0.0 and uvs.max() == 1.0


def test_area_converges():
    areas = [0.5 * _face_normals(*newell_teapot(n)[:2])[1].sum() for n in (4, 8, 16, 32)]
    # A smooth surface's flat tessellation errs by O(h^2): each halving of the quads cuts the error about 4-fold.
    steps = np.abs(np.diff(areas))
    assert steps[1] < 0.4 * steps[0] and steps[2] < 0.4 * steps[1]


def test_the_built_in_teapot_stands_on_the_origin_y_up():
    from spectrace.geometry.primitives import BUILTIN_SHAPES

    mesh = BUILTIN_SHAPES["teapot"]()
    low, high = mesh.vertices.min(axis=0), mesh.vertices.max(axis=0)
    assert np.isclose(low[1], 0.0) and np.isclose(high[1], 1.575)  # base on y = 0, the knob at half of 3.15
    assert np.isclose(low[2], -1.0) and np.isclose(high[2], 1.0)  # body radius 1 across the spout's plane
    assert high[0] > 1.5 and low[0] < -1.4  # spout towards +x, handle towards -x
    # The normals turned with the vertices: on the body's widest ring they point straight out.
    widest = np.abs(mesh.vertices[:, 2]) > 0.999
    assert np.allclose(mesh.normals[widest][:, 2], np.sign(mesh.vertices[widest][:, 2]), atol=1e-6)
