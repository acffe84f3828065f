"""Analytic shapes in whole renders, measured with the meters against closed forms: furnaces (an albedo-1 surface of
any shape in a uniform environment of radiance k shows k; smooth glass too, as L/n² is conserved), shadow rays
blocked by a disk and thinned by a cut-out one, and an absorbing medium inside an index-matched sphere
(Beer–Lambert along a chord)."""

import numpy as np
import pytest

import spectrace
from spectrace.engine.meters import IrradianceMeter, RadianceMeter, measure
from spectrace.scene.model import Scene
from stats_toolkit import assert_within_standard_errors

K = 1.0


def _scene(shapes, lights, max_depth=-1) -> Scene:
    camera = spectrace.Camera(origin=(0.0, 0.0, 5.0), target=(0.0, 0.0, 0.0))
    return Scene(camera=camera, width=1, height=1, shapes=shapes, lights=lights, max_depth=max_depth)


def _radiance_550(scene, origin, direction, device, streams=32, samples=32):
    reading = measure(scene, RadianceMeter(origin, direction), [550.0], streams, samples, device=device)
    return reading.spectral[0], reading.spectral_standard_error[0]


@pytest.mark.parametrize(
    "kind, transform",
    [
        ("sphere", [{"scale": 0.8}]),
        ("cylinder", [{"scale": [0.6, 0.9, 1.2]}, {"rotate": {"axis": [1, 0, 0], "angle": 70}}]),
        ("disk", [{"scale": [1.0, 0.5, 1.0]}, {"rotate": {"axis": [1, 0, 0], "angle": 40}}]),
    ],
)
def test_white_furnace(device, kind, transform):
    """Seen from outside at two angles (into the open cylinder's inside, whose light bounces many times)."""
    shape = spectrace.shape(kind, spectrace.diffuse(1.0), transform=transform)
    scene = _scene([shape], [spectrace.constant_environment(K)])
    for origin in ((0.1, 0.05, 3.0), (0.05, 2.5, 0.6)):
        direction = -np.asarray(origin) / np.linalg.norm(origin)
        value, se = _radiance_550(scene, origin, tuple(direction), device)
        assert_within_standard_errors(value, K, se, sigmas=4, slack=1e-4, what=f"{kind} from {origin}")


def test_glass_sphere_furnace(device):
    """A smooth n = 1.5 analytic sphere: every path through it refracts in and out, so L = k exactly; a sphere
    hit from inside at the wrong side would darken or brighten it."""
    scene = _scene([spectrace.shape("sphere", spectrace.dielectric(1.5))], [spectrace.constant_environment(K)], 64)
    for origin in ((0.0, 0.0, 3.0), (0.0, 0.8, 3.0)):  # through the centre, and near the rim (grazing refraction)
        value, se = _radiance_550(scene, origin, (0.0, 0.0, -1.0), device)
        assert_within_standard_errors(value, K, se, sigmas=4, slack=1e-4, what=f"glass from {origin}")


def test_shadow_rays_meet_disks_and_pass_cut_outs(device):
    """A point light of intensity I 2 m above a meter: E = I / 4 unblocked; 0 behind an opaque disk; (1 − α) I / 4
    behind a cut-out disk of opacity α."""
    intensity = 4.0
    light = spectrace.point_light((0.0, 0.0, 2.0), intensity=intensity)
    meter = IrradianceMeter((0.0, 0.0, 0.0), (0.0, 0.0, 1.0))
    for opacity in (None, 1.0, 0.25):
        shapes = []
        if opacity is not None:
            material = spectrace.diffuse(0.0, opacity=opacity)
            shapes = [spectrace.shape("disk", material, transform=[{"scale": 0.3}, {"translate": [0, 0, 1]}])]
        reading = measure(_scene(shapes, [light], max_depth=2), meter, [550.0], 16, 64, device=device)
        expected = intensity / 4.0 * (1.0 if opacity is None else 1.0 - opacity)
        # Noiseless but for the cut-out, whose shadow rays each pass it or not.
        se = reading.spectral_standard_error[0]
        assert (se > 0) == (opacity == 0.25)
        assert_within_standard_errors(reading.spectral[0], expected, se, sigmas=4, slack=1e-4 * expected, what=opacity)


def test_absorbing_medium_inside_an_analytic_sphere(device):
    """An index-matched sphere of radius R filled with an absorber σa: looking through it at offset h from its
    centre, L = k exp(−σa · 2√(R² − h²)); the chord's two ends are the analytic sphere's crossings."""
    sigma_a, radius = 0.9, 0.7
    medium = spectrace.medium(sigma_a=sigma_a)
    ball = spectrace.shape("sphere", interior=medium, transform=[{"scale": radius}])
    scene = _scene([ball], [spectrace.constant_environment(K)])
    for h in (0.0, 0.5):
        value, se = _radiance_550(scene, (0.0, h, 3.0), (0.0, 0.0, -1.0), device, streams=8, samples=8)
        expected = K * np.exp(-sigma_a * 2.0 * np.sqrt(radius**2 - h**2))
        assert value == pytest.approx(expected, rel=2e-4), h


def _first_hits(surfaces, origin, directions) -> np.ndarray:
    """Index of the surface each ray meets first (float64 closed forms), -1 for none."""
    best_t = np.full(len(directions), np.inf)
    best = np.full(len(directions), -1)
    for index, surface in enumerate(surfaces):
        inverse = np.linalg.inv(surface.to_world)
        o = inverse[:3, :3] @ origin + inverse[:3, 3]
        d = directions @ inverse[:3, :3].T
        candidates = []
        with np.errstate(divide="ignore", invalid="ignore"):
            if surface.kind == "disk":
                t = -o[2] / d[:, 2]
                p = o + t[:, None] * d
                candidates.append(np.where(np.hypot(p[:, 0], p[:, 1]) <= 1, t, np.inf))
            else:
                axes = 3 if surface.kind == "sphere" else 2
                a, b, c = (d[:, :axes] ** 2).sum(1), d[:, :axes] @ o[:axes], (o[:axes] ** 2).sum() - 1
                root = np.sqrt(b * b - a * c)
                for t in ((-b - root) / a, (-b + root) / a):
                    z = o[2] + t * d[:, 2]
                    inside = (z >= 0) & (z <= 1) if surface.kind == "cylinder" else np.isfinite(t)
                    candidates.append(np.where(inside, t, np.inf))
        for t in candidates:
            t = np.where(t > 0, t, np.inf)
            closer = t < best_t
            best_t, best = np.where(closer, t, best_t), np.where(closer, index, best)
    return best


def test_many_shapes_are_found_through_their_bvh(device):
    """60 spheres, disks and cylinders at random, each emitting its own constant radiance 1.2^index, seen directly
    (max_depth 1): every pixel whose 4 x 4 grid of points all meet the same shape first (float64 closed forms) shows
    that shape's radiance, and a pixel that meets none shows black."""
    rng = np.random.default_rng(12)
    shapes = []
    for index in range(60):
        kind = ("sphere", "disk", "cylinder")[index % 3]
        # Disks face the camera (down -z) within 45° and cylinders lie within 45° of the image plane, so that none
        # is a sliver thinner than the reference's grid of points in a pixel.
        tilt = float(rng.uniform(-45, 45))
        if kind == "sphere":
            steps = [{"scale": float(rng.uniform(0.1, 0.35))}]
        elif kind == "disk":
            steps = [{"scale": [float(rng.uniform(0.15, 0.4)), float(rng.uniform(0.15, 0.4)), 1.0]}]
            steps.append({"rotate": {"axis": [1, 0, 0], "angle": tilt}})
        else:
            radius = float(rng.uniform(0.1, 0.3))
            steps = [{"scale": [radius, radius, float(rng.uniform(0.2, 0.5))]}]
            steps.append({"rotate": {"axis": [1, 0, 0], "angle": 90 + tilt}})
        steps.append({"rotate": {"axis": [0, 0, 1], "angle": float(rng.uniform(0, 360))}})
        steps.append({"translate": [float(x) for x in rng.uniform(-1.5, 1.5, 3)]})
        emitter = spectrace.area_emitter(1.2**index, two_sided=True)
        shapes.append(spectrace.shape(kind, spectrace.diffuse(0.0), emitter=emitter, transform=steps))
    size = 48
    camera = spectrace.Camera(origin=(0.0, 0.0, 6.0), target=(0.0, 0.0, 0.0), fov_degrees=45.0)
    scene = Scene(camera=camera, width=size, height=size, shapes=shapes, max_depth=1, spp=16)
    from spectrace.engine.renderer import Renderer

    y = Renderer(scene, device).render().xyz[..., 1]
    origin, forward, right, up = camera.basis(1.0)
    hits = []
    for dx, dy in ((x / 3, y / 3) for x in range(4) for y in range(4)):
        px, py = np.meshgrid(np.arange(size) + dx, np.arange(size) + dy)
        directions = forward + (2 * px / size - 1).ravel()[:, None] * right + (1 - 2 * py / size).ravel()[:, None] * up
        directions /= np.linalg.norm(directions, axis=1, keepdims=True)
        hits.append(_first_hits([s.analytic for s in shapes], origin, directions).reshape(size, size))
    clear = np.all([h == hits[0] for h in hits[1:]], axis=0)
    assert clear.mean() > 0.6 and len(np.unique(hits[0][clear])) > 25
    expected = np.where(hits[0] >= 0, 1.2 ** hits[0], 0.0)
    # The film's Y estimates a constant radiance through four sampled wavelengths per sample: within a few per cent
    # at 16 spp, far inside the 20 % between two shapes' radiances.
    np.testing.assert_allclose(y[clear], expected[clear], rtol=0.08, atol=1e-6)


def test_a_scene_without_analytic_shapes_never_meets_the_empty_shape_bvh(device):
    """The meters run the general kernels, which trace the (empty) analytic shapes' BVH too: a ray straight through
    the origin, where the dummy row's sphere of radius 0 sits, sees only the floor, L = ρ E / π."""
    albedo, irradiance = 0.6, 2.0
    floor = spectrace.shape("rectangle", spectrace.diffuse(albedo), transform=[{"translate": [0.0, 0.0, -1.0]}])
    light = spectrace.distant_light((0.0, 0.0, -1.0), irradiance=irradiance)
    value, se = _radiance_550(_scene([floor], [light], max_depth=2), (0.0, 0.0, 3.0), (0.0, 0.0, -1.0), device, 4, 4)
    assert value == pytest.approx(albedo * irradiance / np.pi, rel=1e-4) and se < 1e-4


def test_a_flipped_sphere_light_lights_its_inside(device):
    """A sphere light of radiance L with flip_normals emits inward: inside it E = π L whichever way a meter faces (a
    uniformly bright enclosure), outside nothing; unflipped, the reverse, with E = π L (R/d)² outside."""
    radiance, radius = 2.0, 1.5
    for flip in (True, False):
        lamp = spectrace.shape(
            "sphere", spectrace.diffuse(0.0), emitter=spectrace.area_emitter(radiance), radius=radius, flip_normals=flip
        )
        scene = _scene([lamp], [], max_depth=1)
        inside = measure(scene, IrradianceMeter((0.3, -0.2, 0.4), (0.6, 0.0, 0.8)), [550.0], 8, 16, device=device)
        outside = measure(scene, IrradianceMeter((0.0, 0.0, 3.0), (0.0, 0.0, -1.0)), [550.0], 8, 16, device=device)
        if flip:
            assert_within_standard_errors(
                inside.spectral[0], np.pi * radiance, inside.spectral_standard_error[0], slack=1e-4, what="inside"
            )
            assert outside.spectral[0] == 0.0
        else:
            assert inside.spectral[0] == 0.0
            assert_within_standard_errors(
                outside.spectral[0],
                np.pi * radiance * (radius / 3.0) ** 2,
                outside.spectral_standard_error[0],
                slack=1e-4,
                what="outside",
            )


def test_an_air_bubble_in_glass_is_a_flipped_sphere(device):
    """Inside an air bubble (a flipped n = 1.5 sphere) in a glass ball in radiance k, the radiance is k again (L/n² is
    conserved and the bubble's inside is air); unflipped, the bubble would be glass within glass, n = 2.25, where
    L = 2.25² k."""
    for flip, expected in ((True, K), (False, 2.25**2 * K)):
        glass = spectrace.shape("sphere", spectrace.dielectric(1.5), radius=1.0)
        bubble = spectrace.shape("sphere", spectrace.dielectric(1.5), radius=0.5, flip_normals=flip)
        scene = _scene([glass, bubble], [spectrace.constant_environment(K)], max_depth=64).with_overrides(rr_depth=64)
        value, _ = _radiance_550(scene, (0.05, 0.1, 0.0), (0.3, 0.2, 0.93), device, streams=4, samples=8)
        assert value == pytest.approx(expected, rel=1e-5), flip


def test_direct_integrator_equals_path_at_depth_two(device):
    """The local model (direct light at the first hit) and the global one at max_depth 2 estimate the same image of a
    floor lit by a sphere light (cone-sampled) and a tilted elliptic disk light (area-sampled): 8 x 8-pixel blocks
    agree within 5 standard errors (tests/replica_agreement.py)."""
    from replica_agreement import assert_replicas_agree, spectrace_replicas
    from spectrace.engine.renderer import Renderer

    floor = spectrace.shape("disk", spectrace.plastic(0.5, roughness=0.3), transform=[{"scale": 3}])
    bulb = spectrace.shape("sphere", spectrace.diffuse(0.0), emitter=spectrace.area_emitter(30.0), center=[0.5, 0, 1],
                           radius=0.1)  # fmt: skip
    panel = spectrace.shape(
        "disk",
        spectrace.diffuse(0.0),
        emitter=spectrace.area_emitter(4.0),
        transform=[{"scale": [0.4, 0.2, 1]}, {"rotate": {"axis": [0, 1, 0], "angle": 150}}, {"translate": [-1, 0, 1]}],
    )
    camera = spectrace.Camera(origin=(0.0, -3.0, 2.0), target=(0.0, 0.0, 0.0))
    scene = Scene(camera=camera, width=32, height=32, shapes=[floor, bulb, panel], max_depth=2)
    path = spectrace_replicas(Renderer(scene, device), 8, 24)
    direct = spectrace_replicas(Renderer(scene.with_overrides(integrator="direct", seed=1), device), 8, 24)
    assert_replicas_agree(direct, path, 8)
    assert path[..., 1].mean() > 0.05
