"""`texel_spectra = "smooth"`: each environment-map texel emits the smooth illuminant uplift of its own colour (a
sigmoid-polynomial reflectance of rgb / (2 max), times 2 max, times D65: pbrt-v4's RGBIlluminantSpectrum, Mitsuba 3's
spectral envmap), rather than the three primaries' uplifts weighted by its channels. Both show the texel's colour;
a coloured surface reflects them differently. Checked against the closed form of each texel's spectrum
(`uplift_illuminant` of its colour, the one-colour fit), at single wavelengths and as the film colour of a coloured
plate, and against Mitsuba 3 rendering the same XML."""

import numpy as np
import pytest
from tests.lights.test_environment_map import quadrature_irradiance

from replica_agreement import assert_renders_like_mitsuba, spectrace_replicas
from scene_text import camera_film, mitsuba_envmap_over_plate
from spectrace.engine.meters import IrradianceMeter, measure
from spectrace.errors import SpectraceError
from spectrace.io.exr import write_exr
from spectrace.lights.envmap import smooth_texels
from spectrace.scene import load_scene
from spectrace.scene.model import Camera, EnvironmentMap, Scene
from spectrace.spectral.colorimetry import XYZ_TO_LINEAR_SRGB, spectrum_to_xyz
from spectrace.spectral.grid import GRID_NM
from spectrace.spectral.illuminants import d65_normalised
from spectrace.spectral.uplift import sigmoid, uplift_illuminant, uplift_reflectance

SKY = (19.0, 10.7, 6.8)  # an orange sky, far from grey: the two texel spectra differ most on a coloured surface
BLUE = (0.2, 0.25, 0.7)


def _primaries_spectrum(rgb) -> np.ndarray:
    return np.asarray(rgb, float) @ np.array([uplift_illuminant(p).values for p in np.eye(3)])


def _few_colours(height: int = 8, width: int = 16) -> np.ndarray:
    """A map of four colours in large blocks: the zenith's quarter of the rows, two halves of the rest of the upper
    sky, the ground."""
    rgb = np.empty((height, width, 3), np.float32)
    rgb[: height // 4] = (3.0, 5.0, 9.0)
    rgb[height // 4 : height // 2, : width // 2] = SKY
    rgb[height // 4 : height // 2, width // 2 :] = (0.5, 6.0, 1.0)
    rgb[height // 2 :] = (1.0, 0.8, 0.6)
    return rgb


def test_smooth_texels_show_their_colour():
    """The device's numbers for a texel (float32 dimensionless coefficients and multiplier, times D65) give a
    spectrum whose linear sRGB is the texel's, within 1 % of its largest channel, bright, dark and saturated."""
    colours = np.array([SKY, BLUE, (0.01, 0.02, 0.005), (1.0, 1.0, 1.0), (0.0, 3.0, 0.0), (250.0, 40.0, 90.0)])
    texels = smooth_texels(colours).astype(np.float64)
    t = (GRID_NM - (GRID_NM[0] + GRID_NM[-1]) / 2) / ((GRID_NM[-1] - GRID_NM[0]) / 2)
    for texel, rgb in zip(texels, colours):
        spectrum = texel[3] * sigmoid((texel[0] * t + texel[1]) * t + texel[2]) * d65_normalised().values
        shown = XYZ_TO_LINEAR_SRGB @ spectrum_to_xyz(spectrum)
        np.testing.assert_allclose(shown, rgb, atol=0.01 * rgb.max())


@pytest.mark.parametrize("normal", [(0.0, 1.0, 0.0), (0.6, -0.2, -0.77)])
def test_smooth_map_irradiance_matches_quadrature_of_each_texels_uplift(device, normal):
    """Irradiance at single wavelengths from a map of a few colours equals the quadrature over its texels, each
    emitting uplift_illuminant of its colour; the primaries' sum is far off at 600 nm (what the test would catch)."""
    rgb = _few_colours()
    normal = tuple(np.asarray(normal) / np.linalg.norm(normal))
    scene = Scene(
        camera=Camera(origin=(0.0, 0.0, -1.0), target=(0.0, 0.0, 0.0)),
        width=1,
        height=1,
        shapes=[],
        lights=[EnvironmentMap(rgb, 0.5, texel_spectra="smooth")],
    )
    wavelengths = [450.0, 600.0]
    reading = measure(
        scene, IrradianceMeter((0.0, 0.0, 0.0), normal), wavelengths_nm=wavelengths, streams=64, samples_per_item=64
    )
    colours = {tuple(c) for c in rgb.reshape(-1, 3).tolist()}
    spectra = {c: uplift_illuminant(c).values for c in colours}
    for i, nm in enumerate(wavelengths):
        radiance = np.array([[np.interp(nm, GRID_NM, spectra[tuple(c)]) for c in row] for row in rgb.tolist()])
        expected = quadrature_irradiance(0.5 * radiance, normal)
        value, standard_error = reading.spectral[i], reading.spectral_standard_error[i]
        assert standard_error < 0.02 * expected
        assert abs(value - expected) < 4 * standard_error + 2e-3 * expected, (nm, value, expected, standard_error)
    primaries = np.array([[np.interp(600.0, GRID_NM, _primaries_spectrum(c)) for c in row] for row in rgb.tolist()])
    assert abs(quadrature_irradiance(0.5 * primaries, normal) / reading.spectral[1] - 1) > 0.2


def _plate_scene(tmp_path, texel_spectra: str):
    """A blue diffuse plate facing +z under a uniform map whose zenith is +z, seen from above: each pixel's
    radiance is ρ(λ) L(λ) (the plate sees the upper hemisphere, all sky)."""
    write_exr(tmp_path / "sky.exr", np.broadcast_to(np.float32(SKY), (4, 8, 3)).copy(), None, {})
    path = tmp_path / f"{texel_spectra}.toml"
    path.write_text(
        camera_film(origin="[0, 0, 5]", target="[0, 0, 0]", fov="10", width="4", height="4")
        + f"""
[materials.blue]
type = "diffuse"
reflectance = {{ rgb = [{BLUE[0]}, {BLUE[1]}, {BLUE[2]}] }}

[[shapes]]
type = "rectangle"
material = "blue"
transform = [{{ scale = [2, 2, 1] }}]

[[lights]]
type = "envmap"
file = "sky.exr"
up = [0, 0, 1]
front = [1, 0, 0]
texel_spectra = "{texel_spectra}"
"""
    )
    return load_scene(path)


@pytest.mark.parametrize(
    ("integrator", "kernel"),
    [("path", "megakernel"), ("path", "wavefront"), ("bdpt", "megakernel"), ("sppm", "megakernel")],
)
def test_coloured_plate_under_a_uniform_map_renders_the_closed_form_of_its_texel_spectrum(
    tmp_path, device, integrator, kernel
):
    """Film XYZ of the plate = ∫ ρ(λ) L(λ) (x̄, ȳ, z̄) dλ / ∫ ȳ dλ, with L the texel's spectrum of each kind, within
    4 standard errors (from 8 replicas), from camera paths (both kernel shapes) and from light paths; the two kinds'
    closed forms are more than 6 of them apart."""
    import dataclasses

    from spectrace.engine.wavefront import make_renderer

    reflectance = uplift_reflectance(BLUE)[0].values
    expected = {
        "smooth": spectrum_to_xyz(reflectance * uplift_illuminant(SKY).values),
        "primaries": spectrum_to_xyz(reflectance * _primaries_spectrum(SKY)),
    }
    for texel_spectra, xyz in expected.items():
        scene = dataclasses.replace(_plate_scene(tmp_path, texel_spectra), integrator=integrator)
        replicas = spectrace_replicas(make_renderer(scene, device, kernel), 8, 64).mean(axis=(1, 2))
        mean = replicas.mean(axis=0)
        standard_error = replicas.std(axis=0, ddof=1) / np.sqrt(len(replicas))
        assert np.all(np.abs(mean - xyz) < 4 * standard_error), (texel_spectra, mean, xyz, standard_error)
        other = expected["primaries" if texel_spectra == "smooth" else "smooth"]
        assert np.max(np.abs(other - xyz) / standard_error) > 6


def test_texel_spectra_in_a_scene_file(tmp_path):
    """The key reaches the light; another word is refused, naming the key path."""
    scene = _plate_scene(tmp_path, "smooth")
    assert scene.lights[0].texel_spectra == "smooth"
    path = tmp_path / "smooth.toml"
    path.write_text(path.read_text().replace('"smooth"', '"spectral"'))
    with pytest.raises(SpectraceError, match=r"lights\[0\]\.texel_spectra.*primaries, smooth"):
        load_scene(path)


def _mitsuba_xml(folder, rgb: np.ndarray, size: int = 8):
    write_exr(folder / "sky.exr", rgb, None, {})
    path = folder / "blue_plate.xml"
    path.write_text(mitsuba_envmap_over_plate("sky.exr", f"{BLUE[0]}, {BLUE[1]}, {BLUE[2]}", size))
    return path


@pytest.mark.peer
@pytest.mark.parametrize("sky", ["uniform", "few colours"])
def test_blue_plate_under_a_coloured_map_renders_like_mitsuba(tmp_path, device, mitsuba_scalar_spectral, sky):
    """Both renderers, spectral, 8 replicas each: 4 x 4-pixel blocks and the image agree within 5 standard errors
    (tests/replica_agreement.py); with the primaries' texels the uniform sky's plate is 4.9 % redder than
    Mitsuba's."""
    from spectrace.interop.mitsuba import mitsuba_scene_data

    # Many texels, so that the bands where Mitsuba interpolates between colours (coefficients and scales apart;
    # spectrace looks up the nearest texel) hold little of the light.
    rgb = np.broadcast_to(np.float32(SKY), (9, 16, 3)).copy() if sky == "uniform" else _few_colours(65, 128)
    path = _mitsuba_xml(tmp_path, rgb)
    assert mitsuba_scene_data(path)[0]["lights"][0]["texel_spectra"] == "smooth"
    assert_renders_like_mitsuba(mitsuba_scalar_spectral, path, device, 8, 64, 4)
