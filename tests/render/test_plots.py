"""Plots: the luminance unit against colour-science's photometry, the false-colour scale against the colour map
itself, and the `spectra` commands and `render --false-color` as a user runs them."""

import json

import colour
import matplotlib
import numpy as np
import pytest
from PIL import Image as PILImage

from cli_runner import render_cornell_box
from cli_runner import run_spectrace as _run
from spectrace.errors import SpectraceError
from spectrace.plots import (
    FALSE_COLOUR_MAP,
    default_limits,
    false_colour,
    luminance_cd_m2,
    plot_false_colour_luminance,
    plot_spectra,
)
from spectrace.resources import scenes_dir
from spectrace.spectral import Spectrum, library_spectrum, spectrum_to_xyz

pytestmark = pytest.mark.filterwarnings("ignore:Aligning")


def test_luminance_is_photometric():
    # A constant spectral radiance of 1 W/(m² sr nm) over 360-830 nm: colour-science's luminous flux function
    # (K_m = 683 lm/W times the integral of the CIE 1924 photopic V(λ) = ȳ) gives its luminance in cd/m².
    constant = colour.SpectralDistribution(dict.fromkeys(range(360, 831), 1.0))
    expected = colour.luminous_flux(constant, K_m=683)
    film_xyz = spectrum_to_xyz(Spectrum.constant(1.0))
    assert luminance_cd_m2(film_xyz) == pytest.approx(expected, rel=1e-3)


def test_false_colour_follows_the_colour_map():
    low, high = 1.0, 1e4
    values = np.array([[0.0, low, 100.0, high, 1e6]])
    rgba = false_colour(values, (low, high), scale="log")
    cmap = matplotlib.colormaps[FALSE_COLOUR_MAP]
    np.testing.assert_allclose(rgba[0, 1], cmap(0.0))
    np.testing.assert_allclose(rgba[0, 2], cmap(0.5))  # 100 is half way between 1 and 10^4 in log10
    np.testing.assert_allclose(rgba[0, 3], cmap(1.0))
    np.testing.assert_allclose(rgba[0, 4], cmap(1.0))  # above the range: the top colour
    np.testing.assert_allclose(rgba[0, 0], (0, 0, 0, 1))  # no light: black
    linear = false_colour(values, (0.0, 200.0), scale="linear")
    np.testing.assert_allclose(linear[0, 2], cmap(0.5))


def test_default_limits():
    values = np.geomspace(1.0, 1e8, 10001)
    low, high = default_limits(values, "log")
    assert high == pytest.approx(np.percentile(values, 99.9)) and low == pytest.approx(high / 1e4)
    assert default_limits(values, "linear")[0] == 0.0


def test_false_colour_map_file(tmp_path):
    xyz = np.zeros((6, 8, 3))
    xyz[..., 1] = np.linspace(0.001, 1.0, 48).reshape(6, 8)
    out = tmp_path / "map.png"
    low, high = plot_false_colour_luminance(xyz, out, scale="linear")
    assert (low, high) == (0.0, pytest.approx(np.percentile(luminance_cd_m2(xyz), 99.9)))
    with PILImage.open(out) as figure:
        assert figure.size[0] > 100 and figure.size[1] > 100
    with pytest.raises(SpectraceError):
        plot_false_colour_luminance(xyz, tmp_path / "map.jpg")


def test_plot_spectra_file(tmp_path):
    out = tmp_path / "spectra.svg"
    plot_spectra({"D65": library_spectrum("cie:D65"), "A": library_spectrum("cie:A")}, out, normalise=True)
    assert out.read_text().lstrip().startswith("<?xml")
    with pytest.raises(SpectraceError):
        plot_spectra([], tmp_path / "none.png")


@pytest.mark.slow
@pytest.mark.subprocess
def test_spectra_commands(tmp_path):
    scene = str(scenes_dir() / "cornell_box.toml")
    listing = _run("spectra", "list", "--scene", scene, "--json")
    assert listing.returncode == 0, listing.stderr
    data = json.loads(listing.stdout)
    assert "cie:D65" in data["library"] and "cornell_box/light" in data["library"]
    # The scene's white wall: its measured reflectance (spectra/cornell_box) as the scene uses it.
    assert data["scene"]["materials.white.reflectance"]["max"] == pytest.approx(
        library_spectrum("cornell_box/reflectance:white").max()
    )
    out = tmp_path / "walls.png"
    result = _run("spectra", "plot", "materials.red.reflectance", "cie:D65", "--scene", scene, "-o", str(out))
    assert result.returncode == 0, result.stderr
    with PILImage.open(out) as figure:
        assert figure.format == "PNG"
    unknown = _run("spectra", "plot", "cie:D66", "-o", str(out))
    assert unknown.returncode == 2 and "did you mean 'cie:D65'" in unknown.stderr and "Traceback" not in unknown.stderr


@pytest.mark.subprocess
@pytest.mark.slow
def test_render_false_colour(tmp_path):
    out, figure = tmp_path / "box.exr", tmp_path / "luminance.png"
    result = _run(
        *render_cornell_box(out, 1, 8, 6),
        "--false-color",
        str(figure),
        "--false-color-scale",
        "linear",
    )
    assert result.returncode == 0, result.stderr
    assert "cd/m²" in result.stderr
    with PILImage.open(figure) as image:
        assert image.format == "PNG"
