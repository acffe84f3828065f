"""The stochastic layered BSDFs (coatedconductor, coateddiffuse: pbrt-v4's LayeredBxDF, kernels/layered.cl) on the
device through kernels/testing/bsdf.cl.

Their eval and pdf are random-walk estimates (a fixed function of the directions, through a hash), so the registry
harness's exact laws (reciprocity of each value, a sample's weight equal to eval/pdf, the chi-square of the sampler
against its pdf) do not hold for them; what holds, checked here:
- the sampler against the eval: the sampled directions' histogram, each weighted by f·cos/pdf, estimates
  ∫_bin f cos dωi, which the eval's estimates at directions drawn uniformly in the bin also estimate (each bin
  compared within the two estimates' combined standard error);
- a sample's reported pdf is the pdf function at its direction (the one MIS evaluates for light samples too);
- energy: a lossless metal (η = 0, F = 1) under a clear coat and a non-absorbing slab (albedo 1) reflects at most
  everything; with smooth interfaces and 100 events per walk all but the walks still inside (below 2e-3 here) comes
  back;
- limits: smooth coat over smooth metal, no slab scattering: the closed form F + (1 − F)² Σⱼ Rcʲ Fʲ⁻¹ Tʲ (F the
  coat's Fresnel reflectance, Rc the metal's under the coat at the refracted angle, T = exp(−2 thickness / cos θt),
  j ≤ max_depth / 2 round trips); an index-matched coat of thickness 0 is the bare rough conductor, value for
  value (conductor's own kernel as the reference); a clear smooth coat over a Lambertian base, absorbing nothing,
  is the nonlinear plastic's closed form (plastic's own kernel as the reference).
Tolerances come from standard errors (4σ) with fixed seeds."""

import numpy as np
import pytest
from tests.materials.test_bsdfs import (
    HARNESS,
    Bsdf,
    _csv_optical_constants,
    _fresnel_complex,
    _uniform_hemisphere,
    _wo,
)

import spectrace as S
from stats_toolkit import assert_furnace, assert_within_standard_errors

SIGMAS = 4.0
LOSSLESS = {"eta": 0.0, "k": 1.0}  # Fresnel reflectance 1 at every angle


@pytest.fixture(scope="module")
def bsdf(kernel_runner):
    runner = kernel_runner(HARNESS)
    return lambda material: Bsdf(runner, material)


ROUGH_CASES = [
    ("coatedconductor-rough-rough", S.coatedconductor("Au", roughness=0.3, conductor_roughness=0.2, thickness=0.1)),
    (
        "coatedconductor-scattering-slab",
        S.coatedconductor("Cu", roughness=0.2, conductor_roughness=0.4, thickness=0.5, albedo=0.8, g=0.5),
    ),
    ("coateddiffuse-rough", S.coateddiffuse(0.8, roughness=0.4, thickness=0.2)),
    ("coateddiffuse-smooth-coat", S.coateddiffuse(0.7, thickness=0.3, albedo=0.6, g=-0.3)),
]
COS_BINS, PHI_BINS = 6, 8
HISTOGRAM_SAMPLES = 200_000
EVALS_PER_BIN = 4000


@pytest.mark.parametrize("name, material", ROUGH_CASES, ids=[c[0] for c in ROUGH_CASES])
def test_weighted_sample_histogram_matches_the_eval(bsdf, name, material):
    """Per bin (uniform in cos θ and φ) and wavelength: Σ weight / N over samples landing there against the bin's
    solid angle times the mean of eval at directions drawn uniformly in it."""
    device = bsdf(material)
    theta = 40.0
    wo = _wo(theta)
    s = device.sample(wo, HISTOGRAM_SAMPLES, seed=31)
    keep = s.ok & ~s.is_delta
    weight = np.where(keep[:, None], s.weight, 0.0)
    cos_bin = np.clip((s.wi[:, 2] * COS_BINS).astype(int), 0, COS_BINS - 1)
    phi = np.mod(np.arctan2(s.wi[:, 1], s.wi[:, 0]), 2.0 * np.pi)
    phi_bin = np.clip((phi / (2.0 * np.pi) * PHI_BINS).astype(int), 0, PHI_BINS - 1)
    bins = cos_bin * PHI_BINS + phi_bin
    rng = np.random.default_rng(32)
    n = EVALS_PER_BIN
    area = (1.0 / COS_BINS) * (2.0 * np.pi / PHI_BINS)
    wi_all, which = [], []
    for b in range(COS_BINS * PHI_BINS):
        c = (b // PHI_BINS + rng.random(n)) / COS_BINS
        p = (b % PHI_BINS + rng.random(n)) / PHI_BINS * 2.0 * np.pi
        r = np.sqrt(1.0 - c * c)
        wi_all.append(np.stack([r * np.cos(p), r * np.sin(p), c], axis=1))
        which.append(np.full(n, b))
    f_cos, _ = device.eval_pdf(wo, np.concatenate(wi_all))
    f_cos = f_cos.reshape(COS_BINS * PHI_BINS, n, 4)
    expected = area * f_cos.mean(axis=1)
    expected_se = area * f_cos.std(axis=1, ddof=1) / np.sqrt(n)
    # Each sample's weight in its bin and 0 in every other: the mean and standard error of those per bin.
    count = COS_BINS * PHI_BINS
    sums = np.stack([np.bincount(bins, weight[:, c], count) for c in range(4)], axis=1)
    squares = np.stack([np.bincount(bins, weight[:, c] ** 2, count) for c in range(4)], axis=1)
    observed = sums / HISTOGRAM_SAMPLES
    observed_se = np.sqrt(np.maximum(squares / HISTOGRAM_SAMPLES - observed**2, 0.0) / (HISTOGRAM_SAMPLES - 1))
    assert expected.sum() > 0.05, name
    se = np.sqrt(observed_se**2 + expected_se**2)
    # 192 bins × wavelengths: 4.5σ keeps the family's chance of a false alarm near 1 % for these fixed seeds.
    assert_within_standard_errors(observed, expected, se, 4.5, slack=1e-5, what=name)
    # And over the whole hemisphere: the albedo the sampler carries is the eval's integral.
    total_se = np.sqrt((weight.std(axis=0, ddof=1) / np.sqrt(HISTOGRAM_SAMPLES)) ** 2 + (expected_se**2).sum(axis=0))
    assert_within_standard_errors(weight.mean(axis=0), expected.sum(axis=0), total_se, SIGMAS, what=name)


@pytest.mark.parametrize("name, material", ROUGH_CASES, ids=[c[0] for c in ROUGH_CASES])
def test_a_samples_pdf_is_the_pdf_function_at_its_direction(bsdf, name, material):
    """MIS weighs a BSDF sample and a light sample by one function of the direction: the pdf a sample reports is
    material_pdf at the direction it returns (the walk's hash reads directions rounded to 2⁻²⁰, so the round trip
    through world space hashes alike), and it is positive wherever the eval is."""
    device = bsdf(material)
    rng = np.random.default_rng(33)
    wo = _uniform_hemisphere(rng, 4000)
    s = device.sample(wo, len(wo), seed=34)
    keep = s.ok & ~s.is_delta
    assert keep.sum() > 1000
    f_cos, pdf = device.eval_pdf(wo[keep], s.wi[keep])
    agree = np.isclose(s.pdf[keep], pdf, rtol=1e-5)
    assert agree.mean() > 0.99, (name, agree.mean())
    f_any, pdf_any = device.eval_pdf(wo, _uniform_hemisphere(rng, len(wo)))
    assert np.all(pdf_any[np.any(f_any > 0, axis=1)] > 0)


FURNACE_CASES = [
    ("smooth-coat-smooth-metal", dict(thickness=0.5)),
    ("smooth-coat-rough-metal", dict(conductor_roughness=0.4, thickness=0.5, g=0.3)),
    ("rough-coat-rough-metal", dict(roughness=0.3, conductor_roughness=0.3, thickness=0.2, g=-0.4)),
]


@pytest.mark.parametrize("name, layers", FURNACE_CASES, ids=[c[0] for c in FURNACE_CASES])
def test_a_lossless_coated_metal_reflects_at_most_everything(bsdf, name, layers):
    """η = 0 (F = 1 at every angle) under a clear coat with a slab of albedo 1: nothing is absorbed, so the albedo
    is at most 1 (less by the walks max_depth cuts off and by what rough interfaces lose to their single-scattering
    microfacets at every one of a walk's many bounces: 0.62 for a smooth coat over α = 0.4); with max_depth 100 and
    smooth interfaces it is 1 within 4σ and 2e-3, the cut-off walks' share."""
    n = 40000
    for depth in (10, 100):
        material = S.coatedconductor(**LOSSLESS, albedo=1.0, max_depth=depth, **layers)
        device = bsdf(material)
        for theta in (0.0, 45.0, 80.0):
            s = device.sample(_wo(theta), n, seed=40 + int(theta) + depth)
            weight = np.where(s.ok[:, None], s.weight, 0.0)
            mean, se = assert_furnace(weight, 1.0, SIGMAS, slack=1e-5, what=(name, depth, theta), at_most=True)
            if depth == 100 and not layers.get("roughness") and not layers.get("conductor_roughness"):
                assert_within_standard_errors(mean, 1.0, se, SIGMAS, slack=2e-3, what=(name, theta))


def _fresnel_dielectric(cos_i: np.ndarray, eta: float) -> np.ndarray:
    sin2_t = (1.0 - cos_i**2) / eta**2
    cos_t = np.sqrt(1.0 - sin2_t)
    r_s = (cos_i - eta * cos_t) / (cos_i + eta * cos_t)
    r_p = (eta * cos_i - cos_t) / (eta * cos_i + cos_t)
    return 0.5 * (r_s**2 + r_p**2)


@pytest.mark.parametrize("metal, ior, thickness", [("Au", 1.5, 0.2), ("Cu", 1.33, 0.05), ("Ag", 2.0, 0.0)])
def test_smooth_layers_sum_the_reflections_between_coat_and_metal(bsdf, metal, ior, thickness):
    """The albedo along the mirror direction of a smooth coat over a smooth metal with an absorbing slab: light
    reflected by the coat, F(θ), plus what enters ((1 − F) each way) and comes back after j ≤ max_depth / 2 round
    trips, each reflected by the metal (its η + ik over the coat's index, at θt) and attenuated by
    exp(−2 thickness / cos θt), with j − 1 reflections inside the coat (F again: the same at θt from inside)."""
    eta, k = _csv_optical_constants(metal)
    depth = 10
    device = bsdf(S.coatedconductor(metal, ior=ior, thickness=thickness, max_depth=depth))
    n = 40000
    for theta in (0.0, 35.0, 70.0, 85.0):
        cos_i = np.cos(np.radians(theta))
        f = _fresnel_dielectric(np.array(cos_i), ior)
        cos_t = np.sqrt(1.0 - (1.0 - cos_i**2) / ior**2)
        rc = _fresnel_complex(cos_t, eta / ior, k / ior)
        tr = np.exp(-2.0 * max(thickness, 0.0) / cos_t)
        trips = np.arange(1, depth // 2 + 1)[:, None]
        expected = f + (1.0 - f) ** 2 * np.sum((rc * tr) ** trips * f ** (trips - 1), axis=0)
        s = device.sample(_wo(theta), n, seed=50 + int(theta))
        assert np.all(s.is_delta[s.ok])
        np.testing.assert_allclose(s.wi[s.ok], np.broadcast_to(_wo(theta) * [-1, -1, 1], s.wi[s.ok].shape), atol=1e-5)
        weight = np.where(s.ok[:, None], s.weight, 0.0)
        mean, se = assert_furnace(weight, expected, SIGMAS, slack=2e-5, what=(metal, theta))


def test_an_index_matched_coat_of_no_thickness_is_the_bare_conductor(bsdf):
    """ior 1 passes light straight and thickness 0 absorbs nothing: eval is the conductor's value for value, and
    the sampler's mean weight the conductor's albedo."""
    rng = np.random.default_rng(60)
    wo, wi = _uniform_hemisphere(rng, 3000), _uniform_hemisphere(rng, 3000)
    coated = bsdf(S.coatedconductor("Au", ior=1.0, thickness=0.0, conductor_roughness=0.3))
    bare = bsdf(S.conductor("Au", roughness=0.3))
    f_coated, _ = coated.eval_pdf(wo, wi)
    f_bare, _ = bare.eval_pdf(wo, wi)
    assert np.any(f_bare > 0.01)
    np.testing.assert_allclose(f_coated, f_bare, rtol=1e-4, atol=1e-7)
    for theta in (20.0, 70.0):
        a = coated.sample(_wo(theta), 40000, seed=61)
        b = bare.sample(_wo(theta), 40000, seed=62)
        wa, wb = (np.where(x.ok[:, None], x.weight, 0.0) for x in (a, b))
        se = np.sqrt(wa.var(axis=0) / len(wa) + wb.var(axis=0) / len(wb))
        assert_within_standard_errors(wa.mean(axis=0), wb.mean(axis=0), se, SIGMAS, what=theta)


def test_estimates_are_functions_of_the_directions(bsdf):
    """The same (ωo, ωi) gives the same bits (a render split any way stays the same), and the estimates of nearby
    directions are independent walks: their spread is the estimator's noise, not a constant."""
    device = bsdf(S.coateddiffuse(0.8, roughness=0.3, albedo=0.5, thickness=0.5))
    rng = np.random.default_rng(70)
    wi = _uniform_hemisphere(rng, 2000)
    first, pdf_first = device.eval_pdf(_wo(30.0), wi)
    second, pdf_second = device.eval_pdf(_wo(30.0), wi)
    assert np.array_equal(first, second) and np.array_equal(pdf_first, pdf_second)
    near = wi + 1e-3 * np.array([1.0, 0.0, 0.0])
    near /= np.linalg.norm(near, axis=1)[:, None]
    third, _ = device.eval_pdf(_wo(30.0), near)
    assert np.mean(first[:, 0] != third[:, 0]) > 0.9


@pytest.mark.parametrize("name, material", ROUGH_CASES[:2], ids=[c[0] for c in ROUGH_CASES[:2]])
def test_reciprocal_in_the_mean(bsdf, name, material):
    """f(ωo, ωi) = f(ωi, ωo) holds for the estimates' means: at 64 pairs of directions, 32 replicas each way (the
    directions nudged by multiples of 4e-6, above the hash's resolution: independent walks of the same value); the
    differences' z-scores, summed in squares, fit a chi-square of 64 degrees of freedom."""
    from scipy import stats

    rng = np.random.default_rng(80)
    a, b = _uniform_hemisphere(rng, 64), _uniform_hemisphere(rng, 64)
    device = bsdf(material)
    forward, backward = [], []
    for replica in range(32):
        nudge = 4e-6 * (replica + 1)
        a_r = a + nudge * np.array([1.0, -1.0, 0.0])
        b_r = b + nudge * np.array([0.0, 1.0, -1.0])
        forward.append(device.eval_pdf(a_r, b_r)[0][:, 0] / b_r[:, 2])
        backward.append(device.eval_pdf(b_r, a_r)[0][:, 0] / a_r[:, 2])
    difference = np.array(forward) - np.array(backward)
    se = difference.std(axis=0, ddof=1) / np.sqrt(len(difference))
    assert np.mean(forward) > 0.01
    carried = se > 0
    z = difference.mean(axis=0)[carried] / se[carried]
    statistic = float(np.sum(z**2))
    assert stats.chi2.sf(statistic, carried.sum()) > 1e-3, (name, statistic, carried.sum())


@pytest.mark.parametrize("reflectance", [1.0, 0.5])
def test_a_clear_smooth_coat_over_a_diffuse_base_is_the_nonlinear_plastic(bsdf, reflectance):
    """With a slab that absorbs nothing (thickness 0) and walks long enough to lose nothing (max_depth 100), the
    walk over a Lambertian base under a smooth coat is the physics the plastic sums in closed form (nonlinear: the
    base's albedo met at every return): their albedos agree at every angle within 4σ and the walks' cut-off."""
    walk = bsdf(S.coateddiffuse(reflectance, ior=1.5, thickness=0.0, max_depth=100))
    closed = bsdf(S.plastic(reflectance, ior=1.5, nonlinear=True))
    n = 40000
    for theta in (0.0, 45.0, 80.0):
        a = walk.sample(_wo(theta), n, seed=90 + int(theta))
        b = closed.sample(_wo(theta), n, seed=91 + int(theta))
        wa, wb = (np.where(x.ok[:, None], x.weight, 0.0) for x in (a, b))
        se = np.sqrt(wa.var(axis=0) / n + wb.var(axis=0) / n)
        assert_within_standard_errors(wa.mean(axis=0), wb.mean(axis=0), se, SIGMAS, slack=1e-3, what=theta)
