"""Analytic spheres, disks and cylinders inside instanced objects (kernels/scene.cl, "Instances"): the kernels carry
the ray into the object's space, so an instance's map may stretch, shear or mirror the exact surface. Checked
against float64 closed forms of the placed quadric (hit distance in world units, point, normal by the inverse
transpose, texture coordinates), against the same shape placed directly by the composite map, against analytic
projected areas seen orthographically (an elliptic cylinder's 2 a h, an ellipsoid's π a b), and by rendering the
instanced scene and the same scene placed directly (block means within 5 standard errors)."""

from dataclasses import replace

import numpy as np
import pytest
from tests.geometry.test_analytic_shapes import _reference_hits
from tests.geometry.test_instances import _trace

import spectrace
from replica_agreement import assert_replicas_agree
from spectrace.engine.renderer import Renderer
from spectrace.geometry.analytic import AnalyticSurface
from spectrace.geometry.transforms import transform_matrix
from spectrace.scene.model import Shape
from stats_toolkit import assert_within_standard_errors

# The object's shapes in object space, then instance placements: a move, a non-uniform scale under a rotation, a
# shear and a mirror (which turns the object inside out unless normals follow M⁻ᵀ).
OBJECT = {
    "sphere": [{"scale": 0.4}, {"translate": [0.0, 0.5, 0.0]}],
    "disk": [{"scale": [0.5, 0.3, 1.0]}, {"rotate": {"axis": [1, 0, 0], "angle": -70}}, {"translate": [0.6, 0, 0]}],
    "cylinder": [
        {"scale": [0.2, 0.2, 0.8]},
        {"rotate": {"axis": [1, 0, 0], "angle": -90}},
        {"translate": [-0.6, 0, 0]},
    ],
}
PLACEMENTS = [
    [{"translate": [-1.5, 0.0, 0.0]}],
    [{"scale": [1.6, 0.7, 1.2]}, {"rotate": {"axis": [0, 1, 1], "angle": 35}}, {"translate": [1.4, 0.2, 0.3]}],
    [{"matrix": [[1, 0.4, 0, 0], [0, 1, 0, 0], [0.3, 0, 1, 0], [0, 0, 0, 1]]}, {"translate": [0.0, 0.1, -1.3]}],
    [{"matrix": [[-1, 0, 0, 0], [0, 1.3, 0, 0], [0, 0, 0.8, 0], [0, 0, 0, 1]]}, {"translate": [0.1, 0.0, 1.4]}],
]
CAMERA = spectrace.Camera(origin=(0.0, 2.5, -4.0), target=(0.0, 0.3, 0.0))


def _object_shapes(material=None) -> list[Shape]:
    material = material or spectrace.diffuse(0.6)
    return [spectrace.shape(kind, material, transform=steps, name=kind) for kind, steps in OBJECT.items()]


def _placed(kind: str, placement) -> AnalyticSurface:
    """The shape placed directly by the composite map (instance ∘ object-space placement)."""
    return AnalyticSurface(kind, transform_matrix(placement, "t") @ transform_matrix(OBJECT[kind], "t"))


def _scene(shapes: list[Shape] = (), instances=(), lights=()) -> spectrace.Scene:
    return spectrace.Scene(
        camera=CAMERA, width=24, height=24, spp=4, shapes=list(shapes), instances=list(instances), lights=list(lights)
    )


def _rays(count: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    origins = rng.normal(size=(count, 3))
    origins = 4.0 * origins / np.linalg.norm(origins, axis=1, keepdims=True)
    targets = rng.uniform([-2.2, -0.8, -1.8], [2.2, 1.2, 1.8], (count, 3))
    directions = targets - origins
    return origins, directions / np.linalg.norm(directions, axis=1, keepdims=True)


def _reference(origins, directions):
    """Closest hit over every placed shape in float64: t, world point, unit normal (M⁻ᵀ of the object-space normal),
    texture coordinates (Mitsuba 3's conventions, spectrace.geometry.analytic)."""
    best_t = np.full(len(origins), np.inf)
    best_n, best_uv = np.zeros((len(origins), 3)), np.zeros((len(origins), 2))
    for placement in PLACEMENTS:
        for kind in OBJECT:
            surface = _placed(kind, placement)
            t, local = _reference_hits(surface, origins, directions)
            n_local = {
                "sphere": local,
                "disk": np.tile([0.0, 0.0, 1.0], (len(local), 1)),
                "cylinder": local * [1, 1, 0],
            }
            n = n_local[kind] @ np.linalg.inv(surface.linear)
            n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)
            phi = np.mod(np.arctan2(local[:, 1], local[:, 0]) / (2 * np.pi), 1.0)
            uv = {
                "sphere": np.stack([phi, np.arctan2(np.hypot(local[:, 0], local[:, 1]), local[:, 2]) / np.pi], 1),
                "disk": np.stack([np.hypot(local[:, 0], local[:, 1]), phi], 1),
                "cylinder": np.stack([phi, local[:, 2]], 1),
            }[kind]
            closer = t < best_t
            best_t[closer], best_n[closer], best_uv[closer] = t[closer], n[closer], uv[closer]
    return best_t, best_n, best_uv


def _turns_apart(a, b):
    """Distance between azimuths in turns, across the seam."""
    d = np.abs(a - b) % 1.0
    return np.minimum(d, 1.0 - d)


@pytest.mark.parametrize("with_triangles", [False, True])
def test_instanced_shapes_meet_rays_as_the_placed_quadrics(kernel_runner, with_triangles):
    """Objects of analytic shapes only (no BVH of their own) and with a small mesh beside them."""
    shapes = _object_shapes()
    if with_triangles:  # a speck of triangles far below, so the object has a BVH too
        shapes.append(
            spectrace.shape("cube", spectrace.diffuse(0.3), transform=[{"scale": 0.01}, {"translate": [0, -5, 0]}])
        )
    obj = spectrace.instanced_object(shapes, name="parts")
    scene = _scene(instances=[spectrace.instance(obj, steps) for steps in PLACEMENTS])
    origins, directions = _rays(4000, seed=3)
    t_ref, n_ref, uv_ref = _reference(origins, directions)
    assert 0.3 < np.isfinite(t_ref).mean() < 0.9
    t_max = np.where(np.isfinite(t_ref), t_ref, 10.0)
    short = _trace(kernel_runner, scene, origins, directions, t_max * 0.999)[1][4]
    _, (hit, point, normal, shading, past) = _trace(kernel_runner, scene, origins, directions, t_max * 1.001)
    t = hit[:, 0].astype(np.float64)
    agree = np.isfinite(t) == np.isfinite(t_ref)
    assert agree.mean() > 0.998  # rays grazing a rim may fall either side in float
    both = agree & np.isfinite(t_ref)
    # Distances in world units, whatever the instance's scale.
    np.testing.assert_allclose(t[both], t_ref[both], rtol=5e-5, atol=5e-6)
    np.testing.assert_allclose(point[both, :3], origins[both] + t_ref[both, None] * directions[both], atol=5e-5)
    np.testing.assert_allclose(normal[both, :3], n_ref[both], atol=2e-4)  # the front kept under the mirror
    np.testing.assert_array_equal(shading[both, :3], normal[both, :3])  # exact surfaces shade with their normal
    u_is_turns = np.abs(uv_ref[both, 1] - hit[both, 2]) < 1e-3  # sphere and cylinder: u; disk: v
    assert u_is_turns.mean() > 0.5
    assert np.quantile(_turns_apart(hit[both, 1], uv_ref[both, 0]) * u_is_turns, 0.999) < 1e-3
    assert np.quantile(np.abs(hit[both, 2] - uv_ref[both, 1]), 0.999) < 1e-3
    # Any-hit queries see the shape just past its distance and not just before it.
    hits = np.isfinite(t_ref)
    assert np.mean(short[hits] == 0) > 0.998 and np.mean(past[hits] == 1) > 0.998
    assert not np.any(past[~hits & ~np.isfinite(t)])


def test_instanced_shapes_match_the_same_shapes_placed_directly(kernel_runner):
    """Disks and cylinders take any affine map directly, spheres a similarity: the placements that allow it give
    the same hits both ways (to float rounding of the two routes)."""
    obj = spectrace.instanced_object(_object_shapes(), name="parts")
    placements = PLACEMENTS[:1] + [
        [{"scale": 1.3}, {"rotate": {"axis": [1, 1, 0], "angle": 50}}, {"translate": [1.2, 0, 0]}]
    ]
    placements += PLACEMENTS[1:]
    material = spectrace.diffuse(0.6)
    direct = []
    for k, placement in enumerate(placements):
        for kind in OBJECT:
            surface = _placed(kind, placement)
            if kind == "sphere" and k > 1:
                continue  # a stretched sphere is no sphere: only instances can hold it (the test above)
            direct.append(Shape(surface.tessellation(), material, name=f"{kind}{k}", analytic=surface))
    instanced = _scene(instances=[spectrace.instance(obj, steps) for steps in placements])
    origins, directions = _rays(3000, seed=8)
    t_max = np.full(len(origins), 1e9)
    _, (hit_i, point_i, normal_i, _, _) = _trace(kernel_runner, instanced, origins, directions, t_max)
    _, (hit_d, point_d, normal_d, _, _) = _trace(kernel_runner, _scene(direct), origins, directions, t_max)
    # Where the direct scene lacks a stretched sphere, the instanced one may meet that sphere first.
    t_ref_spheres = np.full(len(origins), np.inf)
    for placement in placements[2:]:
        t_ref_spheres = np.minimum(t_ref_spheres, _reference_hits(_placed("sphere", placement), origins, directions)[0])
    compare = np.isfinite(hit_d[:, 0]) & ~(t_ref_spheres <= hit_d[:, 0] * 1.001)
    assert compare.sum() > 800
    same = np.abs(hit_i[compare, 0] - hit_d[compare, 0]) <= 2e-5 * hit_d[compare, 0]
    assert same.mean() > 0.998
    sel = np.flatnonzero(compare)[same]
    np.testing.assert_allclose(point_i[sel, :3], point_d[sel, :3], atol=5e-5)
    np.testing.assert_allclose(normal_i[sel, :3], normal_d[sel, :3], atol=2e-4)


def _orthographic_hit_fraction(kernel_runner, scene, axis: int, half: tuple[float, float], count: int, seed: int):
    """Fraction of parallel rays along −axis, from uniform points of a 2 half[0] x 2 half[1] window, that meet the
    scene; its binomial standard error."""
    rng = np.random.default_rng(seed)
    others = [k for k in range(3) if k != axis]
    origins = np.zeros((count, 3))
    origins[:, others[0]] = rng.uniform(-half[0], half[0], count)
    origins[:, others[1]] = rng.uniform(-half[1], half[1], count)
    origins[:, axis] = 10.0
    directions = np.zeros((count, 3))
    directions[:, axis] = -1.0
    occluded = _trace(kernel_runner, scene, origins, directions, np.full(count, 100.0))[1][4]
    p = float(np.mean(occluded == 1))
    return p, np.sqrt(p * (1 - p) / count)


@pytest.mark.parametrize(
    ("kind", "placement", "axis", "area"),
    [
        # An elliptic cylinder (semi-axes 0.5 along x, 0.3 along y, length 2): from +y its silhouette is 2·0.5 x 2,
        # from +x 2·0.3 x 2 (2 r h times the scale across the view).
        ("cylinder", [{"scale": [0.5, 0.3, 2.0]}], 1, 2.0 * 0.5 * 2.0),
        ("cylinder", [{"scale": [0.5, 0.3, 2.0]}], 0, 2.0 * 0.3 * 2.0),
        # An ellipsoid of semi-axes (1, 0.5, 1.5) seen along z: an ellipse of area π·1·0.5.
        ("sphere", [{"scale": [1.0, 0.5, 1.5]}], 2, np.pi * 1.0 * 0.5),
        # An elliptic disk (semi-axes 2, 1) tilted 30° about x, seen along z: π·2·1·cos 30°.
        (
            "disk",
            [{"scale": [2.0, 1.0, 1.0]}, {"rotate": {"axis": [1, 0, 0], "angle": 30}}],
            2,
            2 * np.pi * np.cos(np.pi / 6),
        ),
    ],
)
def test_projected_areas_seen_orthographically_are_the_analytic_ones(kernel_runner, kind, placement, axis, area):
    obj = spectrace.instanced_object([spectrace.shape(kind, spectrace.diffuse(0.5))], name=kind)
    scene = _scene(instances=[spectrace.instance(obj, placement)])
    half = (2.5, 2.5)
    p, error = _orthographic_hit_fraction(kernel_runner, scene, axis, half, 200_000, seed=21)
    window = 4 * half[0] * half[1]
    assert_within_standard_errors(p * window, area, error * window, sigmas=4.5, what=f"{kind} projected area")


@pytest.mark.slow
def test_instanced_shapes_render_as_the_same_shapes_placed_directly(device):
    """Plastic disks, cylinders and spheres under a light, instanced under non-uniform scales (the spheres' placements
    similarities, so they can be placed directly too) and placed directly: 8 independent images each, every 6 x 6
    block's mean XYZ within 5 standard errors of the difference."""
    material = spectrace.plastic((0.7, 0.4, 0.2), roughness=0.3)
    obj = spectrace.instanced_object(_object_shapes(material), name="parts")
    placements = [
        [{"scale": 1.2}, {"rotate": {"axis": [0, 1, 0], "angle": 30}}, {"translate": [-1.2, 0, 0]}],
        [{"scale": [1.5, 1.5, 0.6]}, {"translate": [1.1, 0, 0.2]}],  # scales the sphere's z: kept out of `direct`
    ]
    ground = spectrace.shape(
        "rectangle",
        spectrace.diffuse(0.5),
        transform=[{"rotate": {"axis": [1, 0, 0], "angle": -90}}, {"scale": 3}, {"translate": [0, -0.4, 0]}],
    )
    light = spectrace.shape(
        "rectangle",
        spectrace.diffuse(0.0),
        emitter=spectrace.area_emitter(10.0),
        transform=[{"scale": 0.6}, {"rotate": {"axis": [1, 0, 0], "angle": 90}}, {"translate": [0, 3, 0]}],
    )
    direct = [
        Shape(_placed(kind, placement).tessellation(), material, name=f"{kind}{k}", analytic=_placed(kind, placement))
        for k, placement in enumerate(placements)
        for kind in OBJECT
        if not (kind == "sphere" and k == 1)
    ]
    # The stretched sphere in both scenes: by the object on one side, by a one-shape object on the other.
    ball = spectrace.instanced_object([spectrace.shape("sphere", material, transform=OBJECT["sphere"])], name="ball")
    instanced = _scene([ground, light], [spectrace.instance(obj, steps) for steps in placements])
    expanded = replace(instanced, shapes=[ground, light, *direct], instances=[spectrace.instance(ball, placements[1])])
    replicas = {}
    for name, scene in (("instanced", instanced), ("expanded", expanded)):
        replicas[name] = np.stack(
            [
                Renderer(scene.with_overrides(seed=s + (100 if name == "expanded" else 0)), device).render().xyz
                for s in range(8)
            ]
        )
    assert replicas["instanced"][..., 1].mean() > 0
    assert_replicas_agree(replicas["instanced"], replicas["expanded"], block=6)
