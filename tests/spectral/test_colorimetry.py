"""The renderer's colorimetry against colour-science and published constants."""

import colour
import numpy as np
import pytest

from spectrace.spectral.colorimetry import (
    CIE_Y_INTEGRAL,
    LINEAR_SRGB_TO_XYZ,
    XYZ_TO_LINEAR_SRGB,
    cmf_table_normalised,
    linear_srgb_to_xyz,
    reflectance_to_xyz,
    spectrum_to_xyz,
    srgb_decode,
    srgb_encode,
    xyz_to_linear_srgb,
    xyz_to_xy,
)
from spectrace.spectral.grid import GRID_NM, GRID_SIZE
from spectrace.spectral.illuminants import cie_illuminant, d65_normalised
from spectrace.spectral.spectrum import Spectrum
from spectrace.spectral.spectrum_io import spectrum_from_colour

# colour-science reports each time it resamples a distribution onto the CMFs' shape: expected here.
pytestmark = pytest.mark.filterwarnings("ignore:Aligning")

CMFS = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
D65 = colour.SDS_ILLUMINANTS["D65"]


def colour_emission_xyz(sd: colour.SpectralDistribution) -> np.ndarray:
    """colour-science's XYZ of an emission in our normalisation.

    With no illuminant, `sd_to_XYZ` (method "Integration") weights by an equal-energy illuminant and
    uses k = 100 / sum(ybar dlambda), so XYZ / 100 = integral(L cmf) / integral(ybar): our film XYZ
    (up to its rectangle rule where we use the trapezoid one; the end samples weigh ~3e-4 of Z).
    """
    return colour.sd_to_XYZ(sd, CMFS, method="Integration") / 100


def test_lecture_xyz_to_srgb_matrix_matches_colour_science():
    srgb = colour.RGB_COLOURSPACES["sRGB"]
    np.testing.assert_allclose(XYZ_TO_LINEAR_SRGB, srgb.matrix_XYZ_to_RGB, atol=1e-3)
    np.testing.assert_allclose(LINEAR_SRGB_TO_XYZ, srgb.matrix_RGB_to_XYZ, atol=1e-3)


def test_lecture_matrices_are_inverse_of_each_other():
    np.testing.assert_allclose(XYZ_TO_LINEAR_SRGB @ LINEAR_SRGB_TO_XYZ, np.eye(3), atol=2e-6)


def test_xyz_srgb_conversions_work_on_the_last_axis():
    xyz = np.random.default_rng(3).random((4, 5, 3))
    rgb = xyz_to_linear_srgb(xyz)
    assert rgb.shape == (4, 5, 3)
    np.testing.assert_allclose(rgb[2, 3], XYZ_TO_LINEAR_SRGB @ xyz[2, 3])
    np.testing.assert_allclose(linear_srgb_to_xyz(rgb), xyz, atol=1e-5)


def test_srgb_transfer_curve_matches_colour_science():
    linear = np.concatenate([np.linspace(-0.05, 1.2, 500), [0.0, 0.0031308, 1.0]])
    np.testing.assert_allclose(srgb_encode(linear), colour.cctf_encoding(linear, "sRGB"), atol=1e-12)
    encoded = np.concatenate([np.linspace(-0.05, 1.2, 500), [0.0, 0.04045, 1.0]])
    # atol 1e-8: at exactly 0.04045 IEC 61966-2-1 takes the linear segment, colour-science the power law
    # (its threshold is the encoded 0.0031308, 0.040448); the two differ there by 2.3e-9.
    np.testing.assert_allclose(srgb_decode(encoded), colour.cctf_decoding(encoded, "sRGB"), rtol=0, atol=1e-8)
    np.testing.assert_allclose(srgb_decode(srgb_encode(linear)), linear, atol=1e-12)


def test_y_integral_matches_pbrt_v4_constant():
    # pbrt-v4 src/pbrt/util/spectrum.h: CIE_Y_integral = 106.856895 (same CMFs, 1 nm, 360..830 nm).
    assert pytest.approx(106.856895, rel=1e-6) == CIE_Y_INTEGRAL


def test_constant_unit_spectrum_has_y_one_and_equal_energy_chromaticity():
    xyz = spectrum_to_xyz(np.ones(GRID_SIZE))
    assert xyz[1] == pytest.approx(1.0, abs=1e-12)
    reference = colour_emission_xyz(colour.SpectralDistribution(np.ones(GRID_SIZE), GRID_NM))
    np.testing.assert_allclose(xyz, reference, rtol=1e-3)
    np.testing.assert_allclose(xyz_to_xy(xyz), [1 / 3, 1 / 3], atol=1e-3)  # illuminant E


def test_cmf_table_is_float32_cmfs_over_y_integral():
    table = cmf_table_normalised()
    assert table.dtype == np.float32 and table.shape == (GRID_SIZE, 3)
    for wavelength_nm in (400, 555, 600, 700):
        expected = np.asarray(CMFS[wavelength_nm]) / 106.856895
        np.testing.assert_allclose(table[wavelength_nm - 360], expected, rtol=1e-5)
    # ybar / integral(ybar) integrates to 1 by the trapezoid rule.
    assert np.trapezoid(table[:, 1].astype(np.float64), GRID_NM) == pytest.approx(1.0, rel=1e-6)


@pytest.mark.parametrize("name", ["D65", "A", "FL2", "LED-B3"])
def test_illuminant_xyz_matches_colour_science(name):
    ours = spectrum_to_xyz(cie_illuminant(name))
    reference = colour_emission_xyz(colour.SDS_ILLUMINANTS[name])
    np.testing.assert_allclose(ours, reference, rtol=1e-3)


def test_normalised_d65_has_y_one_and_colour_science_chromaticity():
    ours = spectrum_to_xyz(d65_normalised())
    reference = colour_emission_xyz(D65)
    assert ours[1] == pytest.approx(1.0, abs=1e-12)
    np.testing.assert_allclose(ours, reference / reference[1], rtol=1e-3)
    np.testing.assert_allclose(xyz_to_xy(ours), [0.3127, 0.3290], atol=1e-4)  # CIE 15:2004 D65 white point


def _linearly_interpolated(sd: colour.SpectralDistribution) -> colour.SpectralDistribution:
    # Our loaders join samples linearly (as the kernels do); colour-science's default for evenly spaced
    # reflectance data is Sprague, which alone moves XYZ of these patches by up to 2e-3.
    sd = sd.copy()
    sd.interpolator = colour.LinearInterpolator
    return sd


@pytest.mark.parametrize("patch", ["dark skin", "blue", "yellow", "red", "white 9.5 (.05 D)", "black 2 (1.5 D)"])
def test_colorchecker_reflectance_under_d65_matches_colour_science(patch):
    sd = _linearly_interpolated(colour.SDS_COLOURCHECKERS["ColorChecker N Ohta"][patch])
    # colour-science: XYZ = 100 * sum(R D65 cmf) / sum(D65 ybar); ours has a perfect white at Y = 1.
    reference = colour.sd_to_XYZ(sd, CMFS, D65, method="Integration") / 100
    ours = reflectance_to_xyz(spectrum_from_colour(sd), cie_illuminant("D65"))
    np.testing.assert_allclose(ours, reference, rtol=1e-3)


def test_reflectance_xyz_is_film_xyz_of_the_lit_spectrum_over_the_illuminant_y():
    reflectance = Spectrum(np.linspace(0.1, 0.9, GRID_SIZE))
    lit = reflectance.values * d65_normalised().values  # film Y of d65_normalised is 1
    np.testing.assert_allclose(reflectance_to_xyz(reflectance, cie_illuminant("D65")), spectrum_to_xyz(lit), rtol=1e-12)
