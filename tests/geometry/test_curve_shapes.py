"""Curve shapes in the BVH (geometry/curves.py, kernels/shape_curve.cl): many linear swept-sphere segments, each a
primitive of the analytic shapes' BVH, must be met as a brute-force test of every segment meets them (the single
segment's intersector, kernels/curve.cl, checked against a float64 reference in test_curve_segment.py), in the
closest-hit and the any-hit query; and a long curve lit by a distant light must show a diffuse cylinder's radiance
in closed form, ρ/π E max(0, n·l), pixel by pixel."""

import numpy as np
import pytest

import spectrace
from spectrace.core.contract import SCENE_KERNEL_BUFFERS
from spectrace.engine.renderer import upload_scene
from spectrace.engine.scene_buffers import build_scene_buffers, render_params


def _random_curves(rng, count: int) -> list[np.ndarray]:
    """Polylines of 2..6 points wandering in [-1, 1]³, radii 0.02..0.12."""
    curves = []
    for _ in range(count):
        n = int(rng.integers(2, 7))
        start = rng.uniform(-1, 1, 3)
        steps = rng.normal(scale=0.25, size=(n - 1, 3))
        points = np.concatenate([[start], start + np.cumsum(steps, axis=0)])
        curves.append(np.concatenate([points, rng.uniform(0.02, 0.12, (n, 1))], axis=1))
    return curves


def _scene(shapes, **kwargs) -> spectrace.Scene:
    return spectrace.Scene(
        camera=spectrace.Camera(origin=(0.0, 0.0, -5.0), target=(0.0, 0.0, 0.0)),
        width=8,
        height=8,
        spp=1,
        shapes=shapes,
        **kwargs,
    )


def _scene_hits(kernel_runner, scene, origins, directions, t_max):
    """(t, u, v, material), point, normal and occlusion before t_max of each ray (kernels/testing/scene_hits.cl)."""
    buffers = build_scene_buffers(scene)
    runner = kernel_runner("testing/scene_hits.cl")
    n = len(origins)
    scene_args = upload_scene(runner.device.context, buffers)
    assert len(scene_args) == len(SCENE_KERNEL_BUFFERS)
    out = [np.zeros((n, 4), np.float32) for _ in range(4)] + [np.zeros(n, np.int32)]
    four = lambda a: np.concatenate([a, np.zeros((n, 1))], axis=1).astype(np.float32)  # noqa: E731
    args = [
        runner.buffer(render_params(scene, buffers, 0, 1)),
        *scene_args,
        runner.buffer(four(origins)),
        runner.buffer(four(directions)),
        runner.buffer(t_max.astype(np.float32)),
    ]
    first = len(args)
    args += [runner.buffer(o, True) for o in out] + [np.int32(n)]
    runner.run("scene_hits", n, args, {first + k: o for k, o in enumerate(out)})
    return out


def _segment_hits(kernel_runner, surface, origins, directions):
    """Each ray against every segment alone (kernels/testing/curve_hits.cl), by brute force: (segments, rays) arrays
    of the front-facing hits' t (inf: none) and normals."""
    runner = kernel_runner("testing/curve_hits.cl")
    n = len(origins)
    o4, d4 = np.zeros((n, 4), np.float32), np.zeros((n, 4), np.float32)
    o4[:, :3], d4[:, :3] = origins, directions
    ts, normals = np.full((surface.count, n), np.inf), np.zeros((surface.count, n, 3))
    for k in range(surface.count):
        result, normal = np.zeros((n, 4), np.float32), np.zeros((n, 4), np.float32)
        args = [
            runner.buffer(o4),
            runner.buffer(d4),
            np.array([*surface.a[k], surface.ra[k]], np.float32),
            np.array([*surface.b[k], surface.rb[k]], np.float32),
            runner.buffer(result, True),
            runner.buffer(normal, True),
        ]
        runner.run("curve_segment_hits", n, args, {4: result, 5: normal})
        front = (result[:, 3] > 0) & (np.einsum("ij,ij->i", normal[:, :3], directions) < 0)
        ts[k, front], normals[k] = result[front, 0], normal[:, :3]
    return ts, normals


def _surface_field(surface, points: np.ndarray, samples: int = 4001):
    """min over segments and centre parameters s of |p − c(s)| − r(s) at each point, in float64, and the unit
    p − c(s*) there."""
    s = np.linspace(0.0, 1.0, samples)
    best = np.full(len(points), np.inf)
    normals = np.zeros_like(points)
    boxes = surface.bounds_array()
    for k in range(surface.count):
        # Only the points in the segment's box (widened) can lie on its surface.
        inside = np.all((points >= boxes[k, 0] - 1e-3) & (points <= boxes[k, 1] + 1e-3), axis=1)
        index = np.nonzero(inside)[0]
        if len(index) == 0:
            continue
        centres = surface.a[k] + s[:, None] * (surface.b[k] - surface.a[k])
        radii = surface.ra[k] + s * (surface.rb[k] - surface.ra[k])
        offsets = points[index, None, :] - centres[None]
        lengths = np.linalg.norm(offsets, axis=2)
        field = lengths - radii[None]
        i = field.argmin(axis=1)
        rows = np.arange(len(index))
        value = field[rows, i]
        closer = np.abs(value) < np.abs(best[index])
        best[index[closer]] = value[closer]
        normals[index[closer]] = (offsets[rows, i] / lengths[rows, i, None])[closer]
    return best, normals


def test_curve_segments_in_the_bvh_match_brute_force(kernel_runner):
    rng = np.random.default_rng(36)
    curve = spectrace.curve(_random_curves(rng, 24), spectrace.diffuse(0.5), name="hair")
    ball = spectrace.shape("sphere", spectrace.diffuse(0.3), radius=0.3, center=(0.2, -0.1, 0.4))
    surface = curve.analytic
    assert surface.count > 40
    n = 2000
    origins = rng.normal(size=(n, 3))
    origins = 4.0 * origins / np.linalg.norm(origins, axis=1, keepdims=True)
    directions = rng.uniform(-1.2, 1.2, (n, 3)) - origins
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    t_max = rng.uniform(2.0, 6.0, n)
    hit, point, normal, _, occluded = _scene_hits(kernel_runner, _scene([curve, ball]), origins, directions, t_max)
    segment_t, segment_n = _segment_hits(kernel_runner, surface, origins, directions)
    expected_t = segment_t.min(axis=0)
    expected_n = segment_n[segment_t.argmin(axis=0), np.arange(n)]
    # The sphere, by its closed form, may hide a curve behind it.
    f = origins - np.array([0.2, -0.1, 0.4])
    b = np.einsum("ij,ij->i", f, directions)
    disc = b * b - (np.einsum("ij,ij->i", f, f) - 0.09)
    sphere_t = np.where(disc > 0, -b - np.sqrt(np.maximum(disc, 0)), np.inf)
    sphere_t = np.where(sphere_t > 0, sphere_t, np.inf)
    curve_first = expected_t < sphere_t
    want_t = np.minimum(expected_t, sphere_t)
    # Rays grazing a surface may go either way in float32: those whose two candidates are near are left out.
    with np.errstate(invalid="ignore"):  # inf − inf where both miss
        clear = ~(np.abs(expected_t - sphere_t) <= 1e-3)
    got_t = np.where(hit[:, 3] >= 0, hit[:, 0], np.inf)
    both_miss = np.isinf(want_t) & np.isinf(got_t)
    assert np.count_nonzero(curve_first & np.isfinite(expected_t)) > 200  # the test sees many curve hits
    with np.errstate(invalid="ignore"):
        agree = both_miss | (np.abs(got_t - want_t) <= 1e-4 * np.maximum(1.0, want_t))
    assert np.count_nonzero(~agree & clear) <= 2, np.nonzero(~agree & clear)[0][:10]
    seen = clear & curve_first & np.isfinite(expected_t) & agree
    # The point and normal the path vertex rebuilds from the hit record lie on the curves' surface, the normal
    # the float64 one there: p − c(s*) over its length, c(s*) the centre nearest p (the swept sphere's envelope),
    # away from grazing hits, where float32's error in t moves the normal most.
    facing = seen & (np.einsum("ij,ij->i", expected_n, directions) < -0.2)
    assert np.count_nonzero(facing) > 150
    distance, reference_n = _surface_field(surface, point[facing, :3].astype(np.float64))
    assert np.abs(distance).max() < 1e-4
    assert np.abs(normal[facing, :3] - reference_n).max() < 2e-3
    # Any-hit: something before t_max exactly when the closest hit is before it.
    decided = clear & (np.abs(want_t - t_max) > 1e-3)
    assert np.array_equal(occluded[decided].astype(bool), (want_t < t_max)[decided])


def test_diffuse_curve_under_a_distant_light_matches_the_cylinder_closed_form():
    """A straight curve of radius R along x, longer than the frame, seen side on by an orthographic camera and lit
    by a distant light of irradiance E arriving along −l: a convex diffuse surface (it sees no other surface), so
    each point's radiance is ρ/π E max(0, n·l) with n = (0, y/R, √(1 − y²/R²)) at height y. Each image row is the
    pixel's average of that over its height, against the row's mean over its columns within 5 standard errors."""
    radius, rho, irradiance = 0.6, 0.5, 3.0
    light_from = np.array([0.0, np.sin(np.radians(35.0)), np.cos(np.radians(35.0))])
    curve = spectrace.curve([[-10.0, 0.0, 0.0, radius], [10.0, 0.0, 0.0, radius]], spectrace.diffuse(rho))
    width, height = 24, 32
    scene = spectrace.Scene(
        camera=spectrace.Camera(origin=(0.0, 0.0, 5.0), target=(0.0, 0.0, 0.0), type="orthographic", view_width=1.5),
        width=width,
        height=height,
        spp=64,
        shapes=[curve],
        lights=[spectrace.distant_light(tuple(-light_from), irradiance)],
        max_depth=3,
    )
    y_image = np.asarray(spectrace.render(scene, progress=False).xyz)[..., 1]
    pixel = 1.5 / width
    top = 0.5 * height * pixel
    rows_y = top - (np.arange(height) + 0.5) * pixel
    expected = np.empty(height)
    for j, yc in enumerate(rows_y):
        y = yc + pixel * (np.arange(4000) + 0.5 - 2000) / 4000
        inside = np.abs(y) < radius
        n = np.stack([np.zeros_like(y), y / radius, np.sqrt(np.clip(1 - (y / radius) ** 2, 0, 1))], axis=1)
        expected[j] = np.mean(np.where(inside, rho / np.pi * irradiance * np.maximum(0.0, n @ light_from), 0.0))
    mean = y_image.mean(axis=1)
    standard_error = y_image.std(axis=1, ddof=1) / np.sqrt(width)
    assert expected.max() > 0.3 and np.count_nonzero(expected == 0.0) >= 4  # lit rows and empty ones
    tolerance = 5.0 * standard_error + 1e-4 * expected.max()
    assert np.all(np.abs(mean - expected) <= tolerance), (mean, expected, standard_error)


@pytest.mark.parametrize("curve_type, spp", [("tube", 64), ("flat", 32)])
def test_white_hair_curves_in_a_white_furnace_vanish(curve_type, spp):
    """Chiang et al.'s white furnace on curves: fibres of a hair BSDF that absorbs nothing, lit by a uniform sky
    of radiance 1, scatter all they receive, so every pixel they cover has radiance 1 (within 5 standard errors
    of the covered pixels' mean): the hit record's frame and h, and the culled back faces that let transmitted
    light cross a fibre, lose or add nothing. The covered pixels are those the same curves in black hide. On
    pbrt's flat strips h comes from v across the strip, which stands for the fibre, so light it transmits or
    reflects leaves it."""
    strands = [
        np.array([[x, -1.0, 0.0, 0.08], [x + 0.1, -0.3, 0.1, 0.08], [x - 0.1, 0.3, -0.1, 0.08], [x, 1.0, 0.0, 0.08]])
        for x in np.linspace(-0.6, 0.6, 6)
    ]

    def render(material, spp):
        scene = spectrace.Scene(
            camera=spectrace.Camera(origin=(0.0, 0.0, 4.0), target=(0.0, 0.0, 0.0)),
            width=32,
            height=32,
            spp=spp,
            shapes=[spectrace.curve(strands, material, curve_type=curve_type)],
            lights=[spectrace.constant_environment(1.0)],
            max_depth=100,
            rr_depth=100,
        )
        return np.asarray(spectrace.render(scene, progress=False).xyz)[..., 1]

    covered = render(spectrace.diffuse(0.0), 4) < 0.05
    assert np.count_nonzero(covered) > 60
    furnace = render(spectrace.hair(sigma_a=0.0, beta_m=0.3, beta_n=0.3), spp)[covered]
    assert furnace.std() > 0.005  # the fibres scatter (not a sky seen straight through)
    assert abs(furnace.mean() - 1.0) <= 5.0 * furnace.std(ddof=1) / np.sqrt(furnace.size)


@pytest.mark.parametrize("basis", ["linear", "bspline"])
def test_light_a_white_fibre_scatters_once_leaves_it(basis):
    """The white furnace with one scattering (max_depth 2): a fibre that absorbs nothing sends all it receives
    from a uniform sky back out, so each pixel it covers shows the sky if every direction its lobes send light
    in leaves the fibre. The transmitted lobes (TT, TRT) start inside the fibre; a curve that bends a little per
    segment (a B-spline's short segments, a gently bent polyline) has neighbouring segments whose surfaces cross
    at grazing angles inside the tube, where such a ray must not stop. One fibre, bent gently in its own plane
    (no part of it sees another), 64 samples a pixel: the covered pixels' mean within 5 standard errors of 1."""
    x = np.linspace(-1.2, 1.2, 13 if basis == "linear" else 7)
    points = np.stack([x, 0.25 * np.sin(2.0 * x), np.zeros_like(x), np.full_like(x, 0.15)], axis=1)

    def render(material, spp):
        scene = spectrace.Scene(
            camera=spectrace.Camera(origin=(0.0, 0.0, 4.0), target=(0.0, 0.0, 0.0), fov_degrees=36.0),
            width=32,
            height=32,
            spp=spp,
            shapes=[spectrace.curve(points, material, basis=basis)],
            lights=[spectrace.constant_environment(1.0)],
            max_depth=2,
        )
        return np.asarray(spectrace.render(scene, progress=False).xyz)[..., 1]

    covered = render(spectrace.diffuse(0.0), 4) < 0.02
    assert np.count_nonzero(covered) > 40, np.count_nonzero(covered)
    once = render(spectrace.hair(sigma_a=0.0, beta_m=0.3, beta_n=0.3), 64)[covered]
    assert once.std() > 0.005  # the fibre scatters (not a sky seen straight through)
    assert abs(once.mean() - 1.0) <= 5.0 * once.std(ddof=1) / np.sqrt(once.size), (once.mean(), once.size)
