"""Polarised area lights (emitter.polarization): a light's Stokes state, in the basis of its surface's u direction,
reaches the camera through the path's Mueller matrix, both when a camera ray meets the light and behind a sheet
polariser; checked against Malus's law and the Stokes vectors written here from Collett's conventions."""

import numpy as np
import pytest
from tests.cli_runner import run_spectrace
from tests.polarization.stokes_scenes import header, measure, polarizer, rotator
from tests.polarization.test_closed_forms import FLOOR, assert_stokes

import spectrace
from spectrace.scene.loader import load_scene


def emitter_scene(polarization: str, camera: str = "", sheet: str = "", radiance: str = "{ value = 1 }") -> str:
    """A rectangle of `radiance` in z = 0 (its u direction +x, the image's right) emitting `polarization`, seen
    from +z, behind a sheet of material table `sheet` when given."""
    text = (
        header(camera)
        + f"""
[[shapes]]
type = "rectangle"
material = "black"
emitter = {{ radiance = {radiance}, polarization = "{polarization}" }}
transform = [{{ scale = [2, 2, 1] }}]
"""
    )
    if sheet:
        text += f"""
[materials.sheet]
{sheet}

[[shapes]]
type = "rectangle"
material = "sheet"
transform = [{{ translate = [0, 0, 1] }}]
"""
    return text


def linear(angle_degrees: float) -> np.ndarray:
    a = np.radians(2 * angle_degrees)
    return np.array([1.0, np.cos(a), np.sin(a), 0.0])


@pytest.mark.parametrize("filter_angle", [0, 30, 60, 90])
def test_emitter_polarised_at_zero_follows_malus_through_the_camera_polarizer(tmp_path, filter_angle):
    camera = f"origin = [0, 0, 3]\ntarget = [0, 0, 0]\nfov = 10\npolarizer_angle = {filter_angle}"
    measured = measure(tmp_path, emitter_scene("linear 0", camera))
    assert abs(measured.image_y - np.cos(np.radians(filter_angle)) ** 2) <= 4 * measured.image_stderr + FLOOR
    assert_stokes(measured, linear(0))


@pytest.mark.parametrize("filter_angle", [0, 45, 90])
def test_unpolarised_and_circular_emitters_give_half_through_the_camera_polarizer(tmp_path, filter_angle):
    camera = f"origin = [0, 0, 3]\ntarget = [0, 0, 0]\nfov = 10\npolarizer_angle = {filter_angle}"
    for state, stokes in (("unpolarized", [1.0, 0, 0, 0]), ("circular", [1.0, 0, 0, 1.0])):
        measured = measure(tmp_path, emitter_scene(state, camera), name=state)
        assert abs(measured.image_y - 0.5) <= 4 * measured.image_stderr + FLOOR
        assert_stokes(measured, stokes)


@pytest.mark.parametrize("angle", [30, -60])
def test_emitter_angle_counts_from_the_surface_u_toward_v(tmp_path, angle):
    """S2's sign tells the basis' handedness: +30° from the picture's right toward its up is the image's too."""
    assert_stokes(measure(tmp_path, emitter_scene(f"linear {angle}")), linear(angle))


def test_emitter_seen_in_a_camera_turned_about_its_axis(tmp_path):
    """The camera's right turned 90° from the light's u: light at 0° arrives at -90° in the image's basis."""
    camera = "origin = [0, 0, 3]\ntarget = [0, 0, 0]\nup = [1, 0, 0]\nfov = 10"
    expected = rotator(np.radians(-90)) @ linear(0)
    assert_stokes(measure(tmp_path, emitter_scene("linear 0", camera)), expected)


@pytest.mark.parametrize("sheet_angle", [0, 60, 90])
def test_polarised_emitter_behind_a_sheet_polarizer(tmp_path, sheet_angle):
    """The light passes a polariser sheet: the path's whole Mueller matrix meets the light's Stokes vector."""
    measured = measure(tmp_path, emitter_scene("linear 0", sheet=f'type = "polarizer"\nangle = {sheet_angle}'))
    assert_stokes(measured, polarizer(np.radians(sheet_angle)) @ linear(0))


@pytest.mark.parametrize(
    ("display", "expected"),
    [("LCD-Dell_CCFL", linear(45)), ("CRT-Dell", np.array([1.0, 0.0, 0.0, 0.0]))],
    ids=["LCD, linear 45 in its CSV", "CRT, unpolarised"],
)
def test_display_emitter_takes_the_catalogue_polarization(tmp_path, display, expected):
    radiance = f'{{ display = "{display}", rgb = [0.8, 0.8, 0.8], white_luminance = 100 }}'
    measured = measure(tmp_path, emitter_scene("display", radiance=radiance))
    s0 = measured.stokes[0]
    assert s0 > 0
    tolerance = 4 * measured.stderr + 1e-5 * s0
    assert np.all(np.abs(measured.stokes - s0 * expected) <= tolerance), (measured.stokes, s0 * expected)


@pytest.mark.subprocess
@pytest.mark.parametrize(
    ("polarization", "radiance", "message"),
    [
        ("sideways", "{ value = 1 }", "polarization must be"),
        ("display", "{ value = 1 }", "needs a radiance that names a display"),
        ("unknown", "{ value = 1 }", "renders nothing"),
    ],
    ids=["not a state", "display without a display", "unknown"],
)
@pytest.mark.slow
def test_bad_emitter_polarization_is_refused_in_one_line(tmp_path, polarization, radiance, message):
    scene = tmp_path / "scene.toml"
    scene.write_text(emitter_scene(polarization, radiance=radiance))
    out = tmp_path / "out.exr"
    out.write_bytes(b"kept")
    result = run_spectrace("render", str(scene), "-o", str(out), timeout=300)
    assert result.returncode != 0
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and "polarization" in lines[0] and str(scene) in lines[0], result.stderr
    assert message in lines[0] and "Traceback" not in result.stderr
    assert out.read_bytes() == b"kept"


@pytest.mark.subprocess
@pytest.mark.slow
def test_polarized_emitter_with_another_integrator_is_refused(tmp_path):
    """A polarised emitter alone (no Stokes AOV, polariser or camera filter) makes the scene polarised, which only
    the path integrator renders."""
    text = emitter_scene("linear 0").replace('aovs = ["stokes", "dolp"]', "")
    scene = tmp_path / "scene.toml"
    scene.write_text(text.replace("[integrator]", '[integrator]\ntype = "direct"'))
    result = run_spectrace("render", str(scene), "-o", str(tmp_path / "out.exr"), timeout=300)
    lines = result.stderr.strip().splitlines()
    assert result.returncode != 0 and len(lines) == 1 and "integrator.type" in lines[0], result.stderr


def test_python_emitter_polarization_renders_and_saves(tmp_path):
    """spectrace.area_emitter(..., polarization=) through a camera polariser at 60°: cos² 60° of the light; the scene
    saved as a file (the emitter's polarisation, the camera's polariser, the Stokes AOVs) renders the same bits."""
    import dataclasses

    camera = "origin = [0, 0, 3]\ntarget = [0, 0, 0]\nfov = 10\npolarizer_angle = 60"
    path = tmp_path / "base.toml"
    path.write_text(emitter_scene("unpolarized", camera))
    scene = load_scene(path)
    lamp = spectrace.area_emitter(1.0, polarization="linear 0")
    black = spectrace.diffuse(0.0)
    shapes = [dataclasses.replace(s, emitter=lamp, material=black) for s in scene.shapes]
    scene = dataclasses.replace(scene, shapes=shapes)
    image = spectrace.render(scene, progress=False, colour_space="xyz")
    y = np.asarray(image.xyz, np.float64)[..., 1]
    assert abs(y.mean() - 0.25) <= 4 * y.std(ddof=1) / np.sqrt(y.size) + FLOOR
    saved = spectrace.render(
        spectrace.load_scene(spectrace.save_scene(scene, tmp_path / "saved.toml")), progress=False, colour_space="xyz"
    )
    np.testing.assert_array_equal(saved.xyz, image.xyz)


def test_wavefront_renders_the_polarised_emitter_as_the_megakernel(tmp_path, device):
    """Both kernel shapes run the same segment function: the light at 0° behind a sheet at 60°, through the camera's
    filter at 30°, passes cos² 60° cos² 30° of it in each (delta paths: no noise beyond rounding)."""
    from spectrace.engine.wavefront import WavefrontRenderer

    camera = "origin = [0, 0, 3]\ntarget = [0, 0, 0]\nfov = 10\npolarizer_angle = 30"
    path = tmp_path / "scene.toml"
    path.write_text(emitter_scene("linear 0", camera, sheet='type = "polarizer"\nangle = 60'))
    expected = np.cos(np.radians(60)) ** 2 * np.cos(np.radians(30)) ** 2
    for renderer in (WavefrontRenderer(load_scene(path), device), None):
        if renderer is None:
            image = spectrace.render(load_scene(path), progress=False, colour_space="xyz")
        else:
            image = renderer.render()
        y = np.asarray(image.xyz, np.float64)[..., 1]
        assert abs(y.mean() - expected) <= 4 * y.std(ddof=1) / np.sqrt(y.size) + FLOOR, y.mean()
