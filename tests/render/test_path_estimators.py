"""The path tracer's next-event estimation, MIS weights and Russian roulette, each against a closed form that a 2 %
error in any of them breaks, in three regimes of the MIS weights.

All scenes are the inside of a sphere of radius R, seen by a radiance meter at its centre, where the geometry makes
the transport exact:

- Two points x, y on the sphere see each other with cos θx = cos θy = |x − y| / 2R, so the irradiance from the
  sphere's inner surface at any point is π × (area mean of the radiance leaving it), whatever lies where.
- A ray leaving a wall point at angle θ to its normal meets the wall again at the same angle θ: with everything
  uniform, the radiance at every wall point is one function of the angle to the normal.

Regimes (the path tracer has no switch to turn a strategy off, so the scenes choose which one carries the light):

- NEE-dominated: a black emitting sphere of radius s R at the centre inside a diffuse wall. Its pdf per solid angle
  from a wall point is about 1 / (π s²) against the BSDF's cos θ / π, so next-event estimation carries nearly all
  direct light. The inner sphere hides, from each wall point, the cone around its normal of projected solid angle
  π s²: the wall radiance with j more segments is W_j = ρ s² Le + ρ (1 − s²) W_{j−1}, W_0 = 0.
- Balanced: a diffuse wall that emits Le everywhere. Sampling its area gives a pdf per solid angle
  r² / (A cos θ') = cos θ / π, exactly the BSDF's: both MIS weights are 1/2. With a checkerboard albedo ρ(x) of
  area mean ρ̄, L_d(x) = Le + ρ(x) M_{d−1} and M_j = Le + ρ̄ M_{j−1}, M_1 = Le (M: the area mean).
- BSDF-dominated: an emitting rough conductor wall (GGX, α = 0.2), whose lobe is far narrower than the light's
  cosine-shaped pdf; at α = 0.6 the two strategies share the light. The radiance leaving the wall at angle θ to
  its normal solves L = Le + K L, K the BRDF's integral operator over the angle, here by Gauss–Legendre quadrature
  of the microfacet model (Walter et al. 2007, height-correlated Smith G2 of Heitz 2014) and the exact conductor
  Fresnel term, computed in numpy; the meter reads L(0).

Each check asserts that 4σ of its estimate is below 2 % of the quantity that a broken estimator changes.
"""

import numpy as np
import pytest

import spectrace
from spectrace.engine.meters import RadianceMeter, measure
from spectrace.scene.model import Scene
from stats_toolkit import SIGMAS, assert_within_standard_errors

LE = 1.0
MAX_MISSABLE = 0.02  # the largest relative error a check may still miss at 4σ
WAVELENGTH_NM = 550.0
NO_ROULETTE = 64  # an rr_depth beyond every truncated depth here


def _scene(shapes, max_depth: int, rr_depth: int) -> Scene:
    camera = spectrace.Camera(origin=(0.0, 0.0, 0.0), target=(0.0, 0.0, 1.0))
    return Scene(camera=camera, width=1, height=1, shapes=shapes, max_depth=max_depth, rr_depth=rr_depth)


def _wall(material, emits: bool):
    emitter = spectrace.area_emitter(LE, two_sided=True) if emits else None
    return spectrace.shape("sphere", material, emitter=emitter, center=(0.0, 0.0, 0.0), radius=1.0)


def _check(scene, origin, direction, expected, baseline, device, streams, samples, what):
    """The meter's reading less `baseline` (the part that no estimator under test touches, seen directly) against
    `expected`; the tolerance is relative to `expected`."""
    direction = tuple(np.asarray(direction) / np.linalg.norm(direction))
    reading = measure(scene, RadianceMeter(origin, direction), [WAVELENGTH_NM], streams, samples, seed=7, device=device)
    value = float(reading.spectral[0]) - baseline
    se = float(reading.spectral_standard_error[0])
    missable = SIGMAS * se / expected
    assert missable < MAX_MISSABLE, f"{what}: 4σ = {missable:.2%} of the expected value, too noisy to see 2 %"
    assert_within_standard_errors(
        value, expected, se, slack=1e-5 * expected, what=f"{what} (errors above {missable:.2%} would show)"
    )


# NEE-dominated: a small black emitting sphere inside a diffuse wall.
RHO = 0.6
S = 0.25


def _nee_scene(max_depth: int, rr_depth: int) -> Scene:
    lamp = spectrace.shape(
        "sphere", spectrace.diffuse(0.0), emitter=spectrace.area_emitter(LE), center=(0.0, 0.0, 0.0), radius=S
    )
    return _scene([_wall(spectrace.diffuse(RHO), emits=False), lamp], max_depth, rr_depth)


def _nee_wall_radiance(max_depth: int) -> float:
    """W after the meter's segment: max_depth − 1 more segments, or the limit for max_depth −1."""
    if max_depth < 0:
        return RHO * S * S * LE / (1.0 - RHO * (1.0 - S * S))
    w = 0.0
    for _ in range(max_depth - 1):
        w = RHO * S * S * LE + RHO * (1.0 - S * S) * w
    return w


@pytest.mark.parametrize(
    "max_depth, rr_depth",
    [(2, NO_ROULETTE), (4, NO_ROULETTE), (6, 2), (-1, 1), (-1, 3)],
)
def test_nee_dominated_sphere(device, max_depth, rr_depth):
    """Direct light (max_depth 2) is next-event estimation alone but for a ~0.4 % MIS share; deeper, every bounce
    adds it again, with Russian roulette from the first or the third bounce."""
    scene = _nee_scene(max_depth, rr_depth)
    # From off the centre (the lamp is there), looking away from the lamp at an oblique wall point.
    origin, direction = (0.0, 0.0, 0.4), (0.3, -0.2, 0.93)
    streams, samples = (64, 128) if max_depth == 2 else (64, 1024)
    _check(
        scene,
        origin,
        direction,
        _nee_wall_radiance(max_depth),
        0.0,
        device,
        streams,
        samples,
        f"max_depth {max_depth}, rr_depth {rr_depth}",
    )


# Balanced: an emitting wall with a checkerboard albedo.
RHO_0, RHO_1 = 0.7, 0.3


def _textured_scene(max_depth: int, rr_depth: int) -> Scene:
    # Four squares around in u (azimuth), two in v (polar angle): every band of latitude is half of each, so the
    # area mean is the plain mean of the two albedos.
    albedo = spectrace.checkerboard(RHO_0, RHO_1, uv_scale=(4.0, 2.0))
    return _scene([_wall(spectrace.diffuse(albedo), emits=True)], max_depth, rr_depth)


def _mean_radiance(segments: int) -> float:
    """M_segments, the area mean of the wall radiance with that many segments (the limit for −1)."""
    mean_albedo = 0.5 * (RHO_0 + RHO_1)
    if segments < 0:
        return LE / (1.0 - mean_albedo)
    m = 0.0
    for _ in range(segments):
        m = LE + mean_albedo * m
    return m


@pytest.mark.parametrize("max_depth, rr_depth", [(3, NO_ROULETTE), (-1, 1)])
def test_balanced_weights_on_a_checkerboard(device, max_depth, rr_depth):
    """The middle of a square of each albedo (uv = (1/8, 1/4) and (3/8, 1/4)), seen from the centre; what is
    checked is L − Le, the light the wall reflects, which emission seen directly does not touch."""
    scene = _textured_scene(max_depth, rr_depth)
    theta = np.pi / 4
    for azimuth, albedo in ((np.pi / 4, RHO_0), (3 * np.pi / 4, RHO_1)):
        direction = (np.sin(theta) * np.cos(azimuth), np.sin(theta) * np.sin(azimuth), np.cos(theta))
        expected = albedo * _mean_radiance(max_depth - 1 if max_depth > 0 else -1)
        _check(
            scene,
            (0.0, 0.0, 0.0),
            direction,
            expected,
            LE,
            device,
            64,
            512 if max_depth > 0 else 2048,
            f"albedo {albedo}, max_depth {max_depth}, rr_depth {rr_depth}",
        )


# BSDF-dominated: an emitting rough conductor wall.
GLOSSY_ALPHAS = (0.2, 0.6)
ETA, KAPPA = 0.5, 2.0


def _fresnel_conductor(cos_i, eta):
    """Unpolarised Fresnel reflectance of a complex index η + iκ, from the amplitude coefficients."""
    sin2_t = (1.0 - cos_i**2) / eta**2
    cos_t = np.sqrt(1.0 - sin2_t)
    r_s = (cos_i - eta * cos_t) / (cos_i + eta * cos_t)
    r_p = (eta * cos_i - cos_t) / (eta * cos_i + cos_t)
    return 0.5 * (np.abs(r_s) ** 2 + np.abs(r_p) ** 2)


def _ggx_lambda(cos_t, alpha):
    tan2 = (1.0 - cos_t**2) / cos_t**2
    return 0.5 * (np.sqrt(1.0 + alpha**2 * tan2) - 1.0)


def _conductor_operator(alpha, nodes_mu, weights_mu, azimuths):
    """K[a, b]: ∫ f(θa → θb, φ) cos θb dφ × the quadrature weight of μb = cos θb, for outgoing μa = nodes_mu[a]."""
    mu_i = nodes_mu[:, None]
    sin_i = np.sqrt(1.0 - mu_i**2)
    wi = np.stack(np.broadcast_arrays(sin_i * np.cos(azimuths), sin_i * np.sin(azimuths), mu_i))
    operator = np.empty((len(nodes_mu), len(nodes_mu)))
    for a, mu_o in enumerate(nodes_mu):
        wo = np.array([np.sqrt(1.0 - mu_o**2), 0.0, mu_o])[:, None, None]
        h = wo + wi
        h = h / np.linalg.norm(h, axis=0)
        d = alpha**2 / (np.pi * (h[2] ** 2 * (alpha**2 - 1.0) + 1.0) ** 2)
        g2 = 1.0 / (1.0 + _ggx_lambda(mu_o, alpha) + _ggx_lambda(mu_i, alpha))
        fresnel = _fresnel_conductor(np.sum(wo * h, axis=0), ETA + 1j * KAPPA)
        f_cos = fresnel * d * g2 / (4.0 * mu_o)
        # The integrand is even in φ: the half circle, doubled.
        operator[a] = 2.0 * np.trapezoid(f_cos, azimuths, axis=1) * weights_mu
    return operator


def _conductor_normal_radiance(alpha: float, max_depth: int) -> float:
    """L(θ = 0) − Le, the light the wall reflects toward its centre, by quadrature (the limit for −1)."""
    # Gauss–Legendre in μ = cos θ on [0, 1], refined toward μ = 1 where the narrow lobe seen along the normal lies;
    # μ = 1 itself is added as the last node, the outgoing direction asked for (its weight: zero). Four times as
    # many nodes in each variable change the results by less than 1e-6 of them.
    nodes, weights = [], []
    for lo, hi, n in ((0.0, 0.9, 32), (0.9, 0.99, 32), (0.99, 1.0, 48)):
        x, w = np.polynomial.legendre.leggauss(n)
        nodes.append(lo + (hi - lo) * (x + 1) / 2)
        weights.append((hi - lo) / 2 * w)
    nodes_mu = np.concatenate([*nodes, [1.0 - 1e-12]])
    weights_mu = np.concatenate([*weights, [0.0]])
    operator = _conductor_operator(alpha, nodes_mu, weights_mu, np.linspace(0.0, np.pi, 361))
    radiance = np.full(len(nodes_mu), LE)  # L_1: the emission alone
    segments = max_depth if max_depth > 0 else 200
    for _ in range(segments - 1):
        radiance = LE + operator @ radiance
    return float(radiance[-1] - LE)


@pytest.mark.parametrize("alpha", GLOSSY_ALPHAS)
@pytest.mark.parametrize("max_depth, rr_depth", [(2, NO_ROULETTE), (4, NO_ROULETTE), (-1, 1)])
def test_glossy_rough_conductor(device, alpha, max_depth, rr_depth):
    """Along the wall's normal (every direction from the centre is); the quadrature's own error is far below the
    tolerance."""
    material = spectrace.conductor(eta=ETA, k=KAPPA, roughness=alpha)
    scene = _scene([_wall(material, emits=True)], max_depth, rr_depth)
    expected = _conductor_normal_radiance(alpha, max_depth)
    _check(
        scene,
        (0.0, 0.0, 0.0),
        (0.2, 0.3, 0.93),
        expected,
        LE,
        device,
        64,
        512 if max_depth > 0 else 2048,
        f"α {alpha}, max_depth {max_depth}, rr_depth {rr_depth}",
    )
