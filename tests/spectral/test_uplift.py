"""RGB uplift (Jakob & Hanika 2019) checked through colour-science's colorimetry and fitting code."""

import colour
import numpy as np
import pytest
from colour.recovery import find_coefficients_Jakob2019, sd_Jakob2019
from hypothesis import given, settings
from hypothesis import strategies as st

from spectrace.errors import SpectraceError
from spectrace.spectral import uplift
from spectrace.spectral.colorimetry import XYZ_TO_LINEAR_SRGB, reflectance_to_xyz, spectrum_to_xyz, xyz_to_xy
from spectrace.spectral.grid import GRID_NM
from spectrace.spectral.illuminants import cie_illuminant
from spectrace.spectral.uplift import illuminant_coefficients, uplift_illuminant, uplift_reflectance

pytestmark = pytest.mark.filterwarnings("ignore:Aligning")  # colour-science resampling notices

CMFS = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
D65 = colour.SDS_ILLUMINANTS["D65"]
GRID_SHAPE = colour.SpectralShape(360, 830, 1)


def colorchecker_linear_srgb() -> dict[str, np.ndarray]:
    """colour-science's ColorChecker 24 (X-Rite, after November 2014; xyY under D50) as linear sRGB.

    Bradford-adapted to D65. One patch is slightly outside sRGB: "cyan" has R = -0.044, clipped to 0.
    """
    checker = colour.CCS_COLOURCHECKERS["ColorChecker24 - After November 2014"]
    xyz = colour.xyY_to_XYZ(np.array(list(checker.data.values())))
    rgb = colour.XYZ_to_RGB(
        xyz, "sRGB", illuminant=checker.illuminant, chromatic_adaptation_transform="Bradford", apply_cctf_encoding=False
    )
    assert (rgb < 0).sum() == 1 and rgb.min() > -0.05 and rgb.max() < 1  # only cyan's red channel is out
    return dict(zip(checker.data.keys(), np.clip(rgb, 0.0, 1.0)))


COLORCHECKER = colorchecker_linear_srgb()


def colour_science_linear_srgb_under_d65(values: np.ndarray) -> np.ndarray:
    """Linear sRGB of a reflectance on our grid, with XYZ from colour-science (100 * sum(R E cmf) / sum(E ybar))."""
    sd = colour.SpectralDistribution(values, GRID_NM)
    return XYZ_TO_LINEAR_SRGB @ (colour.sd_to_XYZ(sd, CMFS, D65, method="Integration") / 100)


def colour_science_linear_srgb_of_emission(values: np.ndarray) -> np.ndarray:
    """Linear sRGB of a radiance on our grid; colour-science's equal-energy normalisation is our film XYZ."""
    sd = colour.SpectralDistribution(values, GRID_NM)
    return XYZ_TO_LINEAR_SRGB @ (colour.sd_to_XYZ(sd, CMFS, method="Integration") / 100)


@pytest.mark.parametrize("patch", list(COLORCHECKER))
def test_colorchecker_round_trip_through_colour_science(patch):
    rgb = COLORCHECKER[patch]
    spectrum, _ = uplift_reflectance(rgb)
    assert spectrum.min() >= 0.0 and spectrum.max() <= 1.0
    np.testing.assert_allclose(colour_science_linear_srgb_under_d65(spectrum.values), rgb, atol=0.01)
    # In the renderer's own integration (which colour-science matches to ~1e-3 in test_colorimetry) the fit is exact.
    ours = XYZ_TO_LINEAR_SRGB @ reflectance_to_xyz(spectrum, cie_illuminant("D65"))
    np.testing.assert_allclose(ours, rgb, atol=1e-6)


def test_fits_are_cached():
    first = uplift_reflectance((0.2, 0.4, 0.6))
    assert uplift_reflectance([0.2, 0.4, 0.6 + 1e-9]) is first


@pytest.mark.parametrize("rgb", [(0.6, 0.2, 0.1), (0.1, 0.7, 0.3), (0.2, 0.3, 0.8)])
def test_spectrum_is_close_to_colour_science_fit(rgb):
    # Same model, independent solver: colour-science stops at Delta E ~0.02, so the spectra agree closely
    # but not exactly (a metamer of the same colour would differ by much more than 0.02).
    target_xyz = np.linalg.inv(XYZ_TO_LINEAR_SRGB) @ np.array(rgb)
    reference_coefficients, _ = find_coefficients_Jakob2019(target_xyz, CMFS, D65)
    reference = sd_Jakob2019(reference_coefficients, GRID_SHAPE).values
    spectrum, _ = uplift_reflectance(rgb)
    assert np.abs(spectrum.values - reference).max() < 0.02


def test_coefficients_are_for_wavelength_in_nm():
    spectrum, coefficients = uplift_reflectance((0.7, 0.4, 0.1))
    c0, c1, c2 = coefficients
    x = c0 * GRID_NM**2 + c1 * GRID_NM + c2
    np.testing.assert_allclose(spectrum.values, 0.5 + x / (2 * np.sqrt(1 + x * x)), atol=1e-12)
    # colour-science's model evaluation uses lambda in nm too.
    np.testing.assert_allclose(spectrum.values, sd_Jakob2019(coefficients, GRID_SHAPE).values, atol=1e-12)


@settings(max_examples=200, deadline=None)
@given(st.tuples(*[st.floats(0.0, 1.0, allow_nan=False)] * 3))
def test_any_rgb_in_the_cube_gives_a_bounded_spectrum_that_round_trips(rgb):
    spectrum, _ = uplift_reflectance(rgb)
    assert spectrum.min() >= 0.0 and spectrum.max() <= 1.0
    back = XYZ_TO_LINEAR_SRGB @ reflectance_to_xyz(spectrum, cie_illuminant("D65"))
    # 1e-4: white maps to the constant 1, whose sRGB through the lecture matrix is (1.00001, 0.99999, 1.00008).
    np.testing.assert_allclose(back, np.round(rgb, uplift.RGB_CACHE_DECIMALS), atol=1e-4)


def test_black_and_white_are_constants():
    black, black_coefficients = uplift_reflectance((0, 0, 0))
    white, white_coefficients = uplift_reflectance((1.0, 1.0, 1.0))
    assert black.max() == 0.0 and white.min() == 1.0
    # float32, as in the kernels, saturates the sigmoid exactly.
    for coefficients, expected in ((black_coefficients, 0.0), (white_coefficients, 1.0)):
        x = np.float32(coefficients[2])
        assert np.float32(0.5) + x / (np.float32(2) * np.sqrt(np.float32(1) + x * x)) == np.float32(expected)


@pytest.mark.parametrize(
    "bad", [(1.2, 0.5, 0.5), (-0.01, 0.5, 0.5), (0.5, float("nan"), 0.5), (0.5, 0.5), "red", (True, 0, 0)]
)
def test_invalid_reflectance_raises_naming_where(bad):
    with pytest.raises(SpectraceError) as error:
        uplift_reflectance(bad, where="scene.toml: materials.wall.rgb")
    assert error.value.where == "scene.toml: materials.wall.rgb"


def test_white_emission_is_d65_with_unit_y():
    xyz = spectrum_to_xyz(uplift_illuminant((1, 1, 1)))
    assert xyz[1] == pytest.approx(1.0, abs=1e-4)
    np.testing.assert_allclose(xyz_to_xy(xyz), [0.3127, 0.3290], atol=1e-3)
    reference_xy = colour.XYZ_to_xy(colour.sd_to_XYZ(D65, CMFS, method="Integration"))
    np.testing.assert_allclose(xyz_to_xy(xyz), reference_xy, atol=1e-4)


@pytest.mark.parametrize("rgb", [(1, 1, 1), (0.8, 0.3, 0.1), (0.05, 0.9, 0.2), (0, 0, 0.5), (12.0, 4.0, 1.5)])
def test_emission_reproduces_its_rgb(rgb):
    emission = uplift_illuminant(rgb)
    assert emission.min() >= 0.0
    np.testing.assert_allclose(colour_science_linear_srgb_of_emission(emission.values), rgb, atol=0.01 * max(rgb))


def test_emission_scale_and_black():
    scaled = uplift_illuminant((0.3, 0.6, 0.9), scale=4.0)
    np.testing.assert_allclose(scaled.values, 4.0 * uplift_illuminant((0.3, 0.6, 0.9)).values)
    assert uplift_illuminant((0, 0, 0)).max() == 0.0
    assert illuminant_coefficients((0, 0, 0))[1] == 0.0


def test_negative_emission_raises():
    with pytest.raises(SpectraceError, match="negative"):
        uplift_illuminant((1.0, -0.1, 0.0), where="scene.toml: lights[0].rgb")
