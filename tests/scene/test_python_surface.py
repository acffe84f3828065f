"""The Python surface a notebook meets: subpackages reachable after `import spectrace`, short reprs, scenes and
shapes that compare by value, `np.asarray(image)`, figures returned, colour-science's camera sensitivities as a
film sensor, and a film size of 0 named as the setting it is."""

import io
import os
import subprocess
import sys

import numpy as np
import pytest

import spectrace
from spectrace.resources import bundled_scene_names


@pytest.mark.subprocess
def test_interop_is_reachable_after_import_spectrace_alone():
    code = "import spectrace; print(spectrace.interop.load_mitsuba_scene.__name__, callable(spectrace.api.render))"
    result = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, env=os.environ.copy(), timeout=120
    )
    assert result.returncode == 0, result.stderr
    assert result.stdout.split() == ["load_mitsuba_scene", "True"]


@pytest.mark.parametrize("name", bundled_scene_names())
def test_a_scene_repr_is_short_and_says_its_size_and_counts(name):
    scene = spectrace.load_scene(name)
    text = repr(scene)
    assert len(text) < 300, text
    assert f"{scene.width}x{scene.height}" in text and f"{len(scene.shapes)} shapes" in text


@pytest.mark.parametrize("name", ["cornell_box", "teapot", "material_showcase", "display_lcd_vs_led"])
def test_scenes_and_shapes_compare_by_value(name):
    first, second = spectrace.load_scene(name), spectrace.load_scene(name)
    assert first is not second and first == second
    assert first.shapes[0] == second.shapes[0]
    assert first != first.with_overrides(width=first.width + 1)
    moved = first.shapes[0].mesh.vertices.copy()
    moved[0, 0] += 1e-3
    other = spectrace.Shape(
        spectrace.api.TriangleMesh(moved, first.shapes[0].mesh.faces), first.shapes[0].material, name="moved"
    )
    assert other != first.shapes[0] and other.mesh != first.shapes[0].mesh


def test_an_image_as_an_array_is_its_linear_rgb():
    # D65's chromaticity at Y = 1 is sRGB's white: linear (1, 1, 1) (IEC 61966-2-1).
    white = np.array([0.95047, 1.0, 1.08883], np.float32)
    image = spectrace.Image(xyz=np.tile(white, (3, 4, 1)), spp=1, seed=0, device="test", render_seconds=0.0)
    values = np.asarray(image)
    assert values.shape == (3, 4, 3) and values.dtype.kind == "f"
    np.testing.assert_allclose(values, 1.0, atol=2e-3)
    assert np.asarray(image, dtype=np.float64).dtype == np.float64


def test_plot_spectra_returns_a_figure_and_a_spectrum_shows_itself(tmp_path):
    from matplotlib.figure import Figure
    from PIL import Image

    from spectrace.plots import plot_spectra

    d65, a = spectrace.spectrum("cie:D65"), spectrace.spectrum("cie:A")
    figure = plot_spectra({"D65": d65, "A": a})
    assert isinstance(figure, Figure) and len(figure.axes[0].lines) == 2
    written = plot_spectra([d65], tmp_path / "d65.png")
    assert isinstance(written, Figure) and (tmp_path / "d65.png").stat().st_size > 0
    with Image.open(io.BytesIO(d65._repr_png_())) as shown:
        assert shown.format == "PNG" and shown.width > 100


@pytest.mark.parametrize(("side", "value"), [("width", 0), ("height", -2)])
def test_a_film_side_below_one_pixel_is_named_as_the_setting(side, value):
    scene = spectrace.load_scene("cornell_box").with_overrides(**{side: value})
    with pytest.raises(spectrace.SpectraceError) as failure:
        spectrace.render(scene, progress=False)
    assert str(failure.value) == f"{side} must be ≥ 1, got {value}"


def test_colour_science_camera_sensitivities_are_a_film_sensor(device, tmp_path):
    """A uniform emitter filling the view through the Nikon 5100's measured sensitivities (colour-science's
    MSDS_CAMERA_SENSITIVITIES) gives colour-science's own ∫ L s dλ per channel, within 4 standard errors."""
    colour = pytest.importorskip("colour")
    from scene_text import emitting_screen
    from spectrace.engine.renderer import Renderer
    from spectrace.scene import load_scene
    from spectrace.spectral.grid import GRID_NM

    camera = colour.MSDS_CAMERA_SENSITIVITIES["Nikon 5100 (NPL)"]
    (tmp_path / "screen.toml").write_text(
        emitting_screen(radiance='spectrum = "cie:FL2", scale = 0.01', width=16, height=16), encoding="utf-8"
    )
    scene = load_scene(tmp_path / "screen.toml")
    scene = scene.with_overrides(film_response=spectrace.FilmResponse(sensor=camera))
    image = Renderer(scene, device).render()
    radiance = colour.SpectralDistribution(dict(zip(GRID_NM, scene.shapes[0].emitter.radiance.values)))
    ones = colour.SpectralDistribution(dict(zip(GRID_NM, np.ones_like(GRID_NM))))
    for index, label in enumerate(camera.labels):
        # The sensor is zero outside its table, linear between its samples.
        curve = np.interp(GRID_NM, camera.wavelengths, camera.values[:, index], left=0.0, right=0.0)
        cmfs = colour.MultiSpectralDistributions(dict(zip(GRID_NM, np.stack([curve] * 3, axis=1))))
        expected = 100 * colour.sd_to_XYZ(radiance, cmfs=cmfs, illuminant=ones, k=1, method="Integration")[0]
        values = image.channels[f"sensor.{label}"].astype(np.float64).ravel()
        mean, error = values.mean(), values.std(ddof=1) / np.sqrt(values.size)
        assert error < 0.02 * expected and abs(mean - expected) < 4 * error, (label, mean, expected, error)
