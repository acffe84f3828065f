"""Observers and sensors in the film: a uniform emitter filling the view renders what colour-science integrates for
each observer and for a measured sensor, several observers come out of one render, and the ΔE map is
colour-science's CIEDE2000 of the two observers' XYZ images."""

import colour
import numpy as np
import pytest

from scene_text import emitting_screen
from spectrace.engine.renderer import Renderer
from spectrace.io.exr import read_exr
from spectrace.scene import load_scene
from spectrace.spectral.grid import GRID_NM

COLOUR_NAMES = {
    "CIE 1931 2°": "CIE 1931 2 Degree Standard Observer",
    "CIE 1964 10°": "CIE 1964 10 Degree Standard Observer",
    "CIE 2012 2°": "CIE 2015 2 Degree Standard Observer",
    "CIE 2012 10°": "CIE 2015 10 Degree Standard Observer",
}
PREFIXES = {"CIE 1931 2°": "cie1931_2", "CIE 1964 10°": "cie1964_10", "CIE 2012 2°": "cie2012_2"}
# A fluorescent lamp's spikes make a wrong wavelength pdf show as a biased estimate.
RADIANCE = 'spectrum = "cie:FL2", scale = 0.01'


def _write_scene(tmp_path, film_keys: str, radiance: str = RADIANCE):
    text = emitting_screen(radiance=radiance, width=16, height=16)
    text = text.replace("height = 16\n", f"height = 16\n{film_keys}\n", 1)
    path = tmp_path / "screen.toml"
    path.write_text(text, encoding="utf-8")
    return path


def _scene(tmp_path, film_keys: str, radiance: str = RADIANCE):
    return load_scene(_write_scene(tmp_path, film_keys, radiance))


def _expected_xyz(radiance: np.ndarray, observer: str) -> np.ndarray:
    """colour-science's film XYZ: sd_to_XYZ without an illuminant normalises by 100/∫ȳ, over the observer's
    own table (the 2012 tables start at 390 nm)."""
    cmfs = colour.MSDS_CMFS[COLOUR_NAMES[observer]]
    sd = colour.SpectralDistribution(dict(zip(GRID_NM, radiance))).align(cmfs.shape)
    return colour.sd_to_XYZ(sd, cmfs=cmfs, method="Integration") / 100.0


def _mean_and_error(values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    flat = values.reshape(-1, values.shape[-1]).astype(np.float64)
    return flat.mean(axis=0), flat.std(axis=0, ddof=1) / np.sqrt(len(flat))


def _assert_within_4_sigma(values: np.ndarray, expected: np.ndarray) -> None:
    mean, error = _mean_and_error(values)
    assert np.all(error < 0.02 * np.abs(expected)), "the estimate should be tight"
    assert np.all(np.abs(mean - expected) < 4 * error), (mean, expected, error)


@pytest.mark.parametrize("observer", list(COLOUR_NAMES))
def test_uniform_emitter_gives_each_observers_xyz(device, tmp_path, observer):
    scene = _scene(tmp_path, f'observer = "{observer}"')
    image = Renderer(scene, device).render()
    _assert_within_4_sigma(image.xyz, _expected_xyz(scene.shapes[0].emitter.radiance.values, observer))


def test_several_observers_in_one_render(device, tmp_path):
    observers = ["CIE 1931 2°", "CIE 1964 10°", "CIE 2012 2°"]
    scene = _scene(tmp_path, f"observers = {observers!r}".replace("'", '"'))
    image = Renderer(scene, device).render()
    radiance = scene.shapes[0].emitter.radiance.values
    for observer in observers:
        prefix = PREFIXES[observer]
        triple = np.stack([image.channels[f"{prefix}.{axis}"] for axis in "XYZ"], axis=-1)
        _assert_within_4_sigma(triple, _expected_xyz(radiance, observer))
    # The same paths: the film's own X, Y, Z (CIE 1931) and the CIE 1931 channels add the same estimates.
    np.testing.assert_allclose(np.stack([image.channels[f"cie1931_2.{a}"] for a in "XYZ"], -1), image.xyz, rtol=1e-5)


def _write_sensor(path, channels: dict[str, np.ndarray]) -> None:
    lines = ["# a made-up camera: Gaussian channel sensitivities", "wavelength_nm," + ",".join(channels)]
    lines += [f"{w:g}," + ",".join(f"{c[i]:.9g}" for c in channels.values()) for i, w in enumerate(GRID_NM)]
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")


def _gaussian(centre: float, width: float) -> np.ndarray:
    return np.exp(-0.5 * ((GRID_NM - centre) / width) ** 2)


def test_sensor_channels_match_colour_science_integration(device, tmp_path):
    channels = {"R": _gaussian(600, 30), "G": 0.8 * _gaussian(540, 35), "B": 0.6 * _gaussian(460, 25)}
    channels["NIR"] = _gaussian(800, 15)
    _write_sensor(tmp_path / "camera.csv", channels)
    scene = _scene(tmp_path, 'sensor = "camera.csv"')
    image = Renderer(scene, device).render()
    radiance = colour.SpectralDistribution(dict(zip(GRID_NM, scene.shapes[0].emitter.radiance.values)))
    ones = colour.SpectralDistribution(dict(zip(GRID_NM, np.ones_like(GRID_NM))))
    for name, curve in channels.items():
        # One channel at a time as the three "CMFs" of colour-science's integration, k = 1: ∫ L s dλ (a given k
        # makes colour-science read its sum as a percentage and return it divided by 100).
        cmfs = colour.MultiSpectralDistributions(dict(zip(GRID_NM, np.stack([curve] * 3, axis=1))))
        expected = 100 * colour.sd_to_XYZ(radiance, cmfs=cmfs, illuminant=ones, k=1, method="Integration")[0]
        _assert_within_4_sigma(image.channels[f"sensor.{name}"][..., None], np.array([expected]))


def test_sensor_that_is_the_cie_1931_observer_needs_no_correction(device, tmp_path):
    """A camera whose sensitivities are x̄, ȳ, z̄: white balance and colour correction must give back CIE XYZ."""
    cmfs = colour.MSDS_CMFS[COLOUR_NAMES["CIE 1931 2°"]]
    _write_sensor(tmp_path / "xyz.csv", {axis: np.asarray(cmfs.values[:, i]) for i, axis in enumerate("XYZ")})
    scene = _scene(tmp_path, 'sensor = "xyz.csv"\nsensor_white = "D65"')
    image = Renderer(scene, device).render(spp=4)
    raw = np.stack([image.channels[f"sensor.{axis}"] for axis in "XYZ"], axis=-1)
    y_integral = np.trapezoid(cmfs.values[:, 1], cmfs.wavelengths)
    np.testing.assert_allclose(image.xyz, raw / y_integral, rtol=2e-3)


def test_delta_e_map_is_colour_sciences_ciede2000(device, tmp_path):
    from dataclasses import replace

    scene = _scene(tmp_path, 'observers = ["CIE 1931 2°", "CIE 1964 10°"]')
    scene = scene.with_overrides(
        film_response=replace(scene.film_response, delta_e_pair=("CIE 1931 2°", "CIE 1964 10°"), delta_e_white_y=2.0)
    )
    image = Renderer(scene, device).render(spp=4)
    d65 = colour.SDS_ILLUMINANTS["D65"]
    labs = []
    for observer in ("CIE 1931 2°", "CIE 1964 10°"):
        white = colour.XYZ_to_xy(colour.sd_to_XYZ(d65, cmfs=colour.MSDS_CMFS[COLOUR_NAMES[observer]]))
        xyz = np.stack([image.channels[f"{PREFIXES[observer]}.{a}"] for a in "XYZ"], -1).astype(np.float64)
        labs.append(colour.XYZ_to_Lab(xyz / 2.0, white))  # the white at film Y = 2
    expected = colour.delta_E(labs[0], labs[1], method="CIE 2000")
    assert expected.mean() > 0.5, "the lamp should look different to the two observers"
    np.testing.assert_allclose(image.channels["deltaE00"], expected, rtol=1e-3, atol=1e-3)


def test_channels_are_written_to_the_exr(device, tmp_path):
    channels = {"mono": _gaussian(550, 80)}
    _write_sensor(tmp_path / "mono.csv", channels)
    scene = _scene(tmp_path, 'sensor = "mono.csv"\nobservers = ["CIE 2012 10°"]')
    image = Renderer(scene, device).render(spp=1)
    image.write(tmp_path / "out.exr")
    read, _ = read_exr(tmp_path / "out.exr")
    assert {"sensor.mono", "cie2012_10.X", "cie2012_10.Y", "cie2012_10.Z", "X", "Y", "Z", "RGB"} <= set(read)
    np.testing.assert_array_equal(read["sensor.mono"], image.channels["sensor.mono"])


@pytest.mark.parametrize("kernel", ["megakernel", "wavefront"])
def test_response_film_is_split_invariant_and_resumes_exactly(device, tmp_path, kernel):
    from dataclasses import replace

    from spectrace.engine.checkpoint import resume_render, save_checkpoint
    from spectrace.engine.wavefront import make_renderer
    from spectrace.film.response import load_sensor
    from spectrace.resources import scenes_dir

    _write_sensor(tmp_path / "mono.csv", {"mono": _gaussian(650, 60)})
    scene = load_scene(scenes_dir() / "cornell_box.toml").with_overrides(width=12, height=10, spp=5, seed=3)
    response = replace(
        scene.film_response,
        observer="CIE 1964 10°",
        observers=("CIE 1931 2°", "CIE 2012 2°"),
        sensor=load_sensor(tmp_path / "mono.csv"),
    )
    scene = scene.with_overrides(film_response=response)
    one = make_renderer(scene, device, kernel)
    one.run_pass(5)
    split = make_renderer(scene, device, kernel)
    split.run_pass(2)
    save_checkpoint(tmp_path / "state.npz", split)
    resumed = make_renderer(scene, device, kernel)
    resume_render(resumed, tmp_path / "state.npz")
    resumed.run_pass(1)
    resumed.run_pass(2)
    reference = one.film.read_responses()
    assert reference.shape == (10, 12, 7) and reference[..., -1].mean() > 0
    assert np.array_equal(resumed.film.read_responses().view(np.uint32), reference.view(np.uint32))
    assert np.array_equal(resumed.read_film()[0].view(np.uint32), one.read_film()[0].view(np.uint32))


def test_render_command_writes_the_delta_e_map(device, tmp_path, monkeypatch, capsys):
    from cli_runner import run_in_process

    _write_scene(tmp_path, 'observers = ["CIE 1931 2°", "CIE 2012 2°"]')
    out = tmp_path / "map.exr"
    code, _ = run_in_process(
        monkeypatch, capsys, ["render", str(tmp_path / "screen.toml"), "-o", str(out), "--delta-e-map", "--spp", "2"]
    )
    assert code in (0, None)
    channels, _ = read_exr(out)
    assert np.all(np.isfinite(channels["deltaE00"])) and channels["deltaE00"].mean() > 0.1


@pytest.mark.parametrize(
    ("film_keys", "option", "says"),
    [
        ('observers = ["CIE 1931 2°"]', "--delta-e-map", "--delta-e-map: compares the first two of film.observers"),
        ('observer = "CIE 1931"', "", "film.observer"),
        ('sensor = "missing.csv"', "", "film.sensor"),
        ('sensor_white = "D65"', "", "film.sensor_white"),
    ],
)
def test_bad_film_settings_are_one_line(tmp_path, monkeypatch, capsys, film_keys, option, says):
    from cli_runner import run_in_process

    _write_scene(tmp_path, film_keys)
    argv = ["render", str(tmp_path / "screen.toml"), "-o", str(tmp_path / "out.exr"), *([option] if option else [])]
    code, err = run_in_process(monkeypatch, capsys, argv)
    assert code != 0
    assert len(err.strip().splitlines()) == 1 and says in err and "Traceback" not in err, err
    assert not (tmp_path / "out.exr").exists()


# ---------------------------------------------------------------- the film's wavelength range


def _planck_relative_to_peak(wavelength_nm: np.ndarray, temperature: float) -> np.ndarray:
    """Planck's law from colour-science with the second radiation constant c2 = hc/k of CODATA 2018 (1.438776877
    × 10⁻² m K; colour's default is ITS-90's rounded 1.4388 × 10⁻²), divided by its maximum, found here by searching
    a 0.01 nm grid about λ_max = c2 / (4.965 T) rather than from the renderer's Wien constant. c1 cancels."""
    planck_law = colour.colorimetry.planck_law
    c2 = 1.438776877e-2
    around_peak = c2 / (4.965 * temperature) * 1e9 + np.linspace(-50.0, 50.0, 10001)
    peak = planck_law(around_peak * 1e-9, temperature, c2=c2).max()
    return planck_law(np.asarray(wavelength_nm, float) * 1e-9, temperature, c2=c2) / peak


def test_blackbody_through_a_near_infrared_sensor_gives_the_planck_integral(device, tmp_path):
    wavelengths = np.arange(760, 1101)
    sensitivity = np.exp(-0.5 * ((wavelengths - 950) / 40.0) ** 2)  # nothing below 760 nm: a NIR-only sensor
    lines = ["wavelength_nm,NIR", *(f"{w},{v:.9g}" for w, v in zip(wavelengths, sensitivity))]
    (tmp_path / "nir.csv").write_text("\n".join(lines) + "\n", encoding="utf-8")
    temperature = 1500.0
    scene = _scene(tmp_path, 'sensor = "nir.csv"\nwavelengths = [300, 1100]', radiance=f"blackbody = {temperature}")
    image = Renderer(scene, device).render()
    # Planck's law (normalised to its peak, as the scene format's blackbody is) times the sensor, integrated on a
    # 0.01 nm grid: independent of the renderer's Planck function and of its 1 nm table.
    fine = np.linspace(760.0, 1100.0, 34001)
    integrand = _planck_relative_to_peak(fine, temperature) * np.interp(fine, wavelengths, sensitivity)
    expected = np.trapezoid(integrand, fine)
    _assert_within_4_sigma(image.channels["sensor.NIR"][..., None], np.array([expected]))


def test_a_spectrum_short_of_the_films_range_is_one_line_naming_it(tmp_path, monkeypatch, capsys):
    from cli_runner import run_in_process

    (tmp_path / "lamp.csv").write_text("wavelength_nm,value\n380,1\n780,2\n", encoding="utf-8")
    _write_scene(tmp_path, "wavelengths = [300, 1000]", radiance='file = "lamp.csv"')
    code, err = run_in_process(monkeypatch, capsys, ["render", str(tmp_path / "screen.toml"), "-o", "x.exr"])
    assert code != 0 and len(err.strip().splitlines()) == 1 and "Traceback" not in err, err
    assert "lamp" in err and "380-780 nm" in err and "300-380 nm and 780-1000 nm" in err, err


def test_rgb_outside_the_visible_is_refused_unless_extended(device, tmp_path, monkeypatch, capsys):
    from cli_runner import run_in_process

    text = (
        emitting_screen(reflectance="rgb = [0.2, 0.5, 0.3]", radiance="blackbody = 3000", width=4, height=4)
        .replace("height = 4\n", "height = 4\nwavelengths = [360, 1000]\n", 1)
        .replace("max_depth = 1", "max_depth = 2")
    )
    path = tmp_path / "rgb.toml"
    path.write_text(text, encoding="utf-8")
    out = tmp_path / "out.exr"
    code, err = run_in_process(monkeypatch, capsys, ["render", str(path), "-o", str(out)])
    assert code != 0 and len(err.strip().splitlines()) == 1 and "Traceback" not in err, err
    assert "RGB uplift" in err and "extend_rgb" in err and not out.exists(), err
    path.write_text(text.replace("wavelengths = [360, 1000]", "wavelengths = [360, 1000]\nextend_rgb = true"))
    image = Renderer(load_scene(path), device).render(spp=2)
    assert np.all(np.isfinite(image.xyz)) and image.xyz[..., 1].mean() > 0


def test_a_checkpoint_of_another_film_is_refused(device, tmp_path):
    from dataclasses import replace

    from spectrace.engine.checkpoint import resume_render, save_checkpoint
    from spectrace.errors import SpectraceError

    scene = _scene(tmp_path, 'observers = ["CIE 1964 10°"]')
    renderer = Renderer(scene, device)
    renderer.run_pass(1)
    save_checkpoint(tmp_path / "state.npz", renderer)
    other = scene.with_overrides(film_response=replace(scene.film_response, observers=("CIE 2012 10°",)))
    with pytest.raises(SpectraceError):
        resume_render(Renderer(other, device), tmp_path / "state.npz")
    resume_render(Renderer(scene, device), tmp_path / "state.npz")  # the same film resumes
