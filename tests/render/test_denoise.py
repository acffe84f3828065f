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
    assert "spectrace:denoised" in read_exr(out)[1] and "spectrace:denoised" not in read_exr(noisy)[1]


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
