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
    args = [runner.buffer(table.data), np.int32(offset), runner.buffer(cmf), np.uint32(seed),
            np.int32(SAMPLES_PER_ITEM), runner.buffer(means, True)]
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


def test_visible_pdf_integrates_to_one_and_matches_histogram(kernel_runner):
    runner = kernel_runner("testing/wavelength_estimator.cl")
    n = 200_000
    u = ((np.arange(n) + 0.5) / n).astype(np.float32)
    lam = np.empty(n, np.float32)
    pdf = np.empty(n, np.float32)
    runner.run("sample_wavelength_pdf", n, [runner.buffer(u), runner.buffer(lam, True), runner.buffer(pdf, True)],
               {1: lam, 2: pdf})
    assert lam.min() >= 360 and lam.max() <= 830
    assert np.all(np.diff(lam) >= 0), "inverse CDF must be monotonic"
    # Stratified u: the fraction of samples in each 10 nm bin equals the pdf's integral over the bin.
    edges = np.arange(360, 831, 10.0)
    counts, _ = np.histogram(lam, bins=edges)
    order = np.argsort(lam)
    fine = np.linspace(360, 830, 47001)
    pdf_fine = np.interp(fine, lam[order], pdf[order])
    assert abs(np.trapezoid(pdf_fine, fine) - 1.0) < 2e-3
    bin_mass = np.array([np.trapezoid(pdf_fine[(fine >= a) & (fine <= b)], fine[(fine >= a) & (fine <= b)])
                         for a, b in zip(edges[:-1], edges[1:])])
    np.testing.assert_allclose(counts / n, bin_mass, atol=2e-4)
