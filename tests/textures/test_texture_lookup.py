"""Texture lookups on the device (kernels/texture.cl) against an independent numpy reference (tests/textures/
lookup.py): nearest and bilinear filtering, the three wrap modes, uv scale and offset, MIP level choice and
trilinear blending; the sigmoid spectrum against the host's; spectral bands interpolated per wavelength; the
checkerboard's squares."""

import numpy as np
import pytest
from tests.textures.lookup import (
    HARNESS,
    TextureHarness,
    bilinear,
    half_sigmoid_spectrum,
    nearest,
    pyramid,
    trilinear,
)

from spectrace.core.contract import STORAGE_FLOAT, STORAGE_HALF
from spectrace.spectral.rgb_texture import reflectance_coefficients
from spectrace.spectral.spectrum import Spectrum
from spectrace.spectral.uplift import sigmoid_polynomial_spectrum, uplift_reflectance
from spectrace.textures import bitmap, checkerboard, mix, scale, spectral

GRID_LAMBDAS = (400.0, 470.0, 555.0, 690.0)  # on the 1 nm grid, where the host's table is exact


@pytest.fixture(scope="module")
def runner(kernel_runner):
    return kernel_runner(HARNESS)


def _points(rng, n, low=-1.5, high=2.5) -> np.ndarray:
    return rng.uniform(low, high, (n, 2))


@pytest.mark.parametrize("wrap", ["repeat", "mirror", "clamp"])
@pytest.mark.parametrize("filter", ["nearest", "bilinear"])
def test_scalar_lookups_match_the_reference(runner, wrap, filter):
    """A non-square random grey image read raw (one channel, as stored) at points in and far outside [0, 1)²."""
    rng = np.random.default_rng(4)
    image = rng.uniform(0.0, 1.0, (5, 7, 1))
    texture = bitmap.make(image, wrap=wrap, filter=filter)
    uv = _points(rng, 3000)
    got = TextureHarness(runner, [(texture, "float")]).lookup(0, uv)
    reference = (nearest if filter == "nearest" else bilinear)(image, uv, wrap)[:, 0]
    # A scalar texture gives the same value at every wavelength.
    assert np.all(got == got[:, :1])
    if filter == "bilinear":
        np.testing.assert_allclose(got[:, 0], reference, atol=2e-6, rtol=0)
    else:
        # A point within float32 rounding of a texel edge may land on either side: compare the others exactly.
        st = uv * [image.shape[1], image.shape[0]]
        clear = np.all(np.abs(st - np.round(st)) > 1e-4, axis=1)
        assert clear.mean() > 0.99
        np.testing.assert_array_equal(got[clear, 0], reference[clear].astype(np.float32))


def test_uv_scale_and_offset_place_the_image(runner):
    """st = uv · uv_scale + uv_offset: a texture scaled by (3, 2) and offset by (0.25, -0.5) at uv equals the
    unscaled one at st."""
    rng = np.random.default_rng(5)
    image = rng.uniform(0.0, 1.0, (4, 4, 1))
    scaled = bitmap.make(image, uv_scale=(3.0, 2.0), uv_offset=(0.25, -0.5))
    uv = _points(rng, 1000, 0.0, 1.0)
    got = TextureHarness(runner, [(scaled, "float")]).lookup(0, uv)[:, 0]
    st = uv * [3.0, 2.0] + [0.25, -0.5]
    np.testing.assert_allclose(got, bilinear(image, st, "repeat")[:, 0], atol=3e-6)


@pytest.mark.parametrize("footprint_texels", [0.0, 1.0, 2.0, 3.0, 5.5, 16.0, 64.0, 1000.0])
def test_trilinear_level_choice_matches_the_reference(runner, footprint_texels):
    """A 16 × 16 image's pyramid (2 × 2 means) read with footprints of 0 (finest), whole levels (2 and 16 texels:
    levels 1 and 4, exactly), between levels (3, 5.5 texels) and beyond the coarsest (the 1 × 1 mean)."""
    rng = np.random.default_rng(6)
    image = rng.uniform(0.0, 1.0, (16, 16, 1))
    texture = bitmap.make(image, filter="trilinear", wrap="mirror")
    footprint = footprint_texels / 16.0
    uv = _points(rng, 2000)
    got = TextureHarness(runner, [(texture, "float")]).lookup(0, uv, footprint=footprint)[:, 0]
    expected = trilinear(pyramid(image), uv, footprint, "mirror")[:, 0]
    np.testing.assert_allclose(got, expected, atol=3e-6)
    if footprint_texels >= 16.0:
        np.testing.assert_allclose(got, image.mean(), atol=3e-6)


def test_sigmoid_matches_the_host_spectrum(runner):
    """S(c0 λ² + c1 λ + c2) on the device equals the host's sigmoid_polynomial_spectrum at grid wavelengths, for
    fitted colours and the saturated black and white."""
    colours = [(0.8, 0.2, 0.1), (0.05, 0.6, 0.3), (0.2, 0.3, 0.9), (0.5, 0.5, 0.5), (0.0, 0.0, 0.0), (1.0, 1.0, 1.0)]
    coefficients = np.zeros((len(colours), 4), np.float32)
    coefficients[:, :3] = [uplift_reflectance(c)[1] for c in colours]
    out = np.zeros((len(colours), 4), np.float32)
    args = [runner.buffer(coefficients), runner.buffer(np.array(GRID_LAMBDAS, np.float32)), runner.buffer(out, True)]
    runner.run("sigmoid_spectrum", len(colours), args, {2: out})
    grid_index = np.array(GRID_LAMBDAS).astype(int) - 360
    for i, colour in enumerate(colours):
        host = sigmoid_polynomial_spectrum(uplift_reflectance(colour)[1])[grid_index]
        np.testing.assert_allclose(out[i], host, atol=5e-5, err_msg=str(colour))


def test_rgb_bilinear_blends_the_texels_spectra(runner):
    """A 2 × 2 RGB reflectance texture: between texel centres the value is the bilinear blend of the four texels'
    SPECTRA (each S(poly) of its own coefficients, as textures fit them and store them in half), not the spectrum of
    blended coefficients."""
    rgb = np.array([[[0.9, 0.1, 0.1], [0.1, 0.9, 0.1]], [[0.1, 0.1, 0.9], [0.9, 0.9, 0.2]]])
    texture = bitmap.make(rgb, wrap="clamp")
    rng = np.random.default_rng(7)
    uv = rng.uniform(0.0, 1.0, (500, 2))
    harness = TextureHarness(runner, [(texture, "spectrum")])
    assert harness.rows["storage"][0] == STORAGE_HALF
    got = harness.lookup(0, uv, lambdas=GRID_LAMBDAS)
    spectra = half_sigmoid_spectrum(reflectance_coefficients(rgb), GRID_LAMBDAS)
    np.testing.assert_allclose(got, bilinear(spectra, uv, "clamp"), atol=5e-5)


@pytest.mark.parametrize("storage", [STORAGE_HALF, STORAGE_FLOAT])
def test_sigmoid_texels_in_either_storage(runner, storage):
    """Texels of many colours (random, dark, saturated, black, white) read with nearest filtering: each is its
    coefficients' spectrum as stored, within float rounding (half: the dimensionless coefficients rounded to half;
    float: the coefficients in nm). A texture whose coefficients exceed half's range (those of a colour as dark as
    (1e-9, 0, 0) do: they grow as the colour darkens) keeps float."""
    rng = np.random.default_rng(17)
    rgb = np.concatenate([rng.random((60, 3)), rng.random((20, 3)) * 0.01, [[0, 0, 0], [1, 1, 1], [0.5, 0.5, 0.5]]])
    if storage == STORAGE_FLOAT:
        rgb[0] = [1e-9, 0.0, 0.0]  # coefficients beyond 65504 in their dimensionless form
    image = rgb.reshape(1, -1, 3)
    harness = TextureHarness(runner, [(bitmap.make(image, filter="nearest"), "spectrum")])
    assert harness.rows["storage"][0] == storage
    uv = np.stack([(np.arange(len(rgb)) + 0.5) / len(rgb), np.full(len(rgb), 0.5)], axis=1)
    got = harness.lookup(0, uv, lambdas=GRID_LAMBDAS)
    coefficients = reflectance_coefficients(rgb)
    if storage == STORAGE_HALF:
        expected = half_sigmoid_spectrum(coefficients, GRID_LAMBDAS)
    else:
        grid_index = np.array(GRID_LAMBDAS).astype(int) - 360
        expected = np.array([sigmoid_polynomial_spectrum(c.astype(np.float32))[grid_index] for c in coefficients])
    np.testing.assert_allclose(got, expected, atol=5e-5)
    np.testing.assert_array_equal(got[-3:-1], [[0.0] * 4, [1.0] * 4])


def test_spectral_bands_are_interpolated_per_wavelength(runner):
    """A 3 × 2 spectral texture with bands every 50 nm from 400 nm: at each wavelength the nearest texel's value is
    the linear interpolation between its band centres, the end bands held outside them."""
    rng = np.random.default_rng(8)
    wavelengths = np.arange(400.0, 701.0, 50.0)
    values = rng.uniform(0.0, 1.0, (2, 3, len(wavelengths)))
    texture = spectral.make(values, wavelengths, filter="nearest")
    uv = rng.uniform(0.0, 1.0, (300, 2))
    lambdas = (380.0, 425.0, 612.5, 760.0)
    harness = TextureHarness(runner, [(texture, "spectrum")])
    assert harness.rows["storage"][0] == STORAGE_HALF  # bands stored in half: each within 2^-11 relative
    got = harness.lookup(0, uv, lambdas=lambdas)
    texels = nearest(values.astype(np.float16).astype(np.float64), uv, "repeat")
    expected = np.array([[np.interp(lam, wavelengths, t) for lam in lambdas] for t in texels])
    np.testing.assert_allclose(got, expected, atol=2e-6)


def test_checkerboard_alternates_its_sides(runner):
    """Side 0 where floor(s) + floor(t) is even (st = uv · 4): a spectrum on one side, an image texture on the
    other."""
    inner = bitmap.make(np.full((1, 1, 3), 0.5), filter="nearest")
    board = checkerboard.make(Spectrum.constant(0.25), inner, uv_scale=4.0)
    rng = np.random.default_rng(9)
    uv = _points(rng, 2000)
    got = TextureHarness(runner, [(board, "spectrum")]).lookup(0, uv, lambdas=GRID_LAMBDAS)
    st = uv * 4.0
    clear = np.all(np.abs(st - np.round(st)) > 1e-4, axis=1)
    even = (np.floor(st[:, 0]) + np.floor(st[:, 1])) % 2 == 0
    grey = half_sigmoid_spectrum(reflectance_coefficients(np.full(3, 0.5)), GRID_LAMBDAS)
    np.testing.assert_allclose(got[clear & even], 0.25, atol=1e-6)
    np.testing.assert_allclose(got[clear & ~even], np.broadcast_to(grey, got[clear & ~even].shape), atol=5e-5)


def test_scale_and_mix_compose_their_operands(runner):
    """pbrt-v4's semantics: scale = tex · scale, mix = (1 − amount) · tex1 + amount · tex2, each operand looked up at
    the point with its own placement and filter: an RGB bitmap scaled by a number and by a grey texture of another
    size, a spectrum mixed with a bitmap by a grey amount texture, and two grey textures mixed as a scalar."""
    rng = np.random.default_rng(12)
    rgb = rng.uniform(0.05, 0.95, (3, 4, 3))
    grey = rng.uniform(0.0, 1.0, (5, 2, 1))
    other = rng.uniform(0.0, 1.0, (2, 3, 1))
    image = bitmap.make(rgb, wrap="clamp")
    factor = bitmap.make(grey, raw=True, wrap="mirror", uv_scale=2.0)
    uses = [
        (scale.make(image, 0.5), "spectrum"),
        (scale.make(image, factor), "spectrum"),
        (mix.make(Spectrum.constant(0.25), image, factor), "spectrum"),
        (mix.make(bitmap.make(other, raw=True), factor, 0.3), "float"),
    ]
    harness = TextureHarness(runner, uses)
    uv = rng.uniform(0.0, 1.0, (400, 2))
    image_ref = bilinear(half_sigmoid_spectrum(reflectance_coefficients(rgb), GRID_LAMBDAS), uv, "clamp")
    factor_ref = bilinear(grey, uv * 2.0, "mirror")[:, :1]
    other_ref = bilinear(other, uv, "repeat")[:, :1]
    expected = [
        0.5 * image_ref,
        factor_ref * image_ref,
        (1.0 - factor_ref) * 0.25 + factor_ref * image_ref,
        np.repeat(0.7 * other_ref + 0.3 * factor_ref, 4, axis=1),
    ]
    for which, reference in enumerate(expected):
        got = harness.lookup(which, uv, lambdas=GRID_LAMBDAS)
        np.testing.assert_allclose(got, reference, atol=6e-5, err_msg=f"use {which}")
