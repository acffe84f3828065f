"""The kernel's hero-wavelength estimator of film XYZ converges to colour-science's integration."""

import colour
import numpy as np
import pytest

from spectrace.spectral.colorimetry import cmf_table_normalised
from spectrace.spectral.grid import GRID_NM
from spectrace.spectral.illuminants import d65_normalised
from spectrace.spectral.spectrum import Spectrum
from spectrace.spectral.table import SpectrumTable

ITEMS = 4096
SAMPLES_PER_ITEM = 64


def _colour_xyz(values: np.ndarray) -> np.ndarray:
    """Film XYZ by colour-science: sd_to_XYZ without an illuminant normalises by 100/∫ȳ (illuminant E)."""
    shape = colour.SpectralShape(360, 830, 1)
    sd = colour.SpectralDistribution(dict(zip(GRID_NM, values)))
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"].copy().align(shape)
    return colour.sd_to_XYZ(sd, cmfs=cmfs, method="Integration") / 100.0


def _kernel_estimate(kernel_runner, values: np.ndarray, seed: int) -> tuple[np.ndarray, np.ndarray]:
    table = SpectrumTable()
    table.add(Spectrum(np.zeros_like(values), name="padding"))  # a non-zero offset exercises the indexing
    offset = table.add(Spectrum(values, name="tested"))
    cmf = np.zeros((len(GRID_NM), 4), np.float32)
    cmf[:, :3] = cmf_table_normalised()
    runner = kernel_runner("testing/wavelength_estimator.cl")
    means = np.empty((ITEMS, 4), np.float32)
    args = [
        runner.buffer(table.data),
        np.int32(offset),
        runner.buffer(cmf),
        np.uint32(seed),
        np.int32(SAMPLES_PER_ITEM),
        runner.buffer(means, True),
    ]
    runner.run("estimate_spectrum_xyz", ITEMS, args, {5: means})
    xyz = means[:, :3].astype(np.float64)
    return xyz.mean(axis=0), xyz.std(axis=0, ddof=1) / np.sqrt(ITEMS)


def _colorchecker_under_d65(patch: str) -> np.ndarray:
    sd = colour.SDS_COLOURCHECKERS["ColorChecker N Ohta"][patch].copy()
    sd = sd.interpolate(colour.SpectralShape(380, 780, 1)).extrapolate(colour.SpectralShape(360, 830, 1))
    return np.asarray(sd[GRID_NM]) * d65_normalised().values


@pytest.mark.parametrize("case", ["D65", "dark skin", "blue", "orange yellow"])
def test_estimator_converges_to_colour_science(kernel_runner, case):
    values = d65_normalised().values if case == "D65" else _colorchecker_under_d65(case)
    mean, standard_error = _kernel_estimate(kernel_runner, values, seed=11)
    expected = _colour_xyz(values)
    assert np.all(standard_error < 0.01 * np.abs(expected) + 1e-6), "the estimate should be tight"
    assert np.all(np.abs(mean - expected) < 4 * standard_error), (mean, expected, standard_error)


def _analytic_visible_pdf(lam: np.ndarray) -> np.ndarray:
    """p(λ) = b / (cosh²(b (λ − 538)) (tanh(b (830 − 538)) − tanh(b (360 − 538)))), in double precision, with b the
    kernel's float 0.0072."""
    b = float(np.float32(0.0072))
    span = np.tanh(b * (830 - 538)) - np.tanh(b * (360 - 538))
    return b / (np.cosh(b * (lam.astype(np.float64) - 538)) ** 2 * span)


def _sample_wavelengths(kernel_runner, u: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    runner = kernel_runner("testing/wavelength_estimator.cl")
    n = len(u)
    lam, sampled_pdf, evaluated_pdf = (np.empty(n, np.float32) for _ in range(3))
    runner.run(
        "sample_wavelength_pdf",
        n,
        [
            runner.buffer(u),
            runner.buffer(lam, True),
            runner.buffer(sampled_pdf, True),
            runner.buffer(evaluated_pdf, True),
        ],
        {1: lam, 2: sampled_pdf, 3: evaluated_pdf},
    )
    return lam, sampled_pdf, evaluated_pdf


def test_visible_pdf_integrates_to_one_and_matches_histogram(kernel_runner):
    n = 200_000
    u = ((np.arange(n) + 0.5) / n).astype(np.float32)
    lam, pdf, _ = _sample_wavelengths(kernel_runner, u)
    assert lam.min() >= 360 and lam.max() <= 830
    assert np.all(np.diff(lam) >= 0), "inverse CDF must be monotonic"
    # Stratified u: the fraction of samples in each 10 nm bin equals the pdf's integral over the bin.
    edges = np.arange(360, 831, 10.0)
    counts, _ = np.histogram(lam, bins=edges)
    order = np.argsort(lam)
    fine = np.linspace(360, 830, 47001)
    pdf_fine = np.interp(fine, lam[order], pdf[order])
    assert abs(np.trapezoid(pdf_fine, fine) - 1.0) < 2e-3
    bin_mass = np.array(
        [
            np.trapezoid(pdf_fine[(fine >= a) & (fine <= b)], fine[(fine >= a) & (fine <= b)])
            for a, b in zip(edges[:-1], edges[1:])
        ]
    )
    np.testing.assert_allclose(counts / n, bin_mass, atol=2e-4)


def test_sampled_pdf_is_the_visible_pdf_at_the_sampled_wavelength(kernel_runner):
    """The pdf the estimator divides by (computed from the CDF value, not from λ) and p(λ) evaluated at the λ the
    sampler returned both equal the analytic pdf at that λ, to float rounding; u spans [0, 1) including its ends."""
    u = np.concatenate(
        [
            np.linspace(0, 1, 100_001, dtype=np.float32)[:-1],
            np.array([np.nextafter(np.float32(1), np.float32(0))], np.float32),
        ]
    )
    lam, sampled_pdf, evaluated_pdf = _sample_wavelengths(kernel_runner, u)
    expected = _analytic_visible_pdf(lam)
    np.testing.assert_allclose(sampled_pdf, expected, rtol=1e-5)
    np.testing.assert_allclose(evaluated_pdf, expected, rtol=1e-5)
    assert lam[0] == pytest.approx(360, abs=1e-3) and lam[-1] == pytest.approx(830, abs=1e-3)


@pytest.mark.parametrize("observers", [("CIE 1964 10°",), ("CIE 2012 2°", "CIE 2012 10°")])
def test_tabulated_sampler_inverts_the_films_cdf(kernel_runner, observers):
    """The film's tabulated sampler: λ(u) lands where the piecewise-constant pdf's CDF (built here in double
    precision from the host's pdf) equals u, and the pdf it reports is that pdf on λ's interval."""
    from spectrace.film.response import FilmResponse

    response = FilmResponse(observer=observers[0], observers=observers[1:])
    runner = kernel_runner("testing/wavelength_estimator.cl", response.defines())
    n = 100_000
    u = ((np.arange(n) + 0.5) / n).astype(np.float32)
    lam, pdf = np.empty(n, np.float32), np.empty(n, np.float32)
    table = response.device_table()
    responses = np.int32(len(response.channel_names))
    args = [runner.buffer(table), responses, runner.buffer(u), runner.buffer(lam, True), runner.buffer(pdf, True)]
    runner.run("sample_film_wavelength_pdf", n, args, {3: lam, 4: pdf})
    density = response.sampling_pdf()  # per 1 nm interval of the grid, before rounding to float32
    cdf = np.concatenate([[0.0], np.cumsum(density)]) / density.sum()
    assert np.all(np.diff(lam) >= 0) and lam.min() >= GRID_NM[0] and lam.max() <= GRID_NM[-1]
    np.testing.assert_allclose(np.interp(lam.astype(np.float64), GRID_NM, cdf), u, atol=2e-6)
    # The kernel's pdf is the slope of its float32 CDF: ~6e-8 absolute per node near 1, on interval masses of at
    # least 0.1/470 (the uniform part), hence rtol 5e-4. A λ on a node may report either neighbouring interval.
    normalised = density / density.sum()
    interval = np.floor(lam - GRID_NM[0]).astype(int)
    below = normalised[np.clip(interval - 1, 0, len(density) - 1)]
    at = normalised[np.clip(interval, 0, len(density) - 1)]
    on_node = lam == np.floor(lam)
    matches = np.isclose(pdf, at, rtol=5e-4, atol=0) | (on_node & np.isclose(pdf, below, rtol=5e-4, atol=0))
    assert matches.all(), (lam[~matches][:5], pdf[~matches][:5], at[~matches][:5])
