"""Spectral OpenEXR output (Fichet et al. 2021 layout): read back, its bands integrated against the CIE CMFs
reproduce the film's XYZ."""

import numpy as np
import OpenEXR

from spectrace.engine.renderer import Renderer
from spectrace.io.exr import read_exr, read_spectral_exr
from spectrace.resources import scenes_dir
from spectrace.scene import load_scene
from spectrace.spectral.colorimetry import CIE_1931_CMFS, CIE_Y_INTEGRAL
from spectrace.spectral.grid import GRID_NM


def _band_cmf_weights(edges_nm):
    """∫ over each band of (x̄, ȳ, z̄) / ∫ȳ, with the CMFs interpolated finely (independent of the renderer)."""
    weights = []
    for lo, hi in zip(edges_nm[:-1], edges_nm[1:]):
        lam = np.linspace(lo, hi, 201)
        values = np.stack([np.interp(lam, GRID_NM, CIE_1931_CMFS[:, i]) for i in range(3)], axis=1)
        weights.append(np.trapezoid(values, lam, axis=0))
    return np.array(weights) / CIE_Y_INTEGRAL


def test_spectral_exr_round_trip_reproduces_xyz(device, tmp_path):
    scene = load_scene(scenes_dir() / "cornell_box.toml").with_overrides(width=16, height=16, spp=32)
    bins = 94  # 5 nm bands
    image = Renderer(scene, device, spectral_bins=bins).render()
    path = tmp_path / "cornell_spectral.exr"
    image.write(path)

    with OpenEXR.File(str(path)) as exr:  # any OpenEXR reader sees the layout's channels and attributes
        names = set(exr.channels())
        header = dict(exr.header())  # the live header is cleared when the file closes
    assert "S0.557,500000nm" in names and "S0.362,500000nm" in names
    assert header["spectralLayoutVersion"] == "1.0" and header["emissiveUnits"] == "W.m^-2.sr^-1"

    wavelengths, radiance = read_spectral_exr(path)
    assert radiance.shape == (16, 16, bins)
    np.testing.assert_allclose(wavelengths, np.arange(362.5, 830, 5.0))
    edges = np.linspace(360.0, 830.0, bins + 1)
    xyz_from_bands = radiance @ _band_cmf_weights(edges)
    channels, _ = read_exr(path)
    xyz = np.stack([channels["X"], channels["Y"], channels["Z"]], axis=-1)
    # Same samples, two estimators: they differ only by the CMFs' variation inside each 5 nm band.
    np.testing.assert_allclose(xyz_from_bands.mean(axis=(0, 1)), xyz.mean(axis=(0, 1)), rtol=0.01)
    np.testing.assert_allclose(xyz_from_bands, xyz, rtol=0.05, atol=1e-3 * xyz.max())


def test_spectral_bands_are_pass_split_invariant(device):
    scene = load_scene(scenes_dir() / "cornell_box.toml").with_overrides(width=8, height=8)
    one = Renderer(scene, device, spectral_bins=10)
    one.run_pass(4)
    split = Renderer(scene, device, spectral_bins=10)
    split.run_pass(1)
    split.run_pass(3)
    assert np.array_equal(one.read_spectral_film(), split.read_spectral_film())


def test_halving_the_bands_splits_each_bands_sum_in_two(device):
    """The same samples into 10 and into 20 bands over one range: each wide band's average radiance is the mean of
    its two halves' (every lane lands in one band of each film, weighted 1/Δ). The band count and range reach the
    kernels at run time, so both films come from one program."""
    scene = load_scene(scenes_dir() / "cornell_box.toml").with_overrides(width=8, height=8, spp=4)
    span = (420.0, 700.0)
    wide = Renderer(scene, device, spectral_bins=10, spectral_range_nm=span).render().spectral
    narrow = Renderer(scene, device, spectral_bins=20, spectral_range_nm=span).render().spectral
    assert wide is not None and narrow is not None
    np.testing.assert_allclose(narrow.edges_nm[::2], wide.edges_nm)
    halves = narrow.radiance.astype(np.float64).reshape(8, 8, 10, 2).mean(axis=-1)
    assert wide.radiance.max() > 0.0
    np.testing.assert_allclose(wide.radiance, halves, rtol=1e-5, atol=1e-6 * wide.radiance.max())
