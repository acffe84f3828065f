"""Signed-distance grids (Mitsuba 3's sdfgrid; kernels/shape_sdf_grid.cl): the kernels' hits against a float64 root
find of the same trilinear interpolant (dense sign scan along each ray, then bisection), against the analytic
sphere whose exact distance the grid samples (hit points within the interpolation error bound), and the point and
normals a path sees there, placed directly and through an instance."""

import numpy as np
import pytest
from tests.geometry.test_instances import _trace

import spectrace
from spectrace.geometry.transforms import transform_matrix

PLACEMENT = [{"scale": [1.4, 0.9, 1.1]}, {"rotate": {"axis": [0, 1, 1], "angle": 30}}, {"translate": [0.1, 0.2, 0.0]}]
CAMERA = spectrace.Camera(origin=(0.0, 0.5, -4.0), target=(0.0, 0.0, 0.0))


def sphere_samples(n: int, centre=(0.5, 0.5, 0.5), radius: float = 0.3) -> np.ndarray:
    """The exact signed distance to a sphere at the corners of an n³ grid over the unit cube, (nz, ny, nx)."""
    x = np.linspace(0.0, 1.0, n)
    z, y, x = np.meshgrid(x, x, x, indexing="ij")
    return np.sqrt((x - centre[0]) ** 2 + (y - centre[1]) ** 2 + (z - centre[2]) ** 2) - radius


def wavy_samples(shape=(9, 11, 13)) -> np.ndarray:
    """A smooth field with a curved zero set that crosses voxels in every way (saddles, several roots a voxel)."""
    nz, ny, nx = shape
    z, y, x = np.meshgrid(np.linspace(0, 1, nz), np.linspace(0, 1, ny), np.linspace(0, 1, nx), indexing="ij")
    return 0.35 - np.hypot(x - 0.5, y - 0.5) + 0.12 * np.sin(9.0 * z + 4.0 * x) * np.cos(7.0 * y)


def trilinear(values: np.ndarray, p: np.ndarray) -> np.ndarray:
    """The grid's interpolant (samples at voxel corners over the unit cube) at object-space points p (..., 3), in
    float64."""
    nz, ny, nx = values.shape
    cells = np.array([nx - 1, ny - 1, nz - 1], float)
    q = np.clip(p, 0.0, 1.0) * cells
    i = np.clip(np.floor(q).astype(int), 0, cells.astype(int) - 1)
    w = q - i
    v = values.astype(np.float64)
    out = 0.0
    for cz in (0, 1):
        for cy in (0, 1):
            for cx in (0, 1):
                weight = (w[..., 0] if cx else 1 - w[..., 0]) * (w[..., 1] if cy else 1 - w[..., 1])
                weight = weight * (w[..., 2] if cz else 1 - w[..., 2])
                out = out + weight * v[i[..., 2] + cz, i[..., 1] + cy, i[..., 0] + cx]
    return out


def occupied_at(values: np.ndarray, p: np.ndarray) -> np.ndarray:
    """Whether the voxel holding each point has corner samples of both signs (where Mitsuba's surface exists)."""
    nz, ny, nx = values.shape
    cells = np.array([nx - 1, ny - 1, nz - 1])
    i = np.clip(np.floor(np.clip(p, 0, 1) * cells).astype(int), 0, cells - 1)
    corners = np.stack(
        [values[i[..., 2] + cz, i[..., 1] + cy, i[..., 0] + cx] for cz in (0, 1) for cy in (0, 1) for cx in (0, 1)]
    )
    return (corners >= 0).any(axis=0) & (corners <= 0).any(axis=0)


def reference_hits(values, matrix, origins, directions, steps=4000):
    """First zero of the interpolant along each world ray (t in world units, inf on a miss): a dense scan for the
    first sign change inside the unit cube, then 60 bisections. Also the root's |df/dt| (object-space field along
    the world ray), small where a ray grazes the surface."""
    inverse = np.linalg.inv(matrix)
    o = origins @ inverse[:3, :3].T + inverse[:3, 3]
    d = directions @ inverse[:3, :3].T
    with np.errstate(divide="ignore", invalid="ignore"):
        ta, tb = (0.0 - o) / d, (1.0 - o) / d
    lo = np.nanmax(np.where(np.isnan(np.minimum(ta, tb)), -np.inf, np.minimum(ta, tb)), axis=1).clip(0.0)
    hi = np.nanmin(np.where(np.isnan(np.maximum(ta, tb)), np.inf, np.maximum(ta, tb)), axis=1)
    t_hit, slope = np.full(len(o), np.inf), np.zeros(len(o))
    for r in np.nonzero(lo < hi)[0]:
        ts = np.linspace(lo[r], hi[r], steps)
        points = o[r] + ts[:, None] * d[r]
        f = trilinear(values, points)
        change = np.nonzero((np.sign(f[:-1]) != np.sign(f[1:])) | (f[1:] == 0))[0]
        change = [k for k in change if occupied_at(values, points[k : k + 2]).any()]
        if not change:
            continue
        a, b = ts[change[0]], ts[change[0] + 1]
        fa = trilinear(values, o[r] + a * d[r])
        for _ in range(60):
            m = 0.5 * (a + b)
            fm = trilinear(values, o[r] + m * d[r])
            if np.sign(fm) == np.sign(fa) and fm != 0:
                a, fa = m, fm
            else:
                b = m
        t_hit[r] = 0.5 * (a + b)
        eps = 1e-6 * (hi[r] - lo[r])
        slope[r] = abs(
            trilinear(values, o[r] + (t_hit[r] + eps) * d[r]) - trilinear(values, o[r] + (t_hit[r] - eps) * d[r])
        ) / (2 * eps)
    return t_hit, slope


def _rays(count, seed, centre=(0.0, 0.0, 0.0), spread=0.8):
    rng = np.random.default_rng(seed)
    origins = rng.normal(size=(count, 3))
    origins = 3.0 * origins / np.linalg.norm(origins, axis=1, keepdims=True)
    targets = np.asarray(centre) + rng.uniform(-spread, spread, (count, 3))
    directions = targets - origins
    return origins, directions / np.linalg.norm(directions, axis=1, keepdims=True)


def _scene(shapes=(), instances=()):
    return spectrace.Scene(camera=CAMERA, width=8, height=8, spp=1, shapes=list(shapes), instances=list(instances))


@pytest.mark.parametrize("instanced", [False, True], ids=["placed", "instanced"])
@pytest.mark.slow
def test_hits_are_the_interpolants_first_zero(kernel_runner, instanced):
    values = wavy_samples()
    steps = [{"translate": [-0.5, -0.5, -0.5]}, *PLACEMENT]
    matrix = transform_matrix(steps, "t")
    material = spectrace.diffuse(0.5)
    if instanced:  # half the map in the object, half in the instance
        grid = spectrace.sdf_grid(values, material, transform=steps[:2])
        obj = spectrace.instanced_object([grid])
        scene = _scene(instances=[spectrace.instance(obj, transform=steps[2:])])
    else:
        scene = _scene([spectrace.sdf_grid(values, material, transform=steps)])
    origins, directions = _rays(300, 5)
    t_ref, slope = reference_hits(values, matrix, origins, directions)
    _, (hit, point, normal, shading, occluded) = _trace(kernel_runner, scene, origins, directions, np.full(300, 100.0))
    t = hit[:, 0].astype(np.float64)
    clear = slope > 0.05  # grazing rays (a double root) may be met or missed by either
    # Shadow rays (the any-hit query): blocked up to 100, not up to just short of the first zero.
    np.testing.assert_array_equal(occluded[clear].astype(bool), np.isfinite(t_ref[clear]))
    short = np.where(np.isfinite(t_ref), t_ref * 0.999, 100.0)
    occluded_short = _trace(kernel_runner, scene, origins, directions, short)[1][4]
    assert not occluded_short[clear].any()
    assert np.isfinite(t_ref[clear]).sum() > 100
    np.testing.assert_array_equal(np.isfinite(t[clear]), np.isfinite(t_ref[clear]))
    both = clear & np.isfinite(t_ref)
    np.testing.assert_allclose(t[both], t_ref[both], atol=2e-5 * 3.0)
    np.testing.assert_allclose(point[both, :3], origins[both] + t_ref[both, None] * directions[both], atol=1e-4)
    # The geometric normal: the interpolant's gradient taken to world space by M⁻ᵀ (one-sided differences inside the
    # voxel, away from its faces, where the gradient jumps).
    inverse = np.linalg.inv(matrix)
    p_object = point[both, :3] @ inverse[:3, :3].T + inverse[:3, 3]
    cells = np.array(values.shape[::-1], float) - 1.0
    inner = np.all(np.abs(p_object * cells - np.rint(p_object * cells)) > 1e-3, axis=1)
    h = 1e-4 / cells
    step = np.where((p_object * cells) % 1.0 < 0.5, h, -h)
    gradient = np.stack(
        [
            (trilinear(values, p_object + step * e) - trilinear(values, p_object)) / step[:, k]
            for k, e in enumerate(np.eye(3))
        ],
        -1,
    )
    expected = gradient @ inverse[:3, :3]
    expected /= np.linalg.norm(expected, axis=1, keepdims=True)
    assert inner.sum() > 80
    assert np.min(np.einsum("ij,ij->i", normal[both, :3][inner], expected[inner])) > 0.9999


def test_sphere_grid_hits_the_sphere_within_the_interpolation_bound(kernel_runner):
    """Samples of the exact distance to a sphere (radius r, voxel size h): the trilinear interpolant differs from the
    distance by at most (h²/8) Σ|∂²f/∂xᵢ²| ≤ 3h²/(8 ρ) where ρ ≥ r − √3 h bounds the distance to the centre within a
    voxel the surface crosses; |∇f| = 1, so each hit point lies that close to the sphere."""
    n, radius = 33, 0.3
    h = 1.0 / (n - 1)
    scene = _scene([spectrace.sdf_grid(sphere_samples(n, radius=radius), spectrace.diffuse(0.5))])
    origins, directions = _rays(400, 9, centre=(0.5, 0.5, 0.5), spread=0.35)
    _, (hit, point, normal, shading, _) = _trace(kernel_runner, scene, origins, directions, np.full(400, 100.0))
    centre = np.array([0.5, 0.5, 0.5])
    # Rays that meet the sphere clearly (miss distance below r − h) hit the grid; rays that pass clearly outside miss.
    closest = np.linalg.norm(np.cross(centre - origins, directions), axis=1)
    met = np.isfinite(hit[:, 0])
    assert met[closest < radius - 2 * h].all() and not met[closest > radius + 2 * h].any()
    bound = 3 * h * h / (8 * (radius - np.sqrt(3) * h)) + 1e-5
    distance = np.linalg.norm(point[met, :3] - centre, axis=1)
    assert np.max(np.abs(distance - radius)) <= bound
    # Each partial derivative of the interpolant is a blend of difference quotients over one voxel, within h·max|∂²f|
    # ≤ h/ρ of the true one; the smooth shading normal blends gradients of voxels up to two away.
    radial = (point[met, :3] - centre) / distance[:, None]
    slip = np.sqrt(3) * h / (radius - np.sqrt(3) * h)
    assert np.min(np.einsum("ij,ij->i", normal[met, :3], radial)) > np.cos(np.arcsin(slip))
    assert np.min(np.einsum("ij,ij->i", shading[met, :3], radial)) > np.cos(np.arcsin(2 * slip))
    assert (hit[met, 1:3] == 0.0).all()  # no texture coordinates


def _mitsuba_hits(values, matrix, normals, origins, directions):
    """Mitsuba 3's own intersection of the same grid (scalar variant): t (inf on a miss), n, shading n."""
    mi = pytest.importorskip("mitsuba")
    mi.set_variant("scalar_rgb")
    grid = mi.TensorXf(np.ascontiguousarray(values, np.float32)[..., None])
    scene = mi.load_dict(
        {
            "type": "scene",
            "grid": {"type": "sdfgrid", "grid": grid, "normals": normals, "to_world": mi.ScalarTransform4f(matrix)},
        }
    )
    t = np.full(len(origins), np.inf)
    n, ns = np.zeros((len(origins), 3)), np.zeros((len(origins), 3))
    for r, (o, d) in enumerate(zip(origins, directions, strict=True)):
        si = scene.ray_intersect(mi.Ray3f(mi.Point3f(*o), mi.Vector3f(*d)))
        if si.is_valid():
            t[r], n[r], ns[r] = si.t, np.array(si.n), np.array(si.sh_frame.n)
    return t, n, ns


@pytest.mark.peer
@pytest.mark.parametrize("normals", ["smooth", "analytic"])
def test_hits_and_normals_agree_with_mitsuba(kernel_runner, normals):
    """The same grid and rays in Mitsuba 3: distances, geometric normals and both kinds of shading normal (which
    shows the samples sit at voxel corners and the smooth normal blends as Mitsuba's does). A cubic grid: Mitsuba
    3.9's sdfgrid misses most of a grid whose resolutions differ along the axes (a sphere sampled on 17 × 9 × 9
    corners is not hit at all), which the float64 reference above holds spectrace to."""
    values = wavy_samples((10, 10, 10))
    matrix = transform_matrix([{"translate": [-0.5, -0.5, -0.5]}, {"scale": [1.3, 1.0, 1.1]}], "t")
    scene = _scene(
        [spectrace.sdf_grid(values, spectrace.diffuse(0.5), transform=[{"matrix": matrix.tolist()}], normals=normals)]
    )
    origins, directions = _rays(200, 21)
    t_ref, slope = reference_hits(values, matrix, origins, directions)
    t_mi, n_mi, ns_mi = _mitsuba_hits(values, matrix, normals, origins, directions)
    _, (hit, _, normal, shading, _) = _trace(kernel_runner, scene, origins, directions, np.full(200, 100.0))
    clear = slope > 0.05
    both = clear & np.isfinite(t_mi)
    assert both.sum() > 60
    np.testing.assert_array_equal(np.isfinite(hit[clear, 0]), np.isfinite(t_mi[clear]))
    np.testing.assert_allclose(hit[both, 0], t_mi[both], atol=1e-5)
    assert np.min(np.einsum("ij,ij->i", normal[both, :3], n_mi[both])) > 0.99999
    assert np.min(np.einsum("ij,ij->i", shading[both, :3], ns_mi[both])) > 0.99999
