"""Partial analytic shapes (kernels/shape_partial.cl; pbrt-v4's phimax, zmin/zmax, innerradius): hits against a
float64 ray-quadric reference written here (the far root where the near one is cut away), pbrt-v4's texture
coordinates at the hits, and uniform area sampling of the partial surface (chi-square over its own parameters, its
density integrating to the closed-form area)."""

import numpy as np
import pytest

from spectrace.core.contract import ANALYTIC_SHAPE_DTYPE
from spectrace.geometry.analytic import AnalyticSurface
from spectrace.geometry.transforms import transform_matrix
from stats_toolkit import assert_chi_square_fits

STEPS = {
    "sphere": [{"scale": 0.8}, {"rotate": {"axis": [1, 2, 3], "angle": 40}}, {"translate": [0.3, -0.2, 0.5]}],
    "disk": [{"scale": [1.5, 0.6, 1.0]}, {"rotate": {"axis": [1, 0, 0], "angle": 60}}, {"translate": [0.1, 0, 0]}],
    "cylinder": [{"scale": [0.5, 0.5, 1.8]}, {"rotate": {"axis": [0, 1, 1], "angle": 70}}],
}
# (kind, φmax in degrees, sphere z range or disk inner radius)
CASES = [
    ("sphere", 250.0, (-0.4, 0.7)),
    ("sphere", 360.0, (-1.0, 0.3)),
    ("sphere", 90.0, (-1.0, 1.0)),
    ("disk", 270.0, 0.4),
    ("disk", 360.0, 0.6),
    ("disk", 120.0, 0.0),
    ("cylinder", 200.0, None),
]


def _surface(kind, phimax, cut, pbrt_uv=True) -> AnalyticSurface:
    extra: dict = {"phi_max": np.radians(phimax)}
    if kind == "sphere":
        extra["z_range"] = cut
    elif kind == "disk":
        extra["inner_radius"] = cut
    return AnalyticSurface(kind, transform_matrix(STEPS[kind], where="test"), pbrt_uv=pbrt_uv, **extra)


def _reference(surface: AnalyticSurface, origins, directions):
    """Nearest kept hit (t, object point), float64, written from the quadrics: every root in order, kept when its
    azimuth is within φmax and it lies in the cut's range."""
    inverse = np.linalg.inv(surface.to_world)
    o = origins @ inverse[:3, :3].T + inverse[:3, 3]
    d = directions @ inverse[:3, :3].T
    with np.errstate(divide="ignore", invalid="ignore"):
        if surface.kind == "disk":
            roots = [-o[:, 2] / d[:, 2]]
        else:
            xy = slice(0, 3) if surface.kind == "sphere" else slice(0, 2)
            a, b = (d[:, xy] ** 2).sum(1), (o[:, xy] * d[:, xy]).sum(1)
            root = np.sqrt(b * b - a * ((o[:, xy] ** 2).sum(1) - 1))
            roots = [(-b - root) / a, (-b + root) / a]
        t = np.full(len(o), np.inf)
        for candidate in roots[::-1]:  # the far one first, so the near one wins where both are kept
            p = o + candidate[:, None] * d
            phi = np.arctan2(p[:, 1], p[:, 0]) % (2 * np.pi)
            keep = (candidate > 0) & (phi <= surface.phi_max)
            if surface.kind == "sphere":
                keep &= (p[:, 2] >= surface.z_range[0]) & (p[:, 2] <= surface.z_range[1])
            elif surface.kind == "disk":
                r = np.hypot(p[:, 0], p[:, 1])
                keep &= (r >= surface.inner_radius) & (r <= 1)
            else:
                keep &= (p[:, 2] >= 0) & (p[:, 2] <= 1)
            t = np.where(keep, candidate, t)
    return t, o + np.where(np.isfinite(t), t, 0)[:, None] * d


def _pbrt_uv(surface: AnalyticSurface, local):
    """pbrt-v4's (u, v) (its Sphere, Disk, Cylinder::InteractionFromIntersection) at object points."""
    phi = np.arctan2(local[:, 1], local[:, 0]) % (2 * np.pi)
    u = phi / surface.phi_max
    if surface.kind == "sphere":
        theta = np.arccos(np.clip(local[:, 2], -1, 1))
        theta_lo, theta_hi = np.arccos(surface.z_range[0]), np.arccos(surface.z_range[1])
        return np.stack([u, (theta - theta_lo) / (theta_hi - theta_lo)], 1)
    if surface.kind == "disk":
        r = np.hypot(local[:, 0], local[:, 1])
        return np.stack([u, (1 - r) / (1 - surface.inner_radius)], 1)
    return np.stack([u, local[:, 2]], 1)


def _run(kernel_runner, name, rows, inputs, outputs, count):
    runner = kernel_runner("testing/analytic_shapes.cl")
    args = [runner.buffer(rows), *(runner.buffer(a) for a in inputs)]
    args += [runner.buffer(o, writable=True) for o in outputs] + [np.int32(count)]
    runner.run(name, count, args, {1 + len(inputs) + k: o for k, o in enumerate(outputs)})
    return outputs


@pytest.mark.parametrize(("kind", "phimax", "cut"), CASES)
def test_partial_hits_agree_with_a_float64_ray_quadric_reference(kernel_runner, kind, phimax, cut):
    surface = _surface(kind, phimax, cut)
    rng = np.random.default_rng(7)
    n = 3000
    centre = surface.to_world[:3, 3]
    origins = centre + rng.normal(size=(n, 3)) * 3.0
    targets = centre + rng.uniform(-1, 1, size=(n, 3))
    directions = targets - origins
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    pad = np.zeros((n, 1), np.float32)
    rows = np.repeat(surface.device_row()[None], n).astype(ANALYTIC_SHAPE_DTYPE)
    inputs = [np.hstack([origins, pad]).astype(np.float32), np.hstack([directions, pad]).astype(np.float32)]
    hit, p, normal, dpdu, dpdv = _run(
        kernel_runner, "shape_hits", rows, inputs, [np.zeros((n, 4), np.float32) for _ in range(5)], n
    )
    t_ref, local = _reference(surface, origins, directions)
    hits = np.isfinite(t_ref)
    assert 0.05 < hits.mean() < 0.9
    inverse = np.linalg.inv(surface.to_world)
    o = origins @ inverse[:3, :3].T + inverse[:3, 3]
    # Rays grazing a rim or a cut edge may land either side in float; they are few.
    assert np.mean(np.isfinite(hit[:, 0]) != hits) < 0.004
    with np.errstate(invalid="ignore"):
        both = hits & np.isfinite(hit[:, 0]) & (np.abs(hit[:, 0] - t_ref) < 1e-3)
    assert both.sum() > 0.99 * (hits & np.isfinite(hit[:, 0])).sum()  # the same root, near or far
    np.testing.assert_allclose(p[both, :3], origins[both] + t_ref[both, None] * directions[both], atol=3e-5)
    uv = _pbrt_uv(surface, local)
    np.testing.assert_allclose(hit[both, 1:3], uv[both], atol=2e-4)
    n_local = {"sphere": local, "disk": np.tile([0.0, 0.0, 1.0], (n, 1)), "cylinder": local * [1, 1, 0]}[kind]
    n_ref = n_local @ np.linalg.inv(surface.linear)
    n_ref /= np.linalg.norm(n_ref, axis=1, keepdims=True)
    np.testing.assert_allclose(normal[both, :3], n_ref[both], atol=3e-5)
    # dp/du and dp/dv as pbrt-v4 defines them, by finite differences of the reference's parametrisation.
    for k, tangent in ((0, dpdu), (1, dpdv)):
        step = np.zeros(2)
        step[k] = 1e-4
        ahead = _point_at_uv(surface, uv[both] + step)
        behind = _point_at_uv(surface, uv[both] - step)
        np.testing.assert_allclose(tangent[both, :3], (ahead - behind) / 2e-4, atol=2e-3 * np.abs(ahead).max())
    if kind != "disk":  # rays from outside that meet the inside through a cut-out (the far root) are among them
        d = directions @ inverse[:3, :3].T
        outside = np.linalg.norm(o[:, :3] if kind == "sphere" else o[:, :2], axis=1) > 1
        assert (both & outside & (np.einsum("ij,ij->i", d, n_local) > 0)).sum() > 20


def _point_at_uv(surface: AnalyticSurface, uv):
    """The world point at pbrt-v4's (u, v), float64."""
    phi = uv[:, 0] * surface.phi_max
    if surface.kind == "sphere":
        theta_lo, theta_hi = np.arccos(surface.z_range[0]), np.arccos(surface.z_range[1])
        theta = theta_lo + uv[:, 1] * (theta_hi - theta_lo)
        local = np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)], 1)
    elif surface.kind == "disk":
        r = 1 - uv[:, 1] * (1 - surface.inner_radius)
        local = np.stack([r * np.cos(phi), r * np.sin(phi), np.zeros_like(r)], 1)
    else:
        local = np.stack([np.cos(phi), np.sin(phi), uv[:, 1]], 1)
    return local @ surface.to_world[:3, :3].T + surface.to_world[:3, 3]


@pytest.mark.parametrize(("kind", "phimax", "cut"), CASES)
@pytest.mark.parametrize("pbrt_uv", [True, False])
def test_partial_area_sampling_is_uniform_over_the_partial_surface(kernel_runner, kind, phimax, cut, pbrt_uv):
    """Points uniform over the kept surface: (φ/φmax, the area fraction below them) uniform on a 8 x 8 grid
    (chi-square), every point kept, and E[1/p] the closed-form area."""
    surface = _surface(kind, phimax, cut, pbrt_uv)
    count = 40000
    u = np.random.default_rng(11).uniform(size=(count, 2)).astype(np.float32)
    (point,) = _run(
        kernel_runner, "shape_area_samples", surface.device_row()[None], [u], [np.zeros((count, 4), np.float32)], count
    )
    inverse = np.linalg.inv(surface.to_world)
    local = point[:, :3].astype(np.float64) @ inverse[:3, :3].T + inverse[:3, 3]
    phi = np.arctan2(local[:, 1], local[:, 0]) % (2 * np.pi)
    phi = np.where(phi > surface.phi_max + 1e-4, phi - 2 * np.pi, phi)  # φ = 0 may round just below 0
    assert np.all(phi >= -1e-4) and np.all(phi <= surface.phi_max + 1e-4)
    if kind == "sphere":  # Archimedes: the area below height z is proportional to z − zmin
        lo, hi = surface.z_range
        fraction = (local[:, 2] - lo) / (hi - lo)
    elif kind == "disk":
        r2, inner2 = (local[:, :2] ** 2).sum(1), surface.inner_radius**2
        fraction = (r2 - inner2) / (1 - inner2)
    else:
        fraction = local[:, 2]
    assert np.all((fraction > -1e-4) & (fraction < 1 + 1e-4))
    cells = np.clip((phi / surface.phi_max * 8).astype(int), 0, 7) * 8 + np.clip((fraction * 8).astype(int), 0, 7)
    assert_chi_square_fits(np.bincount(cells, minlength=64), np.full(64, count / 64), significance=1e-3, what=kind)
    scale = {"sphere": 0.8**2, "disk": 1.5 * 0.6, "cylinder": None}[kind]
    closed_form = {
        "sphere": np.radians(phimax) * (surface.z_range[1] - surface.z_range[0]),
        "disk": np.radians(phimax) / 2 * (1 - surface.inner_radius**2),
        "cylinder": np.radians(phimax) * 1.8 * 0.5,
    }[kind] * (scale or 1.0)
    assert surface.area() == pytest.approx(closed_form, rel=1e-6)
    inverse_pdf = 1.0 / point[:, 3].astype(np.float64)
    np.testing.assert_allclose(inverse_pdf, closed_form, rtol=1e-4)  # uniform: the density is 1/area everywhere


def test_scene_keys_and_the_api_cut_shapes_alike(tmp_path):
    """phi_max, z_min/z_max (heights within ±radius) and inner_radius in a scene file and in the API give the same
    partial surface; its tessellation (tessellated = true) covers the same area; keys that do not fit are refused
    naming them, and so is an interior in a partial sphere (it encloses no volume)."""
    from spectrace import shape
    from spectrace.errors import SpectraceError
    from spectrace.scene.loader import load_scene

    head = "[camera]\norigin = [0, 0, 5]\ntarget = [0, 0, 0]\nfov = 40\n[film]\nwidth = 4\nheight = 4\n"
    head += '[materials.m]\ntype = "diffuse"\nreflectance = { value = 0.5 }\n'
    body = """[[shapes]]
type = "sphere"
material = "m"
radius = 2
z_min = -1
z_max = 1.5
phi_max = 90
[[shapes]]
type = "disk"
material = "m"
inner_radius = 0.5
phi_max = 180
[[shapes]]
type = "cylinder"
material = "m"
phi_max = 45
tessellated = true
"""
    (tmp_path / "s.toml").write_text(head + body)
    sphere, disk, cylinder = load_scene(tmp_path / "s.toml").shapes
    assert sphere.analytic.z_range == (-0.5, 0.75) and sphere.analytic.phi_max == pytest.approx(np.pi / 2)
    assert sphere.analytic.area() == pytest.approx(np.pi / 2 * 2 * 2.5)  # φmax r (zmax − zmin)
    assert disk.analytic.area() == pytest.approx(np.pi / 2 * (1 - 0.25))
    assert cylinder.analytic is None
    assert cylinder.mesh.area() == pytest.approx(np.pi / 4, rel=1e-3)  # a chord polygon of 8 sectors
    api = shape("sphere", "m", radius=2, z_min=-1, z_max=1.5, phi_max=90)
    assert api.analytic.z_range == sphere.analytic.z_range and api.analytic.phi_max == sphere.analytic.phi_max
    for bad, message in (
        (body.replace("phi_max = 90", "phi_max = 400"), "phi_max must be in"),
        (body.replace("inner_radius = 0.5", "inner_radius = 1"), "inner_radius must be in"),
        (body.replace("z_max = 1.5", "z_max = 2.5"), "z_min < z_max"),
        (body.replace("phi_max = 180", "phi_max = 180\nz_min = 0"), "z_min and z_max cut a sphere"),
        (body.replace("phi_max = 90", "phi_max = 90\ninterior = { sigma_a = { value = 1 } }"), "encloses no volume"),
    ):
        (tmp_path / "bad.toml").write_text(head + bad)
        with pytest.raises(SpectraceError, match=message):
            load_scene(tmp_path / "bad.toml")
    with pytest.raises(SpectraceError, match="inner_radius is a disk's") as raised:
        shape("sphere", "m", inner_radius=0.2)
    assert raised.value.where == "inner_radius"


def test_a_python_scene_with_partial_shapes_is_saved_with_its_cuts(tmp_path):
    """save_scene writes the cuts in the shape's object space (its transform carries the radius): the loaded
    surfaces keep them, and with them their areas."""
    import spectrace
    from spectrace.scene.loader import load_scene

    material = spectrace.diffuse(0.5)
    shapes = [
        spectrace.shape("sphere", material, radius=2, z_min=-1, z_max=1.5, phi_max=90),
        spectrace.shape("disk", material, inner_radius=0.5, phi_max=180, transform=[{"scale": [2, 1, 1]}]),
        spectrace.shape("cylinder", material, phi_max=45, flip_normals=True),
    ]
    camera = spectrace.Camera(origin=(0, 0, 5), target=(0, 0, 0))
    scene = spectrace.Scene(camera=camera, width=4, height=4, shapes=shapes)
    spectrace.save_scene(scene, tmp_path / "saved.toml")
    loaded = load_scene(tmp_path / "saved.toml").shapes
    for before, after in zip(shapes, loaded, strict=True):
        assert after.analytic.cut_keys() == pytest.approx(before.analytic.cut_keys())
        assert after.analytic.area() == pytest.approx(before.analytic.area(), rel=1e-9)
        assert after.analytic.flip_normals == before.analytic.flip_normals


@pytest.mark.peer
def test_the_mitsuba_export_writes_a_partial_shape_as_its_tessellation(tmp_path, mitsuba_scalar_spectral):
    """Mitsuba 3 has no partial shapes: the export writes the cut shape's triangles (their area the partial
    surface's, to the tessellation's chord error), a whole one stays Mitsuba's own disk."""
    import spectrace
    from spectrace.interop.mitsuba.export import scene_to_mitsuba_dict

    material = spectrace.diffuse(0.5)
    cut = spectrace.shape("disk", material, inner_radius=0.5, phi_max=180, transform=[{"scale": [2, 1, 1]}])
    whole = spectrace.shape("disk", material)
    camera = spectrace.Camera(origin=(0, 0, 5), target=(0, 0, 0))
    scene = spectrace.Scene(camera=camera, width=4, height=4, shapes=[cut, whole])
    exported = scene_to_mitsuba_dict(scene, tmp_path)
    shapes = [entry for entry in exported.values() if isinstance(entry, dict) and entry.get("type") in ("ply", "disk")]
    assert sorted(entry["type"] for entry in shapes) == ["disk", "ply"]
    assert cut.mesh.area() == pytest.approx(cut.analytic.area(), rel=2e-3)
    mitsuba_scalar_spectral.load_dict(exported)  # Mitsuba reads what was written
