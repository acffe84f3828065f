"""The dielectric BSDF and the index-of-refraction models, checked on the device against independent references:
Sellmeier/Cauchy in numpy and glass-catalogue values; Fresnel's equations in their angle form; Snell's law;
energy conservation; generalised reciprocity; sample weights against eval/pdf; chi-square goodness of fit of the
rough sampler against its own pdf over the whole sphere.

Conventions of kernels/bsdf_dielectric.cl: local frame with +z the geometric normal to the exterior (index 1),
eta = n_interior; radiance transport, so the BTDF obeys f(ωo, ωi) / n(ωo)² = f(ωi, ωo) / n(ωi)², where n(ω) is the
index of the medium ω lies in, and a refracted radiance sample carries (n(ωo)/n(ωi))².
"""

import numpy as np
import pytest

from spectrace.core.contract import (
    IOR_CAUCHY,
    IOR_CONSTANT,
    IOR_SELLMEIER,
    MATERIAL_DTYPE,
    MATERIAL_NO_SPECTRUM,
    MICROFACET_BECKMANN,
    MICROFACET_GGX,
)
from spectrace.materials import MATERIAL_CODES
from spectrace.spectral.glasses import glass
from stats_toolkit import (
    assert_chi_square_fits,
    assert_furnace,
    assert_reciprocal,
    assert_within_standard_errors,
    mean_and_standard_error,
)

HARNESS = "testing/bsdf_dielectric.cl"
D_LINE_NM = 587.5618  # helium d line, where catalogues quote n_d
F_LINE_NM = 486.1327  # hydrogen F and C lines, which define the Abbe number
C_LINE_NM = 656.2725


# ---------------------------------------------------------------- helpers


def _run(kernel_runner, name, n, inputs, outputs, scalars=()):
    """inputs: arrays copied in; scalars: numpy scalars placed after the inputs; outputs: (dtype, shape) pairs."""
    runner = kernel_runner(HARNESS)
    args = [runner.buffer(np.ascontiguousarray(a)) for a in inputs] + list(scalars)
    host = [np.zeros(shape, dtype) for dtype, shape in outputs]
    first = len(args)
    args += [runner.buffer(h, True) for h in host]
    runner.run(name, n, args, {first + i: h for i, h in enumerate(host)})
    return host


def _directions(theta, phi):
    theta, phi = np.broadcast_arrays(np.asarray(theta, float), np.asarray(phi, float))
    d = np.zeros(theta.shape + (4,), np.float32)
    d[..., 0] = np.sin(theta) * np.cos(phi)
    d[..., 1] = np.sin(theta) * np.sin(phi)
    d[..., 2] = np.cos(theta)
    return d


def _uniform_sphere(rng, n):
    z = rng.uniform(-1.0, 1.0, n)
    phi = rng.uniform(0.0, 2 * np.pi, n)
    return _directions(np.arccos(z), phi)


def _material(model, b=(0, 0, 0, 0), c=(0, 0, 0, 0), ior=1.0):
    m = np.zeros((), MATERIAL_DTYPE)
    m["type"] = MATERIAL_CODES["dielectric"]
    m["reflectance_offset"] = MATERIAL_NO_SPECTRUM
    m["ior_model"] = model
    m["ior_coefficients_b"] = b
    m["ior_coefficients_c"] = c
    m["ior"] = ior
    return m


def _sellmeier_material(name):
    g = glass(name)
    return _material(IOR_SELLMEIER, b=(*g.sellmeier_b, 0), c=(*g.sellmeier_c_um2, 0))


def _device_ior(kernel_runner, materials, index, lambda_nm):
    index = np.asarray(index, np.int32)
    lambda_nm = np.asarray(lambda_nm, np.float32)
    n, dispersive = _run(
        kernel_runner,
        "material_ior_at",
        len(index),
        [np.array(materials), index, lambda_nm],
        [(np.float32, len(index)), (np.int32, len(index))],
    )
    return n.astype(np.float64), dispersive


def _numpy_sellmeier(b, c, lambda_nm):
    """n² = 1 + Σ B λ² / (λ² − C), λ in µm: written out here, apart from the host and kernel code."""
    l2 = (np.asarray(lambda_nm) / 1000.0) ** 2
    return np.sqrt(1 + b[0] * l2 / (l2 - c[0]) + b[1] * l2 / (l2 - c[1]) + b[2] * l2 / (l2 - c[2]))


def _fresnel_angles(cos_i, eta):
    """Fresnel's equations in their angle form (Hecht, Optics, sec. 4.6): R_s = sin²(θi−θt)/sin²(θi+θt),
    R_p = tan²(θi−θt)/tan²(θi+θt), R = (R_s + R_p)/2; eta = n_t/n_i; 1 beyond the critical angle."""
    theta_i = np.arccos(cos_i)
    sin_t = np.sin(theta_i) / eta
    result = np.ones_like(theta_i)
    ok = (sin_t < 1) & (theta_i > 0)
    ti, tt = theta_i[ok], np.arcsin(sin_t[ok])
    rs = (np.sin(ti - tt) / np.sin(ti + tt)) ** 2
    rp = (np.tan(ti - tt) / np.tan(ti + tt)) ** 2
    result[ok] = 0.5 * (rs + rp)
    normal = theta_i == 0
    eta_normal = np.broadcast_to(eta, theta_i.shape)[normal]
    result[normal] = ((eta_normal - 1) / (eta_normal + 1)) ** 2  # the limit θi → 0 of both forms
    return result


# The microfacet distributions, by the name the tests are parametrised with.
DISTRIBUTIONS = {"ggx": MICROFACET_GGX, "beckmann": MICROFACET_BECKMANN}


def _rough_sample(kernel_runner, wo, eta, alpha, u, distribution="ggx"):
    n = len(wo)
    wi, weight, pdf, ok = _run(
        kernel_runner,
        "rough_sample",
        n,
        [wo, u],
        [(np.float32, (n, 4)), (np.float32, n), (np.float32, n), (np.int32, n)],
        scalars=(np.float32(eta), np.float32(alpha), np.int32(DISTRIBUTIONS[distribution])),
    )
    return wi, weight.astype(np.float64), pdf.astype(np.float64), ok


def _rough_eval_pdf(kernel_runner, wo, wi, eta, alpha, distribution="ggx"):
    n = len(wo)
    f_cos, pdf = _run(
        kernel_runner,
        "rough_eval_pdf",
        n,
        [wo, wi],
        [(np.float32, n), (np.float32, n)],
        scalars=(np.float32(eta), np.float32(alpha), np.int32(DISTRIBUTIONS[distribution])),
    )
    return f_cos.astype(np.float64), pdf.astype(np.float64)


def _index_of_side(z, eta):
    return np.where(z > 0, 1.0, eta)


# ---------------------------------------------------------------- index of refraction


def test_ior_models_match_numpy_formulas(kernel_runner):
    lam = np.arange(360.0, 831.0, 10.0)
    glasses = ["N-BK7", "SF11", "N-SF11"]
    cauchy_a, cauchy_b = 1.5046, 0.00420  # a BK7-like Cauchy fit, µm²
    materials = [_sellmeier_material(g) for g in glasses]
    materials += [_material(IOR_CAUCHY, b=(cauchy_a, cauchy_b, 0, 0)), _material(IOR_CONSTANT, ior=1.333)]
    index = np.repeat(np.arange(len(materials)), len(lam))
    n, dispersive = _device_ior(kernel_runner, materials, index, np.tile(lam, len(materials)))
    n = n.reshape(len(materials), len(lam))
    for row, name in enumerate(glasses):
        g = glass(name)
        np.testing.assert_allclose(n[row], _numpy_sellmeier(g.sellmeier_b, g.sellmeier_c_um2, lam), rtol=2e-6)
    np.testing.assert_allclose(n[3], cauchy_a + cauchy_b / (lam / 1000.0) ** 2, rtol=2e-6)
    np.testing.assert_allclose(n[4], 1.333, rtol=1e-7)
    assert list(dispersive.reshape(len(materials), len(lam))[:, 0]) == [1, 1, 1, 1, 0]
    assert np.all(np.diff(n[:4], axis=1) < 0), "normal dispersion: the index falls with wavelength"


@pytest.mark.parametrize(
    "name, nd, abbe",
    [("BK7", 1.5168, 64.17), ("N-BK7", 1.5168, 64.17), ("SF11", 1.78472, 25.76), ("N-SF11", 1.78472, 25.68)],
)
def test_ior_meets_glass_catalogue(kernel_runner, name, nd, abbe):
    """Independent anchors: the SCHOTT catalogue's n_d and Abbe number V_d = (n_d − 1)/(n_F − n_C)."""
    n, _ = _device_ior(kernel_runner, [_sellmeier_material(name)], [0, 0, 0], [D_LINE_NM, F_LINE_NM, C_LINE_NM])
    assert abs(n[0] - nd) < 5e-5, n[0]
    assert abs((n[0] - 1) / (n[1] - n[2]) - abbe) < 0.05


def test_unknown_glass_is_a_one_line_error():
    from spectrace.errors import SpectraceError

    with pytest.raises(SpectraceError, match="unknown glass 'BK8'.*N-BK7"):
        glass("BK8", where="scene.toml: materials.prism.ior")


# ---------------------------------------------------------------- smooth dielectric


def test_fresnel_matches_angle_form(kernel_runner):
    cos_i = np.linspace(0.0005, 1.0, 400)
    etas = [1.5, 1 / 1.5, 1.78472, 1 / 1.78472, 1.0001, 1.0]
    c = np.tile(cos_i, len(etas)).astype(np.float32)
    e = np.repeat(etas, len(cos_i)).astype(np.float32)
    reflectance, cos_t = _run(kernel_runner, "fresnel", len(c), [c, e], [(np.float32, len(c))] * 2)
    expected = _fresnel_angles(c.astype(np.float64), e.astype(np.float64))
    np.testing.assert_allclose(reflectance, expected, atol=2e-5)
    normal = cos_i == 1.0
    etas_as_given = np.array(etas, np.float32).astype(np.float64)
    np.testing.assert_allclose(
        reflectance.reshape(len(etas), -1)[:, normal].ravel(),
        ((etas_as_given - 1) / (etas_as_given + 1)) ** 2,
        rtol=1e-5,
    )
    sin_t = np.sqrt(1 - c.astype(np.float64) ** 2) / e
    refracts = sin_t < 1
    np.testing.assert_allclose(cos_t[refracts], np.sqrt(1 - sin_t[refracts] ** 2), atol=1e-5)
    assert np.all(cos_t[~refracts] == 0)


@pytest.mark.parametrize("eta", [1.5, 1.78472])
def test_smooth_dielectric_obeys_snell_and_fresnel(kernel_runner, eta):
    theta = np.linspace(0.0, np.radians(89.5), 90)
    wo_outside = _directions(theta, 0.7)
    wo = np.concatenate([wo_outside, wo_outside * np.array([1, 1, -1, 1], np.float32)])
    n = len(wo)
    outputs = [(np.float32, (n, 4)), (np.float32, n), (np.float32, n), (np.int32, n)]
    reflect = _run(
        kernel_runner, "smooth_sample", n, [wo, np.zeros(n, np.float32)], outputs, scalars=(np.float32(eta),)
    )
    refract = _run(
        kernel_runner, "smooth_sample", n, [wo, np.full(n, 0.9999999, np.float32)], outputs, scalars=(np.float32(eta),)
    )
    n_o = _index_of_side(wo[:, 2], eta)
    n_t = _index_of_side(-wo[:, 2], eta)
    cos_o = np.abs(wo[:, 2].astype(np.float64))
    fresnel = _fresnel_angles(np.minimum(cos_o, 1 - 1e-12), n_t / n_o)
    assert np.all(reflect[3] == 2) and np.all(refract[3] == 2), "every sample is valid and delta"

    # Reflection: the mirror direction, chosen with probability F.
    np.testing.assert_allclose(reflect[0][:, :3], wo[:, :3] * np.array([-1, -1, 1]), atol=1e-6)
    np.testing.assert_allclose(reflect[2], fresnel, atol=2e-5)
    np.testing.assert_allclose(reflect[1], 1.0, atol=1e-6)

    # Refraction: unit length, the other side, the opposite azimuth, n_o sin θo = n_t sin θt; chosen with 1 − F.
    total_internal = fresnel == 1.0
    assert np.array_equal(total_internal, n_o * np.sqrt(1 - cos_o**2) > n_t), "TIR past the critical angle only"
    wi, weight, pdf = refract[0][~total_internal], refract[1][~total_internal], refract[2][~total_internal]
    wo_t, n_o_t, n_t_t = wo[~total_internal], n_o[~total_internal], n_t[~total_internal]
    np.testing.assert_allclose(np.linalg.norm(wi[:, :3], axis=1), 1.0, atol=2e-6)
    assert np.all(np.sign(wi[:, 2]) == -np.sign(wo_t[:, 2]))
    sin_o = np.hypot(wo_t[:, 0], wo_t[:, 1])
    sin_t = np.hypot(wi[:, 0], wi[:, 1])
    np.testing.assert_allclose(n_t_t * sin_t, n_o_t * sin_o, atol=3e-6)
    moving = sin_o > 1e-3
    np.testing.assert_allclose(wi[moving, :2] / sin_t[moving, None], -wo_t[moving, :2] / sin_o[moving, None], atol=1e-5)
    np.testing.assert_allclose(pdf, 1 - fresnel[~total_internal], atol=2e-5)
    # Radiance crossing into index n_o from n_t scales by (n_o/n_t)² (L/n² is invariant along a refracted ray).
    np.testing.assert_allclose(weight, (n_o_t / n_t_t) ** 2, rtol=1e-6)
    # Energy: each lobe's weight, turned from radiance back into flux, is 1, so reflected + refracted = 1 exactly.
    flux_weight = weight * (n_t_t / n_o_t) ** 2
    np.testing.assert_allclose(reflect[2][~total_internal] + pdf * flux_weight, 1.0, atol=3e-6)


def test_smooth_dielectric_picks_reflection_with_fresnel_frequency(kernel_runner):
    rng = np.random.default_rng(5)
    n = 200_000
    eta = 1.5
    theta = np.radians(75.0)
    wo = np.repeat(_directions(np.array([theta]), 0.0), n, axis=0)
    uc = rng.random(n).astype(np.float32)
    wi, weight, pdf, ok = _run(
        kernel_runner,
        "smooth_sample",
        n,
        [wo, uc],
        [(np.float32, (n, 4)), (np.float32, n), (np.float32, n), (np.int32, n)],
        scalars=(np.float32(eta),),
    )
    reflected = np.mean(wi[:, 2] > 0)
    expected = _fresnel_angles(np.array([np.cos(theta)]), eta)[0]
    sigma = np.sqrt(expected * (1 - expected) / n)
    assert_within_standard_errors(reflected, expected, sigma)


# ---------------------------------------------------------------- rough dielectric

ROUGH_ETAS = [1.5, 1.78472]
ROUGH_ALPHAS = [0.05, 0.3, 0.8]
ROUGH_THETAS_DEG = [0.0, 30.0, 60.0, 80.0]
FRESNEL_SAMPLES = 400_000


def _flux_weights(wo, wi, weight, eta):
    """Turn radiance weights back into flux: a refracted sample's (n(ωo)/n(ωi))² is undone."""
    return weight * (_index_of_side(wi[:, 2], eta) / _index_of_side(wo[:, 2], eta)) ** 2


@pytest.mark.parametrize("distribution", DISTRIBUTIONS)
@pytest.mark.parametrize("eta", ROUGH_ETAS)
def test_rough_dielectric_conserves_energy(kernel_runner, eta, distribution):
    """∫ (f_r + f_t^flux) |cos θi| dωi ≤ 1 for light from every direction on either side, i.e. the sampled flux
    weights average at most 1 (within 4 standard errors)."""
    rng = np.random.default_rng(17)
    n = 20_000
    for alpha in ROUGH_ALPHAS:
        for theta_deg in ROUGH_THETAS_DEG:
            for side in (1, -1):
                theta = np.radians(theta_deg) if side > 0 else np.pi - np.radians(theta_deg)
                wo = np.repeat(_directions(np.array([theta]), 1.1), n, axis=0)
                u = rng.random((n, 4)).astype(np.float32)
                wi, weight, _, ok = _rough_sample(kernel_runner, wo, eta, alpha, u, distribution)
                assert np.all(np.isfinite(weight)) and np.all(weight >= 0)
                flux = _flux_weights(wo, wi, weight, eta)
                where = f"{distribution} eta={eta} alpha={alpha} theta={theta_deg} side={side}"
                mean, _ = assert_furnace(flux, 1.0, slack=1e-6, what=where, at_most=True)
                if alpha <= 0.05 and theta_deg <= 60:
                    # A nearly smooth interface loses almost nothing to masking...
                    assert mean > 0.97, (where, mean)
                if alpha <= 0.05 and theta_deg <= 60 and side > 0:
                    # ...and reflects about Fresnel's F (from outside: inside, the critical angle is too near).
                    # F is near 0.04, so resolving it to 5 % takes its own, larger sample; the slack is the
                    # rough interface's own departure from F (microfacet normals 0.05 rad off the mean, masking:
                    # below 1 % of F).
                    wo_f = np.repeat(wo[:1], FRESNEL_SAMPLES, axis=0)
                    u_f = rng.random((FRESNEL_SAMPLES, 4)).astype(np.float32)
                    wi_f, weight_f, _, _ = _rough_sample(kernel_runner, wo_f, eta, alpha, u_f, distribution)
                    flux_f = _flux_weights(wo_f, wi_f, weight_f, eta)
                    reflected = np.where(wi_f[:, 2] * wo_f[:, 2] > 0, flux_f, 0.0)
                    fresnel = _fresnel_angles(np.array([np.cos(np.radians(theta_deg))]), eta)[0]
                    reflected_mean, reflected_se = mean_and_standard_error(reflected)
                    assert_within_standard_errors(
                        reflected_mean, fresnel, reflected_se, slack=0.01 * fresnel, what=where, power=0.05
                    )


@pytest.mark.parametrize("eta", ROUGH_ETAS)
@pytest.mark.parametrize("alpha, distribution", [(0.1, "ggx"), (0.5, "ggx"), (0.4, "beckmann"), (0.8, "beckmann")])
def test_rough_dielectric_generalised_reciprocity(kernel_runner, eta, alpha, distribution):
    """f(ωo, ωi) / n(ωo)² = f(ωi, ωo) / n(ωi)², for pairs on one side (plain reciprocity) and on both sides (random
    pairs: Beckmann's lobes, with no long tail, need a larger α than GGX's for many such pairs to carry light)."""
    rng = np.random.default_rng(23)
    n = 50_000
    wo = _uniform_sphere(rng, n)
    wi = _uniform_sphere(rng, n)
    forward, _ = _rough_eval_pdf(kernel_runner, wo, wi, eta, alpha, distribution)
    backward, _ = _rough_eval_pdf(kernel_runner, wi, wo, eta, alpha, distribution)
    f_forward = forward / np.abs(wi[:, 2])  # eval returns f |cos θi|
    f_backward = backward / np.abs(wo[:, 2])
    lhs = f_forward / _index_of_side(wo[:, 2], eta) ** 2
    rhs = f_backward / _index_of_side(wi[:, 2], eta) ** 2
    transmission = wo[:, 2] * wi[:, 2] < 0
    assert np.count_nonzero(lhs[transmission] > 0) > n // 20, "thousands of refracting pairs carry light"
    assert_reciprocal(lhs, rhs, rtol=2e-3, what=f"eta={eta} alpha={alpha}")


@pytest.mark.parametrize("distribution", DISTRIBUTIONS)
@pytest.mark.parametrize("eta", ROUGH_ETAS)
def test_rough_dielectric_weight_is_eval_over_pdf(kernel_runner, eta, distribution):
    rng = np.random.default_rng(29)
    n = 40_000
    for alpha in (0.05, 0.4):
        wo = _uniform_sphere(rng, n)
        u = rng.random((n, 4)).astype(np.float32)
        wi, weight, pdf_sampled, ok = _rough_sample(kernel_runner, wo, eta, alpha, u, distribution)
        valid = ok == 1
        assert np.mean(valid) > 0.8
        f_cos, pdf = _rough_eval_pdf(kernel_runner, wo[valid], wi[valid], eta, alpha, distribution)
        np.testing.assert_allclose(pdf_sampled[valid], pdf, rtol=2e-3)
        np.testing.assert_allclose(weight[valid], f_cos / pdf, rtol=2e-3)
        assert np.all(wi[~valid] == 0) and np.all(weight[~valid] == 0)


# Chi-square goodness of fit of the rough sampler against its pdf, over the whole sphere. Each case: eta, alpha,
# θo in degrees (above 90: ωo inside the glass), distribution.
CHI2_CASES = [
    (1.5, 0.3, 40.0, "ggx"),
    (1.5, 0.6, 125.0, "ggx"),
    (1.78472, 0.15, 20.0, "ggx"),
    (1.78472, 0.5, 170.0, "ggx"),
    (1.5, 0.2, 75.0, "ggx"),
    (1.5, 0.3, 40.0, "beckmann"),
    (1.5, 0.6, 125.0, "beckmann"),
    (1.78472, 0.15, 20.0, "beckmann"),
    (1.5, 0.2, 75.0, "beckmann"),
]
CHI2_SAMPLES = 200_000
CHI2_BINS_COS, CHI2_BINS_PHI, CHI2_SUBDIVISIONS = 24, 48, 12


def _binned_pdf_mass(kernel_runner, wo_single, eta, alpha, distribution):
    """∫ pdf dω over every (cos θ, φ) bin by the midpoint rule on sub-cells, each weighted by its exact solid angle
    (cos θ_a − cos θ_b) Δφ. The sub-cells split each bin evenly in θ, not in cos θ, so that lobes near the poles
    (where cos θ barely changes) are still resolved."""
    s = CHI2_SUBDIVISIONS
    cos_edges = np.linspace(-1.0, 1.0, CHI2_BINS_COS + 1)
    theta_edges = np.concatenate(
        [np.linspace(a, b, s + 1)[:-1] for a, b in zip(np.arccos(cos_edges[:-1]), np.arccos(cos_edges[1:]))] + [[0.0]]
    )
    theta_mid = 0.5 * (theta_edges[:-1] + theta_edges[1:])
    cell_cos = np.abs(np.cos(theta_edges[1:]) - np.cos(theta_edges[:-1]))
    nphi = CHI2_BINS_PHI * s
    phi = (np.arange(nphi) + 0.5) * (2 * np.pi / nphi)
    tt, pp = np.meshgrid(theta_mid, phi, indexing="ij")
    wi = _directions(tt.ravel(), pp.ravel())
    wo = np.repeat(wo_single[None, :], len(wi), axis=0)
    _, pdf = _rough_eval_pdf(kernel_runner, wo, wi, eta, alpha, distribution)
    fine = pdf.reshape(len(theta_mid), nphi) * cell_cos[:, None] * (2 * np.pi / nphi)
    return fine.reshape(CHI2_BINS_COS, s, CHI2_BINS_PHI, s).sum(axis=(1, 3))


@pytest.mark.parametrize("eta, alpha, theta_deg, distribution", CHI2_CASES)
def test_rough_dielectric_sampler_matches_pdf_chi_square(kernel_runner, eta, alpha, theta_deg, distribution):
    rng = np.random.default_rng(int(1000 * alpha + theta_deg))
    wo_single = _directions(np.array([np.radians(theta_deg)]), 0.4)[0]
    wo = np.repeat(wo_single[None, :], CHI2_SAMPLES, axis=0)
    u = rng.random((CHI2_SAMPLES, 4)).astype(np.float32)
    wi, _, _, ok = _rough_sample(kernel_runner, wo, eta, alpha, u, distribution)
    valid = ok == 1
    cos_bin = np.clip(((wi[valid, 2] + 1) / 2 * CHI2_BINS_COS).astype(int), 0, CHI2_BINS_COS - 1)
    phi = np.mod(np.arctan2(wi[valid, 1], wi[valid, 0]), 2 * np.pi)
    phi_bin = np.clip((phi / (2 * np.pi) * CHI2_BINS_PHI).astype(int), 0, CHI2_BINS_PHI - 1)
    observed = np.zeros((CHI2_BINS_COS, CHI2_BINS_PHI))
    np.add.at(observed, (cos_bin, phi_bin), 1)
    mass = _binned_pdf_mass(kernel_runner, wo_single, eta, alpha, distribution)
    # The sampler may fail (a direction scattered under the macro-surface); the pdf's missing mass is that chance.
    assert mass.sum() <= 1.0 + 2e-3
    observed = np.append(observed.ravel(), np.count_nonzero(~valid))
    expected = np.append(mass.ravel(), max(1.0 - mass.sum(), 0.0)) * CHI2_SAMPLES
    assert_chi_square_fits(observed, expected, 0.01 / len(CHI2_CASES))


# ---------------------------------------------------------------- the rough coat's tables (plastic)


@pytest.mark.parametrize("eta, alpha, distribution", [(1.5, 0.1, "beckmann"), (1.5, 0.3, "ggx"), (1.78472, 0.6, "ggx")])
def test_rough_coat_tables_are_what_the_rough_dielectric_transmits_and_reflects(
    kernel_runner, eta, alpha, distribution
):
    """spectrace.materials.coat integrates this BSDF by quadrature on the host; Monte Carlo of the device's own
    sampler must give the same numbers within 4 standard errors (plus 2e-3 for the table's interpolation in μ):
    t(μ), the flux transmitted into the coat from outside at several angles, and R_int, the flux reflected back
    inside when light arrives from inside with cosine-weighted directions (μ drawn with density 2μ)."""
    from spectrace.materials.coat import rough_coat

    table, internal = rough_coat(eta, alpha, distribution)
    grid = np.linspace(0.0, 1.0, len(table))
    rng = np.random.default_rng(41)
    n = 100_000
    for theta_deg in (0.0, 40.0, 70.0, 85.0):
        wo = np.repeat(_directions(np.array([np.radians(theta_deg)]), 0.3), n, axis=0)
        wi, weight, _, _ = _rough_sample(
            kernel_runner, wo, eta, alpha, rng.random((n, 4)).astype(np.float32), distribution
        )
        transmitted = np.where(wi[:, 2] < 0, _flux_weights(wo, wi, weight, eta), 0.0)
        mean, se = mean_and_standard_error(transmitted)
        expected = np.interp(np.cos(np.radians(theta_deg)), grid, table)
        assert_within_standard_errors(mean, expected, se, slack=2e-3, what=(theta_deg, "t"))
    mu = np.sqrt(rng.random(n))
    inside = _directions(np.pi - np.arccos(mu), 2.0 * np.pi * rng.random(n))
    wi, weight, _, _ = _rough_sample(
        kernel_runner, inside, eta, alpha, rng.random((n, 4)).astype(np.float32), distribution
    )
    reflected = np.where(wi[:, 2] < 0, _flux_weights(inside, wi, weight, eta), 0.0)
    mean, se = mean_and_standard_error(reflected)
    assert_within_standard_errors(mean, internal, se, slack=2e-3, what="R_int")
