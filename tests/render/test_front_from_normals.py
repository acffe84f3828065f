"""Where a mesh has vertex normals, they say which side of it is the front, whatever its winding: a closed mesh with
outward normals but inward winding (as some exporters write them) must render as the same mesh wound outward, for
one-sided materials and one-sided area lights, on its own or as a mirrored instance, in the path tracer and in the
adjoint integrators (light tracing, BDPT), and its stored geometric normals (which decide a dielectric's and a
medium's inside) must point outward. Mitsuba 3 decides the side by the shading frame alike
(tests/interop/test_mitsuba_one_sided.py compares)."""

from dataclasses import replace

import numpy as np
import pytest

import spectrace
from replica_agreement import assert_replicas_agree, spectrace_replicas
from spectrace.engine.renderer import Renderer
from spectrace.engine.scene_buffers import build_scene_buffers
from spectrace.geometry import primitives
from spectrace.geometry.mesh import TriangleMesh, winding_against_normals
from spectrace.scene.model import Scene

CAMERA = spectrace.Camera(origin=(0.0, -4.0, 1.0), target=(0.0, 0.0, 0.0), fov_degrees=45.0)


def _sphere(wound_inward: bool, subdivisions: int = 2) -> TriangleMesh:
    """The unit icosphere with its radial (outward) normals, its faces wound outward or all reversed."""
    mesh = primitives.sphere(subdivisions)
    faces = mesh.faces[:, ::-1] if wound_inward else mesh.faces
    return TriangleMesh(mesh.vertices, faces, uvs=mesh.uvs, normals=mesh.normals)


def _geometric_normals(mesh: TriangleMesh) -> np.ndarray:
    v0, v1, v2, _, _ = mesh.corners()
    n = np.cross(v1 - v0, v2 - v0)
    return n / np.linalg.norm(n, axis=1, keepdims=True)


def _corner_data(mesh: TriangleMesh) -> np.ndarray:
    """(M, 3, 8): each triangle's corners as corners() gives them, position, texture coordinates and normal."""
    v0, v1, v2, uvs, normals = mesh.corners()
    return np.concatenate([np.stack([v0, v1, v2], axis=1), uvs, normals], axis=-1)


def _rotation_of(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(M,) True where triangle a[i]'s corners are b[i]'s in a cyclic order (the same winding)."""
    return np.any([np.all(a == np.roll(b, shift, axis=1), axis=(1, 2)) for shift in range(3)], axis=0)


def test_corners_wind_each_triangle_toward_its_normals():
    outward = _sphere(False)
    assert not winding_against_normals(*outward.triangles(), outward.triangle_normals()).any()
    # Every face reversed, or every other one: the renderer gets the outward sphere's triangles back.
    mixed = TriangleMesh(outward.vertices, outward.faces.copy(), uvs=outward.uvs, normals=outward.normals)
    mixed.faces[::2] = mixed.faces[::2, ::-1]
    for mesh in (_sphere(True), mixed):
        assert winding_against_normals(*mesh.triangles(), mesh.triangle_normals()).any()
        np.testing.assert_allclose(_geometric_normals(mesh), _geometric_normals(outward), atol=1e-12)
        # The same triangles, each corner keeping its position, texture coordinates and normal: the outward
        # sphere's corners, rotated.
        assert np.all(_rotation_of(_corner_data(mesh), _corner_data(outward)))
    # Without vertex normals the winding alone says where the front is.
    flat = _sphere(True).with_normals(None)
    v0, v1, v2, _, normals = flat.corners()
    assert normals is None
    np.testing.assert_array_equal(np.stack([v0, v1, v2]), np.stack(flat.triangles()))


def test_flipped_turns_both_the_winding_and_the_normals():
    mesh = _sphere(False)
    flipped = mesh.flipped()
    np.testing.assert_allclose(_geometric_normals(flipped), -_geometric_normals(mesh), atol=1e-12)
    np.testing.assert_array_equal(flipped.normals, -mesh.normals)


def _stored_normals(shape) -> tuple[np.ndarray, np.ndarray]:
    """The geometric normals the kernels read (w of each triangle's corners) and the triangles' centroids."""
    scene = Scene(camera=CAMERA, width=4, height=4, shapes=[shape])
    buffers = build_scene_buffers(scene)
    v = buffers.triangle_vertices.reshape(-1, 3, 4)[: buffers.triangle_count].astype(np.float64)
    return v[:, :, 3], v[:, :, :3].mean(axis=1)


@pytest.mark.parametrize(
    "shape, outward",
    [
        (spectrace.shape(_sphere(True), spectrace.dielectric(1.5)), True),
        (spectrace.shape(_sphere(False), spectrace.dielectric(1.5)), True),
        (spectrace.shape(_sphere(True).with_normals(None), spectrace.dielectric(1.5)), False),
        (spectrace.shape("sphere", spectrace.diffuse(0.5), tessellated=True, flip_normals=True), False),
    ],
    ids=["inward-wound, outward normals", "outward", "inward-wound, flat", "tessellated, flip_normals"],
)
def test_the_kernels_geometric_normal_faces_the_front(shape, outward):
    """The geometric normal decides every side (dielectric and medium insides, one-sided materials and lights): it
    must point to the normals' side where there are normals, the winding's where there are none, and inward on a
    tessellated sphere whose flip_normals turns its front."""
    normals, centroids = _stored_normals(shape)
    facing = np.einsum("ij,ij->i", normals, centroids)
    assert np.all(facing > 0) if outward else np.all(facing < 0)


def _sphere_scene(wound_inward: bool, integrator: str) -> Scene:
    """A one-sided diffuse sphere on a one-sided diffuse floor, lit by a point light."""
    sphere = spectrace.shape(_sphere(wound_inward), spectrace.diffuse((0.7, 0.5, 0.3), two_sided=False))
    floor = spectrace.shape(
        "rectangle", spectrace.diffuse(0.5, two_sided=False), transform=[{"scale": 4}, {"translate": [0, 0, -1]}]
    )
    return Scene(
        camera=CAMERA, width=16, height=16, shapes=[sphere, floor],
        lights=[spectrace.point_light((1.5, -2.5, 2.5), intensity=30.0)], integrator=integrator, max_depth=3,
        seed=3,
    )  # fmt: skip


def _lamp_scene(wound_inward: bool, integrator: str) -> Scene:
    """A one-sided emitting sphere (black material) over a one-sided diffuse floor: it lights the floor and shows to
    the camera only from outside."""
    lamp = spectrace.shape(
        _sphere(wound_inward), spectrace.diffuse(0.0), emitter=spectrace.area_emitter(1.0),
        transform=[{"scale": 0.5}, {"translate": [0, 0, 0.3]}],
    )  # fmt: skip
    floor = spectrace.shape(
        "rectangle", spectrace.diffuse(0.5, two_sided=False), transform=[{"scale": 4}, {"translate": [0, 0, -1]}]
    )
    return Scene(
        camera=CAMERA, width=16, height=16, shapes=[lamp, floor], integrator=integrator, max_depth=3, seed=3
    )  # fmt: skip


def _instanced_scene(wound_inward: bool, integrator: str) -> Scene:
    """_sphere_scene with the sphere an instanced object, placed by a mirroring map (which turns the winding)."""
    scene = _sphere_scene(wound_inward, integrator)
    obj = spectrace.instanced_object([scene.shapes[0]])
    mirrored = spectrace.instance(obj, [{"scale": [-1, 1, 1]}, {"rotate": {"axis": [0, 0, 1], "angle": 30}}])
    return replace(scene, shapes=scene.shapes[1:], instances=[mirrored])


@pytest.mark.parametrize("integrator", ["path", "light", "bdpt"])
@pytest.mark.parametrize(
    "make",
    [_sphere_scene, _lamp_scene, _instanced_scene],
    ids=["one-sided material", "one-sided lamp", "mirrored instance"],
)
def test_a_mesh_wound_against_its_normals_renders_as_wound_along_them(device, integrator, make):
    """REPLICAS independent images of each: 4 x 4-pixel block means and the image mean within 5 standard errors
    (tests/replica_agreement.py). The reference is the outward-wound sphere, whose sides were never in question."""
    # The light tracer's image of a point-lit sphere is the noisy one: 192 spp hold its image mean to 3 %.
    noisy = integrator == "light" and make is not _lamp_scene
    replicas, replica_spp = 8, 192 if noisy else 32

    def images(wound_inward: bool) -> np.ndarray:
        return spectrace_replicas(Renderer(make(wound_inward, integrator), device), replicas, replica_spp)

    reference = images(False)
    assert reference[..., 1].mean() > 0.01  # the comparison sees a lit scene
    assert_replicas_agree(images(True), reference, block=4)
