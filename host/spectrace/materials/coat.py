"""What light crossing a rough dielectric coat keeps: the plastic's `coat_transmission = "rough"` (docs/materials.md).

A rough interface of relative index η (microfacets of `distribution` and roughness α, the model of
kernels/bsdf_dielectric.cl: Walter et al. 2007 with Smith's height-correlated G2) transmits, of the light arriving
at cos θ = μ from outside, the fraction

    t(μ) = ∫ f_t(ωo, ωi) |cos θi| dωi = ∫ (1 − F(ωo·h)) G2(ωo, ωi(h)) D(h) (ωo·h) / μ dh      (ωi refracted through h)

and reflects from inside, averaged over a diffuse (cosine-weighted) hemisphere, R_int = 2 ∫ r_in(μ) μ dμ, with
r_in(μ) the same integral over reflected directions for light inside (index 1/η, total internal reflection
included). Single scattering: both lose what bounces between microfacets, so t(μ) < 1 − F(μ) for a rough coat.
Mitsuba 3's roughplastic uses these two (with Smith's separable G1 G1). The integrals are over the microfacet normal
h, drawn by the inverse of the D(h) cos θh distribution at Gauss–Legendre nodes (so the quadrature follows the
lobe), in float64.
"""

from functools import lru_cache

import numpy as np

from spectrace.spectral.grid import GRID_SIZE

# Nodes of the quadrature over the microfacet normal: in the distribution's cumulative polar angle and in azimuth.
_POLAR_NODES, _AZIMUTH_NODES = 160, 48
_MU_NODES = 64  # Gauss–Legendre nodes in μ for R_int
_TABLE_NODES = 97  # μ at which t is integrated, then interpolated linearly onto the table


def _lambda(cos_w: np.ndarray, alpha: float, distribution: str) -> np.ndarray:
    """Smith's Λ as the kernels evaluate it (kernels/microfacet.cl): GGX exact, Beckmann's rational
    approximation."""
    c2 = np.clip(cos_w * cos_w, 1e-12, 1.0)
    tan2 = (1.0 - c2) / c2
    if distribution == "beckmann":
        with np.errstate(divide="ignore"):
            a = 1.0 / (alpha * np.sqrt(tan2))
        lam = (1.0 - 1.259 * a + 0.396 * a * a) / (3.535 * a + 2.181 * a * a)
        return np.where(a >= 1.6, 0.0, lam)
    return 0.5 * (np.sqrt(1.0 + alpha * alpha * tan2) - 1.0)


def _normals(alpha: float, distribution: str) -> tuple[np.ndarray, np.ndarray]:
    """Microfacet normals at the quadrature's nodes, (n, 3), drawn from D(h) cos θh (the nodes' weights w sum to 1),
    and each one's weight w / cos θh, so that Σ weight · g(h) ≈ ∫ D(h) g(h) dh."""
    u, wu = np.polynomial.legendre.leggauss(_POLAR_NODES)
    u, wu = 0.5 * (u + 1.0), 0.5 * wu
    # ωo lies in the xz plane, so the integrands are even in φ: the half turn [0, π] stands for the whole.
    phi = (np.arange(_AZIMUTH_NODES) + 0.5) * (np.pi / _AZIMUTH_NODES)
    # Inverse cumulative distribution of D(h) cos θh in tan²θh (Walter et al. 2007, eqs. 28 and 35).
    tan2 = -alpha * alpha * np.log1p(-u) if distribution == "beckmann" else alpha * alpha * u / (1.0 - u)
    cos_h = 1.0 / np.sqrt(1.0 + tan2)
    sin_h = np.sqrt(np.maximum(1.0 - cos_h * cos_h, 0.0))
    h = np.stack(
        [
            np.outer(sin_h, np.cos(phi)).ravel(),
            np.outer(sin_h, np.sin(phi)).ravel(),
            np.repeat(cos_h, _AZIMUTH_NODES),
        ],
        axis=1,
    )
    return h, np.repeat(wu, _AZIMUTH_NODES) / (_AZIMUTH_NODES * h[:, 2])


def _fresnel(cos_i: np.ndarray, eta: float) -> tuple[np.ndarray, np.ndarray]:
    """Unpolarised reflectance for light at cos θi from the side where eta = n_beyond / n_here, and cos θt (0 under
    total internal reflection)."""
    cos2_t = 1.0 - (1.0 - cos_i * cos_i) / (eta * eta)
    cos_t = np.sqrt(np.maximum(cos2_t, 0.0))
    r_par = (eta * cos_i - cos_t) / (eta * cos_i + cos_t)
    r_perp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t)
    return np.where(cos2_t <= 0.0, 1.0, 0.5 * (r_par * r_par + r_perp * r_perp)), cos_t


def _albedos(mu: np.ndarray, eta: float, alpha: float, distribution: str) -> tuple[np.ndarray, np.ndarray]:
    """(reflected, transmitted) fractions for light arriving at each cos θ = μ from the side where the index beyond
    is eta times this side's."""
    h, weight = _normals(alpha, distribution)
    reflected, transmitted = np.zeros(len(mu)), np.zeros(len(mu))
    with np.errstate(divide="ignore", invalid="ignore"):
        for index, m in enumerate(mu):
            reflected[index], transmitted[index] = _albedo_at(m, h, weight, eta, alpha, distribution)
    return reflected, transmitted


def _albedo_at(m, h, weight, eta, alpha, distribution) -> tuple[float, float]:
    wo = np.array([np.sqrt(max(1.0 - m * m, 0.0)), 0.0, m])
    wo_h = h @ wo
    front = wo_h > 0.0
    f, cos_t = _fresnel(np.where(front, wo_h, 1.0), eta)
    common = np.where(front, weight * wo_h / m, 0.0)
    lam_o = _lambda(np.array([m]), alpha, distribution)[0]
    wr = 2.0 * wo_h[:, None] * h - wo
    up = front & (wr[:, 2] > 0.0)
    g_r = 1.0 / (1.0 + lam_o + _lambda(wr[:, 2], alpha, distribution))
    reflected = np.sum(np.where(up, common * f * g_r, 0.0))
    wt = (wo_h / eta - cos_t)[:, None] * h - wo / eta  # refracted through h (unit when not totally reflected)
    down = front & (cos_t > 0.0) & (wt[:, 2] < 0.0)
    g_t = 1.0 / (1.0 + lam_o + _lambda(wt[:, 2], alpha, distribution))
    transmitted = np.sum(np.where(down, common * (1.0 - f) * g_t, 0.0))
    return float(reflected), float(transmitted)


@lru_cache(maxsize=64)
def rough_coat(eta: float, alpha: float, distribution: str) -> tuple[np.ndarray, float]:
    """t(μ) at μ = i / (GRID_SIZE − 1), i = 0 … GRID_SIZE − 1 (the kernels read it as a row of the spectrum table,
    interpolating linearly in μ), and R_int."""
    mu = np.linspace(0.0, 1.0, _TABLE_NODES)
    _, transmitted = _albedos(np.maximum(mu, 1e-4), eta, alpha, distribution)
    transmitted = np.interp(np.linspace(0.0, 1.0, GRID_SIZE), mu, transmitted)
    # Inside, light beyond the critical angle (μ below μc) is totally reflected by a smooth coat: the integrand's
    # kink there gets a node interval of its own on each side.
    critical = np.sqrt(1.0 - 1.0 / (eta * eta))
    nodes, weights = np.polynomial.legendre.leggauss(_MU_NODES // 2)
    mu = np.concatenate([critical * 0.5 * (nodes + 1.0), critical + (1.0 - critical) * 0.5 * (nodes + 1.0)])
    mu_weights = np.concatenate([critical * 0.5 * weights, (1.0 - critical) * 0.5 * weights])
    reflected_inside, _ = _albedos(mu, 1.0 / eta, alpha, distribution)
    return transmitted, float(np.sum(2.0 * mu * reflected_inside * mu_weights))
