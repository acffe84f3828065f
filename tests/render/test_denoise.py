"""Denoising (spectrace.denoising, `spectrace render --denoise`): the channels exist and are finite, and without the
optional binding the user is told in one line what to install. How much it lowers the error is a measurement
(`spectrace bench denoise`), not a test."""

import sys

import numpy as np
import pytest

import spectrace
from cli_runner import render_cornell_box, run_in_process
from spectrace.denoising import INSTALL_HINT, noisy_path_for
from spectrace.errors import SpectraceError
from spectrace.resources import scenes_dir


def _cornell(aovs=("albedo", "normal")):
    return spectrace.load_scene(scenes_dir() / "cornell_box.toml").with_overrides(width=16, height=16, aovs=aovs)


def test_denoised_image_is_finite_and_keeps_its_aovs(device):
    pytest.importorskip("pyoidn", reason="the denoise extra (pyoidn) is not installed")
    image = spectrace.render(_cornell(), spp=4, device=device, progress=False)
    denoised = spectrace.denoise(image)
    assert denoised.xyz.shape == image.xyz.shape
    assert np.isfinite(denoised.xyz).all()
    assert set(denoised.aovs) == {"albedo", "normal"}
    assert "denoised" in denoised.metadata()


def test_denoising_needs_the_albedo_and_normal(device):
    image = spectrace.render(_cornell(aovs=("depth",)), spp=1, device=device, progress=False)
    with pytest.raises(SpectraceError, match="albedo and normal AOVs"):
        spectrace.denoise(image)


def test_without_the_extra_denoising_says_what_to_install(monkeypatch, capsys, tmp_path, device):
    monkeypatch.setitem(sys.modules, "pyoidn", None)  # import pyoidn now raises ImportError
    image = spectrace.render(_cornell(), spp=1, device=device, progress=False)
    with pytest.raises(SpectraceError, match=r"spectrace\[denoise\]"):
        spectrace.denoise(image)
    out = tmp_path / "c.exr"
    status, err = run_in_process(monkeypatch, capsys, [*render_cornell_box(out, 1, 8, 8), "--denoise", "-q"])
    assert status != 0
    assert err.strip().count("\n") == 0 and INSTALL_HINT in err
    assert not out.exists() and not noisy_path_for(out).exists()


def test_cli_denoise_writes_the_denoised_and_the_noisy_image(monkeypatch, capsys, tmp_path):
    pytest.importorskip("pyoidn", reason="the denoise extra (pyoidn) is not installed")
    from spectrace.io.exr import read_exr

    out = tmp_path / "c.exr"
    status, err = run_in_process(monkeypatch, capsys, [*render_cornell_box(out, 4, 16, 16), "--denoise", "-q"])
    assert status in (0, None), err
    noisy = tmp_path / "c.noisy.exr"
    for path in (out, noisy):
        channels, header = read_exr(path)
        assert {"RGB", "albedo", "normal.X", "normal.Y", "normal.Z"} <= set(channels)
        assert all(np.isfinite(values).all() for values in channels.values())
    assert "spectrace:denoised" not in read_exr(noisy)[1]
    assert "directly seen emission rendered apart" in str(read_exr(out)[1]["spectrace:denoised"])


@pytest.mark.parametrize(
    ("option", "message"), [("bogus", "unknown AOV 'bogus'"), ("albedo,depth", "--aov needs an .exr output")]
)
def test_cli_refuses_bad_aov_options_in_one_line(monkeypatch, capsys, tmp_path, option, message):
    out = tmp_path / ("c.exr" if option == "bogus" else "c.png")
    status, err = run_in_process(monkeypatch, capsys, [*render_cornell_box(out, 1, 8, 8), "--aov", option])
    assert status != 0
    assert err.strip().count("\n") == 0 and message in err
    assert not out.exists()


def test_directly_seen_emission_is_exchanged_for_its_expected_value(device):
    """A view of nothing but a constant environment: once its sampled emission is taken out nothing is left to
    denoise, so the denoised image is the emission's expected film XYZ (the spectrum's, by colour-science's tables)
    in every pixel; denoised whole, the colour noise of sampled wavelengths stays in it."""
    pytest.importorskip("pyoidn", reason="the denoise extra (pyoidn) is not installed")
    import colour

    wavelengths = np.arange(360.0, 831.0)
    radiance = 0.5 + 2.0 * np.exp(-(((wavelengths - 560.0) / 40.0) ** 2))
    scene = _cornell(aovs=("albedo", "normal", "emission")).with_overrides(
        shapes=[], lights=[spectrace.constant_environment(spectrace.spectrum((wavelengths, radiance)))]
    )
    image = spectrace.render(scene, spp=2, device=device, progress=False)
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"].copy().align(colour.SpectralShape(360, 830, 1))
    table = cmfs.values * np.r_[0.5, np.ones(len(wavelengths) - 2), 0.5][:, None]
    expected = (radiance[:, None] * table).sum(axis=0) / table[:, 1].sum()
    denoised = spectrace.denoise(image).xyz.reshape(-1, 3)
    np.testing.assert_allclose(denoised, np.broadcast_to(expected, denoised.shape), rtol=2e-4, atol=1e-5)
    whole = spectrace.denoise(image, exchange_emission=False).xyz.reshape(-1, 3)
    assert np.abs(whole - expected).max() > 1e-2 * expected.max()


# The directly seen emission pass (spectrace.directly_seen_emission): a camera 4 units above the plane z = 0,
# looking down at it. The plane is parallel to the image plane, so the pixels' footprints on it are a square grid
# of side PIXEL_ON_PLANE, the middle pixel's centred on the axis (SIZE odd).
DISTANCE = 4.0
FOV_DEGREES = 20.0
SIZE = 9
PIXEL_ON_PLANE = 2.0 * DISTANCE * np.tan(np.radians(FOV_DEGREES / 2)) / SIZE
WAVELENGTHS = np.arange(360.0, 831.0)
EMISSION = 0.5 + 2.0 * np.exp(-(((WAVELENGTHS - 560.0) / 40.0) ** 2))


def _film_xyz(radiance: np.ndarray) -> np.ndarray:
    """Film XYZ of a radiance on the 1 nm grid: ∫ L x̄ȳz̄ dλ / ∫ȳ (trapezoid rule), from colour-science's tables."""
    import colour

    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"].copy().align(colour.SpectralShape(360, 830, 1))
    table = cmfs.values * np.r_[0.5, np.ones(len(WAVELENGTHS) - 2), 0.5][:, None]
    return (radiance[:, None] * table).sum(axis=0) / table[:, 1].sum()


def _emitter_scene(half_x: float, half_y: float, spp: int = 4) -> spectrace.Scene:
    """An emitting rectangle [-half_x, half_x] x [-half_y, half_y] on the plane z = 0, facing the camera, in front
    of nothing."""
    emitter = spectrace.shape(
        "rectangle",
        spectrace.diffuse(0.0),
        emitter=spectrace.area_emitter(spectrace.spectrum((WAVELENGTHS, EMISSION))),
        transform=[{"scale": [half_x, half_y, 1.0]}],
    )
    return spectrace.Scene(
        camera=spectrace.Camera(origin=(0.0, 0.0, DISTANCE), target=(0.0, 0.0, 0.0), fov_degrees=FOV_DEGREES),
        width=SIZE,
        height=SIZE,
        shapes=[emitter],
        spp=spp,
        sampler="independent",
        aovs=("albedo", "normal", "emission"),
    )


def _covered_fraction(half: float) -> np.ndarray:
    """The fraction of each pixel column (or row) of the footprint grid that [-half, half] covers."""
    edges = (np.arange(SIZE + 1) - SIZE / 2) * PIXEL_ON_PLANE
    return np.clip((np.minimum(edges[1:], half) - np.maximum(edges[:-1], -half)) / PIXEL_ON_PLANE, 0.0, 1.0)


def test_the_emission_pass_of_an_emitter_filling_the_view_is_its_radiance(device):
    """Every camera ray meets the emitter: every pixel of the pass is the emission's film XYZ (colour-science's
    tables), with no noise at all, since each sample records the expected value over the wavelengths."""
    image_spp = 4
    emission = spectrace.directly_seen_emission(_emitter_scene(10.0, 10.0, image_spp), image_spp, device)
    assert emission.spp == max(32, 2 * image_spp)
    # 2e-4: the kernels integrate the linear interpolation of the tables, this sums at the 1 nm points.
    np.testing.assert_allclose(
        emission.aovs["emission"].reshape(-1, 3), np.broadcast_to(_film_xyz(EMISSION), (SIZE * SIZE, 3)), rtol=2e-4
    )


def test_the_emission_pass_covers_edge_pixels_by_the_fraction_the_emitter_covers(device):
    """An emitter whose edges cross pixels: each pixel of the pass is the emission's Y times the fraction of the
    pixel's footprint the emitter covers (the box filter weighs the pixel's area evenly), within 4.5 standard
    errors of that binomial coverage estimate over the pass's samples (the independent sampler)."""
    half_x, half_y = 1.3 * PIXEL_ON_PLANE, 2.25 * PIXEL_ON_PLANE  # columns covered 0.8, rows 0.75 at the edges
    image_spp = 64
    emission = spectrace.directly_seen_emission(_emitter_scene(half_x, half_y, image_spp), image_spp, device)
    samples = emission.spp
    assert samples == 2 * image_spp
    # The footprint grid and the emitter are both symmetric about the axes, so which way the image runs is moot.
    fraction = _covered_fraction(half_y)[:, None] * _covered_fraction(half_x)[None, :]
    assert {0.6, 0.75, 0.8} <= set(np.round(fraction.ravel(), 6))  # partly covered pixels are tested
    y_emitted = _film_xyz(EMISSION)[1]
    expected = y_emitted * fraction
    standard_error = y_emitted * np.sqrt(fraction * (1.0 - fraction) / samples)
    measured = emission.aovs["emission"][..., 1].astype(np.float64)
    assert np.all(np.abs(measured - expected) <= 4.5 * standard_error + 2e-4 * y_emitted)


def test_denoising_with_the_emission_pass_replaces_the_images_emission(device):
    """A view of nothing but an emitter: once the image's sampled emission is taken out nothing is left to denoise,
    so the image denoised with the emission pass is the pass, the emission's film XYZ in every pixel."""
    pytest.importorskip("pyoidn", reason="the denoise extra (pyoidn) is not installed")
    scene = _emitter_scene(10.0, 10.0, 2)
    image = spectrace.render(scene, spp=2, device=device, progress=False)
    emission = spectrace.directly_seen_emission(scene, image.spp, device)
    denoised = spectrace.denoise(image, emission=emission)
    np.testing.assert_allclose(
        denoised.xyz.reshape(-1, 3), np.broadcast_to(_film_xyz(EMISSION), (SIZE * SIZE, 3)), rtol=2e-4, atol=1e-5
    )
    assert "rendered apart" in denoised.extra["denoised"]
    with pytest.raises(SpectraceError, match="emission AOV"):
        spectrace.denoise(
            spectrace.render(scene, spp=1, aovs="albedo,normal", device=device, progress=False), emission=emission
        )
