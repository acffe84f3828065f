"""LCDs built from their layers (backlight × colour filters × polarisers): the fit reproduces the measured primaries'
chromaticities, with the colorimetry computed by colour-science from the files, and changing a layer moves the gamut
the way the physics says."""

import colour
import numpy as np
import pytest

from spectrace.displays import load_display
from spectrace.displays.layer_experiments import layer_variants, triangle_area, xy_to_uv_prime
from spectrace.displays.layers import fit_layer_model, parallel_polarisers_transmittance
from spectrace.resources import spectra_dir
from spectrace.spectral import GRID_NM

# The stated tolerance: each modelled primary's CIE 1931 xy within this distance of the measured one (the fits reach
# 0.0012 at worst, on the HDR-VDP CCFL LCD's blue).
XY_TOLERANCE = 0.003
# colour-science says it aligns the spectra's ranges to its CMFs': expected, the CMFs start at 360 nm
pytestmark = pytest.mark.filterwarnings("ignore:Aligning")
CMFS = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]


def _measured_xy(name: str) -> np.ndarray:
    """xy of the shipped file's columns at their own sampling, by colour-science."""
    lines = (spectra_dir() / "displays" / f"{name}.csv").read_text(encoding="utf-8").splitlines()
    rows = np.genfromtxt([line for line in lines if not line.startswith("#")], delimiter=",", names=True)
    return np.array(
        [
            colour.XYZ_to_xy(
                colour.sd_to_XYZ(
                    colour.SpectralDistribution(rows[c], rows["wavelength_nm"]),
                    cmfs=CMFS.copy().trim(colour.SpectralShape(380, 780, 1)),
                    method="Integration",
                )
            )
            for c in ("red", "green", "blue")
        ]
    )


def _model_xy(values: np.ndarray) -> np.ndarray:
    return np.array(
        [colour.XYZ_to_xy(colour.sd_to_XYZ(colour.SpectralDistribution(row, GRID_NM), cmfs=CMFS)) for row in values]
    )


def test_two_parallel_polarisers_pass_the_mueller_product():
    """(k1² + k2²)/2 against the product of two partial polarisers' Mueller matrices applied to unpolarised light."""
    for k1, k2 in ((0.9, 0.001), (0.85, 0.02), (1.0, 0.0)):
        root = np.sqrt(k1 * k2)
        polariser = 0.5 * np.array(
            [[k1 + k2, k1 - k2, 0, 0], [k1 - k2, k1 + k2, 0, 0], [0, 0, 2 * root, 0], [0, 0, 0, 2 * root]]
        )
        stokes = polariser @ polariser @ np.array([1.0, 0.0, 0.0, 0.0])
        assert parallel_polarisers_transmittance(k1, k2) == pytest.approx(stokes[0], rel=1e-12)
    assert parallel_polarisers_transmittance() == pytest.approx(0.4, abs=0.01)  # the usual figure for an LCD


@pytest.mark.slow
@pytest.mark.parametrize("name", ["LCD-Apple_WLED", "LCD-Dell_CCFL"])
def test_fitted_layers_reproduce_the_measured_primaries(name):
    fit = fit_layer_model(load_display(name))
    assert fit.model.backlight.kind == ("ccfl" if "CCFL" in name else "wled_yag")
    distances = np.linalg.norm(_model_xy(fit.model.primaries_values()) - _measured_xy(name), axis=1)
    assert np.all(distances < XY_TOLERANCE), distances
    assert fit.rms_residual < 0.03  # the spectra too, not only their chromaticities
    for colour_filter in fit.model.filters:
        transmittance = colour_filter.transmittance()
        assert transmittance.min() >= 0 and transmittance.max() <= 1


@pytest.mark.slow
def test_changing_a_layer_moves_the_gamut_as_the_physics_says():
    fit = fit_layer_model(load_display("LCD-Apple_WLED"))
    fitted, yag, qd, narrow = layer_variants(fit)
    white = fit.model.display().white_xy()
    for variant in (fitted, yag, qd, narrow):
        np.testing.assert_allclose(variant.white_xy, white, atol=1e-9)  # white balanced to the model's white
        np.testing.assert_allclose(variant.primaries_xy, variant.display.primaries_xy())
        # the areas against colour-science's u'v' and an independent polygon area
        uv = colour.xy_to_Luv_uv(variant.primaries_xy)
        (ax, ay), (bx, by) = uv[1] - uv[0], uv[2] - uv[0]
        assert variant.gamut_uv == pytest.approx(0.5 * abs(ax * by - ay * bx), rel=1e-9)
        np.testing.assert_allclose(xy_to_uv_prime(variant.primaries_xy), uv, atol=1e-12)
    assert fitted.grey_delta_e_1964 == pytest.approx(0, abs=1e-6)
    # narrow quantum-dot emission makes purer primaries than a broad phosphor through the same filters
    assert qd.gamut_xy > 1.3 * yag.gamut_xy and qd.gamut_uv > 1.3 * yag.gamut_uv
    # narrower filters: purer primaries, less light
    assert narrow.gamut_xy > fitted.gamut_xy and narrow.white_efficiency < fitted.white_efficiency
    # a different spectrum behind the same matched colour: the 10° observer and the lit chart see a difference
    assert qd.grey_delta_e_1964 > 0.5 and qd.colorchecker_max_delta_e > 1


def test_triangle_area():
    assert triangle_area(np.array([[0, 0], [1, 0], [0, 1]])) == 0.5
    assert triangle_area(np.array([[0.64, 0.33], [0.30, 0.60], [0.15, 0.06]])) == pytest.approx(0.1121, abs=1e-4)
