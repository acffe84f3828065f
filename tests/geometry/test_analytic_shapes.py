"""Analytic sphere, disk and cylinder (kernels/shapes.cl, spectrace.geometry.analytic): hits against float64 closed
forms and against Mitsuba 3's own ray_intersect (t, point, normal, uv, dp/du, dp/dv), the sphere's precision far
from the ray origin, the cone sampling of a sphere light (chi-square of the directions, the exact pdf, points on
the sphere), and uniform area sampling (its density integrates to the area, also under a non-uniform scale)."""

import numpy as np
import pytest

from spectrace.core.contract import ANALYTIC_SHAPE_DTYPE
from spectrace.geometry.analytic import AnalyticSurface
from spectrace.geometry.transforms import transform_matrix
from stats_toolkit import assert_chi_square_fits

CASES = {
    "sphere": [{"scale": 0.7}, {"rotate": {"axis": [1, 2, 3], "angle": 40}}, {"translate": [0.3, -0.2, 0.5]}],
    "disk": [
        {"scale": [1.5, 0.6, 1.0]},
        {"rotate": {"axis": [1, 0, 0], "angle": 60}},
        {"rotate": {"axis": [0, 0, 1], "angle": 25}},
        {"translate": [0.1, 0.2, -0.3]},
    ],
    "cylinder": [
        {"scale": [0.5, 0.5, 1.8]},
        {"rotate": {"axis": [0, 1, 1], "angle": 70}},
        {"translate": [-0.2, 0.1, 0.4]},
    ],
}


def _surface(kind: str, steps=None) -> AnalyticSurface:
    return AnalyticSurface(kind, transform_matrix(CASES[kind] if steps is None else steps, where="test"))


def _rays(surface: AnalyticSurface, count: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """Rays from a shell around the shape toward random points of its tessellation's bounds (most hit it)."""
    rng = np.random.default_rng(seed)
    vertices = surface.tessellation().vertices
    lo, hi = vertices.min(axis=0), vertices.max(axis=0)
    centre, size = (lo + hi) / 2, np.linalg.norm(hi - lo)
    origins = centre + rng.normal(size=(count, 3)) * size
    targets = rng.uniform(lo, hi, size=(count, 3))
    directions = targets - origins
    return origins, directions / np.linalg.norm(directions, axis=1, keepdims=True)


def _device_hits(kernel_runner, surface: AnalyticSurface, origins, directions):
    runner = kernel_runner("testing/analytic_shapes.cl")
    n = len(origins)
    shapes = np.repeat(surface.device_row()[None], n).astype(ANALYTIC_SHAPE_DTYPE)
    pad = np.zeros((n, 1), np.float32)
    inputs = [np.hstack([origins, pad]).astype(np.float32), np.hstack([directions, pad]).astype(np.float32)]
    outputs = [np.zeros((n, 4), np.float32) for _ in range(5)]
    args = [runner.buffer(shapes), *(runner.buffer(a) for a in inputs)]
    args += [runner.buffer(o, writable=True) for o in outputs] + [np.int32(n)]
    runner.run("shape_hits", n, args, {3 + k: o for k, o in enumerate(outputs)})
    return outputs  # hit (t, u, v), p (+ area stretch), n, dpdu, dpdv


def _reference_hits(surface: AnalyticSurface, origins, directions) -> tuple[np.ndarray, np.ndarray]:
    """Nearest t > 0 and the object-space hit point, in float64 (inf where the ray misses)."""
    inverse = np.linalg.inv(surface.to_world)
    o = origins @ inverse[:3, :3].T + inverse[:3, 3]
    d = directions @ inverse[:3, :3].T
    t = np.full(len(o), np.inf)
    with np.errstate(divide="ignore", invalid="ignore"):
        if surface.kind == "disk":
            t0 = -o[:, 2] / d[:, 2]
            p = o + t0[:, None] * d
            ok = (t0 > 0) & (np.hypot(p[:, 0], p[:, 1]) <= 1)
            t = np.where(ok, t0, np.inf)
        else:
            xy = slice(0, 3) if surface.kind == "sphere" else slice(0, 2)
            a = (d[:, xy] ** 2).sum(1)
            b = (o[:, xy] * d[:, xy]).sum(1)
            c = (o[:, xy] ** 2).sum(1) - 1
            root = np.sqrt(b * b - a * c)
            for candidate in ((-b + root) / a, (-b - root) / a):
                z = o[:, 2] + candidate * d[:, 2]
                valid = candidate > 0
                if surface.kind == "cylinder":
                    valid &= (z >= 0) & (z <= 1)
                t = np.where(valid & (candidate < t), candidate, t)
    return t, o + np.where(np.isfinite(t), t, 0)[:, None] * d


@pytest.mark.parametrize("kind", CASES)
def test_hits_agree_with_float64_closed_forms(kernel_runner, kind):
    surface = _surface(kind)
    origins, directions = _rays(surface, 2000, seed=1)
    hit, p, n, dpdu, dpdv = _device_hits(kernel_runner, surface, origins, directions)
    t_ref, local = _reference_hits(surface, origins, directions)
    hits = np.isfinite(t_ref)
    assert 0.3 < hits.mean() < 0.95  # both hits and misses are tested
    # Rays grazing the rim may land either side in float; they are few.
    assert np.mean(np.isfinite(hit[:, 0]) != hits) < 0.003
    both = hits & np.isfinite(hit[:, 0])
    np.testing.assert_allclose(hit[both, 0], t_ref[both], rtol=2e-5, atol=2e-6)
    world = origins + t_ref[:, None] * directions
    np.testing.assert_allclose(p[both, :3], world[both], atol=3e-5)
    # Normals: the inverse transpose of the object-space normal, outward (the disk's: +z's image).
    n_local = {"sphere": local, "disk": np.tile([0.0, 0.0, 1.0], (len(local), 1)), "cylinder": local * [1, 1, 0]}[kind]
    n_ref = n_local @ np.linalg.inv(surface.linear)
    n_ref /= np.linalg.norm(n_ref, axis=1, keepdims=True)
    np.testing.assert_allclose(n[both, :3], n_ref[both], atol=3e-5)
    # dp/du and dp/dv are tangent, and the rebuilt point's texture coordinates are the hit's.
    assert np.abs(np.einsum("ij,ij->i", dpdu[both, :3], n[both, :3])).max() < 1e-4 * np.abs(dpdu[both]).max()
    assert np.abs(np.einsum("ij,ij->i", dpdv[both, :3], n[both, :3])).max() < 1e-4 * np.abs(dpdv[both]).max()


def test_sphere_hits_stay_precise_far_from_the_origin(kernel_runner):
    """A unit sphere 10⁴ units away: the stable quadratic and the projection back onto the sphere keep the hit on it
    (the textbook b² − c form loses about 8 of float's 24 bits there)."""
    surface = _surface("sphere", [{"translate": [0.0, 0.0, 1.0e4]}])
    rng = np.random.default_rng(2)
    targets = rng.normal(size=(500, 3)) * 0.5 + [0, 0, 1.0e4]
    origins = np.zeros((500, 3))
    directions = targets / np.linalg.norm(targets, axis=1, keepdims=True)
    hit, p, *_ = _device_hits(kernel_runner, surface, origins, directions)
    t_ref, _ = _reference_hits(surface, origins, directions)
    both = np.isfinite(t_ref) & np.isfinite(hit[:, 0])
    assert both.sum() > 300
    assert np.abs(hit[both, 0] - t_ref[both]).max() < 4e-3  # a few float ulps of 1e4 (ulp 9.8e-4)
    assert np.abs(np.linalg.norm(p[both, :3] - [0, 0, 1.0e4], axis=1) - 1.0).max() < 4e-3


@pytest.mark.peer
@pytest.mark.parametrize("kind", CASES)
def test_hits_agree_with_mitsuba(kernel_runner, mitsuba_scalar_spectral, kind):
    mi = mitsuba_scalar_spectral
    surface = _surface(kind)
    shape = mi.load_dict({"type": kind, "to_world": mi.ScalarTransform4f(surface.to_world.tolist())})
    origins, directions = _rays(surface, 300, seed=3)
    hit, p, n, dpdu, dpdv = _device_hits(kernel_runner, surface, origins, directions)
    compared = disagreed = 0
    for i in range(len(origins)):
        si = shape.ray_intersect(mi.Ray3f(origins[i].tolist(), directions[i].tolist()))
        if si.is_valid() != bool(np.isfinite(hit[i, 0])):
            disagreed += 1  # either one hits alone: only a ray grazing a rim may, within float rounding
            continue
        if not si.is_valid():
            continue
        compared += 1
        assert hit[i, 0] == pytest.approx(si.t, rel=1e-4, abs=1e-5)
        np.testing.assert_allclose(p[i, :3], np.array(si.p), atol=1e-4)
        np.testing.assert_allclose(n[i, :3], np.array(si.n), atol=1e-4)
        du = (hit[i, 1:3] - np.array(si.uv) + 0.5) % 1.0 - 0.5  # u (or the disk's v) wraps at the seam
        np.testing.assert_allclose(du, 0.0, atol=2e-5)
        scale = max(1.0, np.abs(np.array(si.dp_du)).max(), np.abs(np.array(si.dp_dv)).max())
        np.testing.assert_allclose(dpdu[i, :3], np.array(si.dp_du), atol=2e-4 * scale)
        np.testing.assert_allclose(dpdv[i, :3], np.array(si.dp_dv), atol=2e-4 * scale)
    assert compared > 100 and disagreed <= 1, (compared, disagreed)  # one ray in 300 may graze a rim
    # The area of the placed shape, as Mitsuba reports it (under a uniform scale across z, which Mitsuba needs).
    assert surface.area() == pytest.approx(shape.surface_area(), rel=1e-5)


def _cone_samples(kernel_runner, sphere, origin, u):
    runner = kernel_runner("testing/analytic_shapes.cl")
    n = len(u)
    direction, point = np.zeros((n, 4), np.float32), np.zeros((n, 4), np.float32)
    args = [
        np.asarray(sphere, np.float32),
        np.asarray([*origin, 0.0], np.float32),
        runner.buffer(u.astype(np.float32)),
        runner.buffer(direction, writable=True),
        runner.buffer(point, writable=True),
        np.int32(n),
    ]
    runner.run("sphere_cone_samples", n, args, {3: direction, 4: point})
    return direction, point


@pytest.mark.parametrize("distance", [1.5, 40.0, 5000.0])
def test_sphere_cone_sampling_is_uniform_in_the_cone(kernel_runner, distance):
    """Directions uniform over the cone the sphere fills (chi-square over cos θ and φ about its axis), with the
    pdf 1 / (2π (1 − cos θmax)), each meeting the sphere first at the point returned. 5000 radii away the cone is
    0.011° wide: the small-angle branch."""
    centre, radius = np.array([0.3, -0.2, 1.0]), 1.0
    origin = centre + distance * np.array([0.6, 0.0, 0.8])
    u = np.random.default_rng(int(distance)).uniform(size=(40000, 2))
    direction, point = _cone_samples(kernel_runner, [*centre, radius], origin, u)
    sin2_max = (radius / distance) ** 2
    one_minus_cos_max = sin2_max / (1 + np.sqrt(1 - sin2_max))
    np.testing.assert_allclose(point[:, 3], one_minus_cos_max, rtol=2e-3)
    np.testing.assert_allclose(direction[:, 3], 1 / (2 * np.pi * one_minus_cos_max), rtol=2e-3)
    # Points on the sphere, on its near side, along the sampled directions.
    q = point[:, :3].astype(np.float64)
    np.testing.assert_allclose(np.linalg.norm(q - centre, axis=1), radius, rtol=1e-5)
    assert np.all(np.einsum("ij,ij->i", q - centre, origin - q) >= -1e-4 * radius * distance)
    axis = (centre - origin) / distance
    d = direction[:, :3].astype(np.float64)
    to_point = (q - origin) / np.linalg.norm(q - origin, axis=1, keepdims=True)
    np.testing.assert_allclose(np.einsum("ij,ij->i", d, to_point), 1.0, atol=1e-6)
    # cos θ about the axis uniform on [cos θmax, 1] (as 1 − cos θ, for precision), φ uniform: 10 x 10 cells.
    tangent = np.cross(axis, [0.0, 1.0, 0.0])
    tangent /= np.linalg.norm(tangent)
    bitangent = np.cross(axis, tangent)
    one_minus_cos = np.clip(np.sum((to_point - axis) ** 2, axis=1) / 2, 0, None)  # 1 − cos θ = |d − a|² / 2
    phi = np.arctan2(to_point @ bitangent, to_point @ tangent)
    cells = np.minimum((one_minus_cos / one_minus_cos_max * 10).astype(int), 9) * 10 + np.minimum(
        ((phi + np.pi) / (2 * np.pi) * 10).astype(int), 9
    )
    counts = np.bincount(cells, minlength=100)
    assert_chi_square_fits(counts, np.full(100, len(u) / 100), significance=1e-3, what=f"distance {distance}")


def test_area_sampling_density_integrates_to_the_area(kernel_runner):
    """E[1/p] over uniform area samples is the area: for an elliptic cylinder (non-uniform scale) the host's area
    (a quadrature) and the kernel's per-point density agree."""
    surface = _surface("cylinder", [{"scale": [0.5, 1.5, 2.0]}, {"rotate": {"axis": [1, 1, 0], "angle": 30}}])
    runner = kernel_runner("testing/analytic_shapes.cl")
    u = np.random.default_rng(4).uniform(size=(20000, 2)).astype(np.float32)
    point = np.zeros((len(u), 4), np.float32)
    args = [runner.buffer(surface.device_row()[None]), runner.buffer(u), runner.buffer(point, writable=True)]
    runner.run("shape_area_samples", len(u), [*args, np.int32(len(u))], {2: point})
    inverse = 1.0 / point[:, 3].astype(np.float64)
    mean, se = inverse.mean(), inverse.std(ddof=1) / np.sqrt(len(u))
    assert abs(mean - surface.area()) < 4 * se + 1e-5 * surface.area()
    # The ellipse's perimeter (Ramanujan's second formula, exact to 1e-10 here) times the height.
    a, b = 0.5, 1.5
    h = (a - b) ** 2 / (a + b) ** 2
    perimeter = np.pi * (a + b) * (1 + 3 * h / (10 + np.sqrt(4 - 3 * h)))
    assert surface.area() == pytest.approx(perimeter * 2.0, rel=1e-7)


def test_scene_files_and_the_api_place_spheres_disks_and_cylinders(tmp_path):
    from spectrace import shape
    from spectrace.errors import SpectraceError
    from spectrace.scene.loader import load_scene

    head = "[camera]\norigin = [0, 0, 5]\ntarget = [0, 0, 0]\nfov = 40\n[film]\nwidth = 4\nheight = 4\n"
    head += '[materials.m]\ntype = "diffuse"\nreflectance = { value = 0.5 }\n'
    body = """[[shapes]]
type = "sphere"
material = "m"
center = [1, 2, 3]
radius = 0.5
transform = [{ rotate = { axis = [0, 0, 1], angle = 90 } }]
[[shapes]]
type = "disk"
material = "m"
transform = [{ scale = [2, 1, 1] }]
[[shapes]]
type = "cylinder"
material = "m"
tessellated = true
"""
    (tmp_path / "s.toml").write_text(head + body)
    sphere, disk, cylinder = load_scene(tmp_path / "s.toml").shapes
    # Rotating the sphere centred at (1, 2, 3) by 90° about z moves its centre to (-2, 1, 3).
    centre, radius = sphere.analytic.sphere_centre_radius()
    np.testing.assert_allclose(centre, [-2, 1, 3], atol=1e-12)
    assert radius == pytest.approx(0.5) and sphere.analytic.area() == pytest.approx(np.pi)
    assert disk.analytic.area() == pytest.approx(2 * np.pi)
    assert cylinder.analytic is None and len(cylinder.mesh.faces) == 128  # 64 quads around
    api = shape("sphere", "m", center=[1, 2, 3], radius=0.5, transform=[{"rotate": {"axis": [0, 0, 1], "angle": 90}}])
    np.testing.assert_allclose(api.analytic.to_world, sphere.analytic.to_world, atol=1e-12)
    for bad, message in (
        (body.replace("radius = 0.5", "radius = 0.5\ntessellated = 1"), "tessellated"),
        (body.replace('type = "disk"\n', 'type = "disk"\nradius = 2\n'), "center and radius are a sphere's"),
        (body.replace("angle = 90 } }]", "angle = 90 } }, { scale = [1, 1, 2] }]"), "scale uniformly"),
    ):
        (tmp_path / "bad.toml").write_text(head + bad)
        with pytest.raises(SpectraceError, match=message):
            load_scene(tmp_path / "bad.toml")
    with pytest.raises(SpectraceError, match="scale uniformly"):
        shape("sphere", "m", transform=[{"scale": [1, 2, 1]}])
    assert shape("sphere", "m", transform=[{"scale": [1, 2, 1]}], tessellated=True).analytic is None
