"""The linear curve segment (kernels/curve.cl, through kernels/testing/curve_hits.cl): the sphere of radius
ra → rb swept from a to b, met by rays, against a numpy reference that knows nothing of its cone: the surface is
where min over the centre's parameter s of |p − c(s)| − r(s) is 0, found along each ray by stepping and bisection
in float64. Hits and misses agree (away from grazing rays), distances to 1e-4 of the segment's size, the normal is
the reference's gradient, u the parameter of the nearest centre, and h the ray's signed offset from the axis over
the radius where the segment is a cylinder."""

import numpy as np
import pytest

HARNESS = "testing/curve_hits.cl"
CENTRES = np.linspace(0.0, 1.0, 4001)
COARSE = CENTRES[::10]


def _field(
    points: np.ndarray, a: np.ndarray, ra: float, b: np.ndarray, rb: float, centres: np.ndarray = CENTRES
) -> tuple[np.ndarray, np.ndarray]:
    """min_s |p − c(s)| − r(s) and the s that attains it, for points (n, 3), over the centre parameters given."""
    s = centres
    centres = a + s[:, None] * (b - a)
    radii = ra + s * (rb - ra)
    distance = np.linalg.norm(points[:, None, :] - centres[None], axis=2) - radii[None]
    best = distance.argmin(axis=1)
    return distance[np.arange(len(points)), best], s[best]


def _reference_hits(origins, directions, a, ra, b, rb, t_far: float, steps: int = 800):
    """First t where the field turns negative along each ray (inf where it never does), by steps (over coarse
    centres) then bisection (over fine ones)."""
    ts = np.linspace(0.0, t_far, steps)
    result = np.full(len(origins), np.inf)
    for i, (o, d) in enumerate(zip(origins, directions, strict=True)):
        values, _ = _field(o + ts[:, None] * d, a, ra, b, rb, COARSE)
        inside = np.nonzero(values < 0.0)[0]
        if len(inside) == 0:
            continue
        lo, hi = ts[inside[0] - 1], ts[inside[0]]
        for _ in range(40):
            mid = 0.5 * (lo + hi)
            if _field((o + mid * d)[None], a, ra, b, rb)[0][0] < 0.0:
                hi = mid
            else:
                lo = mid
        result[i] = 0.5 * (lo + hi)
    return result


def _device_hits(kernel_runner, origins, directions, a, ra, b, rb):
    runner = kernel_runner(HARNESS)
    n = len(origins)
    o4, d4 = np.zeros((n, 4), np.float32), np.zeros((n, 4), np.float32)
    o4[:, :3], d4[:, :3] = origins, directions
    result, normal = np.zeros((n, 4), np.float32), np.zeros((n, 4), np.float32)
    args = [
        runner.buffer(o4),
        runner.buffer(d4),
        np.array([*a, ra], np.float32),
        np.array([*b, rb], np.float32),
        runner.buffer(result, True),
        runner.buffer(normal, True),
    ]
    runner.run("curve_segment_hits", n, args, {4: result, 5: normal})
    return result.astype(np.float64), normal[:, :3].astype(np.float64)


def _rays_at(rng, a, b, reach: float, n: int):
    """Rays from a sphere of radius 3·reach about the segment's middle, aimed at random points near it."""
    middle = 0.5 * (a + b)
    start = rng.normal(size=(n, 3))
    start = middle + 3.0 * reach * start / np.linalg.norm(start, axis=1, keepdims=True)
    target = middle + (rng.random((n, 1)) - 0.5) * (b - a) * 1.3 + rng.normal(size=(n, 3)) * 0.6 * reach * 0.5
    d = target - start
    return start, d / np.linalg.norm(d, axis=1, keepdims=True)


@pytest.mark.slow
@pytest.mark.parametrize(
    "a, ra, b, rb",
    (
        ((0.0, 0.0, 0.0), 0.2, (0.0, 1.0, 0.0), 0.2),  # a capsule
        ((0.1, -0.3, 0.2), 0.3, (0.8, 0.7, -0.4), 0.1),  # tapering
        ((0.0, 0.0, 0.0), 0.05, (0.3, 0.2, 1.0), 0.25),  # widening
    ),
)
def test_segment_hits_match_the_swept_sphere(kernel_runner, a, ra, b, rb):
    a, b = np.array(a), np.array(b)
    reach = np.linalg.norm(b - a) + max(ra, rb)
    origins, directions = _rays_at(np.random.default_rng(3), a, b, reach, 200)
    ours, normals = _device_hits(kernel_runner, origins, directions, a, ra, b, rb)
    reference = _reference_hits(origins, directions, a, ra, b, rb, t_far=6.0 * reach)
    hit = ours[:, 3] > 0
    # Grazing rays (the reference's field barely dips below 0 along them) may go either way.
    points = origins + np.where(np.isfinite(reference), reference, 0.0)[:, None] * directions
    grazing = np.zeros(len(origins), bool)
    for i in np.nonzero(hit != np.isfinite(reference))[0]:
        t = ours[i, 0] if hit[i] else reference[i]
        probe = origins[i] + np.linspace(t - 0.02 * reach, t + 0.02 * reach, 201)[:, None] * directions[i]
        grazing[i] = _field(probe, a, ra, b, rb)[0].min() > -2e-3 * reach
    assert np.all((hit == np.isfinite(reference)) | grazing)
    assert hit.sum() > 30 and (~hit).sum() > 20
    both = hit & np.isfinite(reference)
    np.testing.assert_allclose(ours[both, 0], reference[both], atol=1e-4 * reach)
    # The normal is the field's gradient (finite differences of the reference), u its nearest centre.
    e = 1e-4 * reach
    for i in np.nonzero(both)[0][:60]:
        p = points[i]
        gradient = np.array(
            [
                _field((p + e * axis)[None], a, ra, b, rb)[0][0] - _field((p - e * axis)[None], a, ra, b, rb)[0][0]
                for axis in np.eye(3)
            ]
        )
        np.testing.assert_allclose(normals[i], gradient / np.linalg.norm(gradient), atol=3e-3)
        np.testing.assert_allclose(ours[i, 1], _field(p[None], a, ra, b, rb)[1][0], atol=2e-3)


def test_h_is_the_rays_offset_from_a_cylinders_axis(kernel_runner):
    """On an equal-radius segment along y, rays parallel to −z at x offsets: |h| = offset / r, the sign fixed by the
    side (Mitsuba 3's convention: h = −ωo·(n × w) / |ωo's part normal to w|), the same for any height and for rays
    tilted along the fibre."""
    a, b, r = np.array([0.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0]), 0.25
    offsets = np.linspace(-0.95, 0.95, 39) * r
    tilt = np.array([0.0, -0.4, -1.0]) / np.linalg.norm([0.0, -0.4, -1.0])
    crossings = np.stack([offsets, np.full_like(offsets, 0.5), np.zeros_like(offsets)], axis=1)
    for direction in (np.array([0.0, 0.0, -1.0]), tilt):
        start = crossings - 3.0 * direction  # each ray passes (offset, 0.5, 0), beside the axis
        ours, _ = _device_hits(kernel_runner, start, np.broadcast_to(direction, start.shape), a, r, b, r)
        assert np.all(ours[:, 3] > 0)
        np.testing.assert_allclose(ours[:, 2], -offsets / r, atol=2e-5)
