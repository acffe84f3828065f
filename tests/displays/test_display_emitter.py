"""Display emitters in scenes: a screen showing an RGB triple emits r·R(λ) + g·G(λ) + b·B(λ) of its primaries."""

import colour
import numpy as np
import pytest

from scene_text import emitting_screen
from spectrace.displays import load_display
from spectrace.engine.renderer import Renderer
from spectrace.errors import SpectraceError
from spectrace.scene import load_scene
from spectrace.spectral.grid import GRID_NM
from stats_toolkit import assert_power, assert_within_standard_errors


def _scene(tmp_path, radiance):
    path = tmp_path / "screen.toml"
    path.write_text(emitting_screen(radiance=radiance, width=16, height=16))
    return load_scene(path)


def test_rendered_screen_matches_colour_science(device, tmp_path):
    rgb = (0.6, 0.3, 0.2)
    scene = _scene(tmp_path, 'display = "LCD-Dell_CCFL", rgb = [0.6, 0.3, 0.2]')
    y = Renderer(scene, device).render().xyz.reshape(-1, 3).astype(np.float64)
    display = load_display("LCD-Dell_CCFL")
    spectrum = sum(c * p.values for c, p in zip(rgb, display.primaries))
    sd = colour.SpectralDistribution(dict(zip(GRID_NM, spectrum)))
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"].copy().align(colour.SpectralShape(360, 830, 1))
    expected = colour.sd_to_XYZ(sd, cmfs=cmfs, method="Integration") / 100.0  # film XYZ: ∫L cmf / ∫ȳ
    mean, standard_error = y.mean(axis=0), y.std(axis=0, ddof=1) / np.sqrt(len(y))
    assert_within_standard_errors(mean, expected, standard_error, power=0.05)


def test_display_spectrum_is_linear_in_the_triple(tmp_path):
    def radiance(rgb):
        scene = _scene(tmp_path, f'display = "OLED-SonyPVM2541", rgb = {list(rgb)}')
        return scene.shapes[0].emitter.radiance.values

    np.testing.assert_allclose(
        radiance((0.5, 0.25, 0.1)) + radiance((0.2, 0.5, 0.3)), radiance((0.7, 0.75, 0.4)), rtol=1e-12, atol=1e-15
    )


def test_white_luminance_rescales_and_relative_displays_need_it(tmp_path):
    scene = _scene(tmp_path, 'display = "LCD-CCFL_HDRVDP2", rgb = [1, 1, 1], white_luminance = 80')
    values = scene.shapes[0].emitter.radiance.values
    luminance = 683.0 * np.trapezoid(
        values
        * colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
        .copy()
        .align(colour.SpectralShape(360, 830, 1))
        .values[:, 1],
        GRID_NM,
    )
    assert luminance == pytest.approx(80.0, rel=1e-3)
    with pytest.raises(SpectraceError, match="white_luminance"):
        _scene(tmp_path, 'display = "LCD-CCFL_HDRVDP2", rgb = [1, 1, 1]')
    with pytest.raises(SpectraceError, match="unknown display 'nope'"):
        _scene(tmp_path, 'display = "nope", rgb = [1, 1, 1]')


def _picture(path, pixels):
    from PIL import Image as PILImage

    PILImage.fromarray(np.asarray(pixels, np.uint8), "RGB").save(path)


def test_screen_shows_its_picture(device, tmp_path):
    """Left half of the picture red, right half blue: the rendered screen's halves have the XYZ of the display's
    red and blue primaries (the srgb encoding maps code 255 to drive 1)."""
    picture = np.zeros((4, 8, 3))
    picture[:, :4, 0] = 255
    picture[:, 4:, 2] = 255
    _picture(tmp_path / "picture.png", picture)
    scene = _scene(tmp_path, 'display = "LCD-Dell_CCFL", image = "picture.png", encoding = "srgb"')
    xyz = Renderer(scene.with_overrides(width=32, height=32), device).render().xyz.astype(np.float64)
    display = load_display("LCD-Dell_CCFL")
    # The 20° view spans x in ±0.53 at the screen; take columns well inside each half.
    for columns, primary in ((slice(2, 12), 0), (slice(20, 30), 2)):
        region = xyz[4:28, columns].reshape(-1, 3)
        expected = display.film_xyz(np.eye(3)[primary])
        mean, standard_error = region.mean(axis=0), region.std(axis=0, ddof=1) / np.sqrt(len(region))
        assert np.all(np.abs(mean - expected) < 4 * standard_error + 1e-6 * expected.max()), (mean, expected)


def test_half_lit_screen_gives_half_the_irradiance(device, tmp_path):
    """Next-event estimation samples textured screens correctly: by symmetry a meter on the screen's axis
    receives exactly half the irradiance when only one half of the picture is lit."""
    from spectrace.engine.meters import IrradianceMeter, measure

    readings = {}
    for name, lit_columns in (("full", slice(0, 8)), ("half", slice(0, 4))):
        picture = np.zeros((4, 8, 3))
        picture[:, lit_columns] = 255
        _picture(tmp_path / f"{name}.png", picture)
        scene = _scene(tmp_path, f'display = "LCD-Dell_CCFL", image = "{name}.png"')
        readings[name] = measure(
            scene,
            IrradianceMeter((0.0, 0.0, 1.0), (0.0, 0.0, -1.0)),
            wavelengths_nm=[550.0],
            streams=64,
            samples_per_item=160,
            device=device,
        )
    full, half = readings["full"], readings["half"]
    difference = full.spectral[0] / 2 - half.spectral[0]
    combined = np.hypot(full.spectral_standard_error[0] / 2, half.spectral_standard_error[0])
    assert_power(half.spectral[0], combined, what="half the display")
    assert_within_standard_errors(difference, 0.0, combined, what="full / 2 - half")


@pytest.mark.parametrize(
    "encoding, decode",
    [
        ("srgb", lambda encoded: colour.cctf_decoding(encoded, function="sRGB")),  # IEC 61966-2-1, by colour-science
        ("gamma2.2", lambda encoded: encoded**2.2),
        ("linear", lambda encoded: encoded),
    ],
)
def test_encoded_values_are_decoded_by_the_stated_curve(tmp_path, encoding, decode):
    """A triple and a picture's code values are encoded: the screen emits the primaries at the decoded drive.
    Mid-range values, where the curves differ (codes 0 and 255 decode alike under every curve)."""
    display = load_display("OLED-SonyPVM2541")
    triple = np.array([0.5, 0.25, 0.1])
    scene = _scene(tmp_path, f'display = "OLED-SonyPVM2541", rgb = {triple.tolist()}, encoding = "{encoding}"')
    np.testing.assert_allclose(
        scene.shapes[0].emitter.radiance.values, decode(triple) @ display.primaries_values, rtol=1e-12, atol=0
    )

    codes = np.array([128, 64, 26])
    _picture(tmp_path / "mid.png", np.broadcast_to(codes, (2, 3, 3)))
    scene = _scene(tmp_path, f'display = "OLED-SonyPVM2541", image = "mid.png", encoding = "{encoding}"')
    drive = scene.shapes[0].emitter.image.texture.values  # the picture is an emission texture of linear drive
    assert drive.shape == (2, 3, 3)
    np.testing.assert_allclose(drive, np.broadcast_to(decode(codes / 255.0), drive.shape), rtol=1e-6)
