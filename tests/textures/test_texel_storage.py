"""Compact texel storage (docs/textures.md, Memory): 8- and 16-bit data files are stored as 8- and 16-bit integers
and read back exactly; half-float sigmoid coefficients stay within the stated colour difference of float ones
(CIEDE2000 by colour-science); the scene's texture budget is checked with the compact sizes, with the amount."""

import colour
import numpy as np
import pytest
from PIL import Image as PILImage
from tests.textures.lookup import HARNESS, TextureHarness, bilinear, pyramid, trilinear

import spectrace
from spectrace.core.contract import STORAGE_FLOAT, STORAGE_HALF, STORAGE_UNORM8, STORAGE_UNORM16
from spectrace.errors import SpectraceError
from spectrace.spectral import srgb_decode
from spectrace.spectral.rgb_texture import reflectance_coefficients
from spectrace.spectral.table import SpectrumTable
from spectrace.textures import TextureRows, bitmap
from spectrace.textures.storage import dimensionless


@pytest.fixture(scope="module")
def runner(kernel_runner):
    return kernel_runner(HARNESS)


def _centres(height: int, width: int) -> np.ndarray:
    y, x = np.mgrid[0:height, 0:width]
    return np.stack([(x.ravel() + 0.5) / width, (y.ravel() + 0.5) / height], axis=1)


def test_8_and_16_bit_data_files_are_stored_as_integers_and_read_exactly(runner, tmp_path):
    """A raw 8-bit grey PNG (a roughness map), a raw 16-bit one (a height map) and a raw 8-bit RGB normal map, written
    by Pillow: stored at 1, 2 and 3 bytes a texel, and each texel reads back as its code over 255 or 65535 (float32:
    within one rounding)."""
    rng = np.random.default_rng(30)
    codes8 = rng.integers(0, 256, (5, 7), dtype=np.uint8)
    codes16 = rng.integers(0, 65536, (4, 6), dtype=np.uint16)
    normals = rng.integers(0, 256, (3, 5, 3), dtype=np.uint8)
    PILImage.fromarray(codes8).save(tmp_path / "r8.png")
    PILImage.fromarray(codes16).save(tmp_path / "h16.png")
    PILImage.fromarray(normals).save(tmp_path / "n.png")
    uses = [
        (bitmap.make(tmp_path / "r8.png", raw=True, filter="nearest"), "float"),
        (bitmap.make(tmp_path / "h16.png", raw=True, filter="nearest"), "float"),
        (bitmap.make(tmp_path / "n.png", raw=True, filter="nearest"), "vector"),
    ]
    harness = TextureHarness(runner, uses)
    assert list(harness.rows["storage"]) == [STORAGE_UNORM8, STORAGE_UNORM16, STORAGE_UNORM8]
    for which, (codes, top) in enumerate([(codes8[..., None], 255.0), (codes16[..., None], 65535.0), (normals, 255.0)]):
        height, width = codes.shape[:2]
        got = harness.lookup(which, _centres(height, width))
        expected = (codes.reshape(-1, codes.shape[-1]) / top).astype(np.float32)
        channels = codes.shape[-1]
        np.testing.assert_allclose(got[:, :channels], expected, rtol=1.2e-7, atol=0, err_msg=f"texture {which}")
    rows = TextureRows(SpectrumTable(), [np.zeros((1, 4), np.float32)])
    for texture, kind in uses:
        rows.add(texture, kind)
    assert rows.bytes == 5 * 7 * 1 + 4 * 6 * 2 + 3 * 5 * 3


def test_8_bit_pyramid_levels_are_within_half_a_code(runner):
    """A trilinear 8-bit data texture: its coarser levels (averages) are rounded to 8 bits, so every lookup is within
    half a code step (1/510) of the float pyramid's, and none exceeds the largest texel (a roughness's bound)."""
    rng = np.random.default_rng(31)
    codes = rng.integers(0, 256, (16, 16, 1))
    image = codes / 255.0
    texture = bitmap.make(image, raw=True, filter="trilinear")
    harness = TextureHarness(runner, [(texture, "float")])
    assert harness.rows["storage"][0] == STORAGE_UNORM8
    uv = rng.uniform(-0.5, 1.5, (2000, 2))
    for footprint_texels in (0.0, 1.5, 3.0, 7.0, 40.0):
        got = harness.lookup(0, uv, footprint=footprint_texels / 16.0)[:, 0]
        expected = trilinear(pyramid(image), uv, footprint_texels / 16.0, "repeat")[:, 0]
        np.testing.assert_allclose(got, expected, atol=0.5 / 255.0 + 3e-6, rtol=0)
        assert got.max() <= codes.max() / 255.0 + 1e-7


def test_float_data_is_half_only_when_exact(runner):
    """Data of float values (a height map computed in float) stays float, since a bump map differentiates it; data
    whose values are all halves (an OpenEXR saved in half) is stored in half and read exactly."""
    rng = np.random.default_rng(32)
    floats = rng.uniform(0.0, 3.0, (4, 5, 1))
    halves = floats.astype(np.float16).astype(np.float64)
    harness = TextureHarness(
        runner,
        [
            (bitmap.make(floats, filter="nearest"), "float"),
            (bitmap.make(halves, filter="nearest"), "float"),
            (bitmap.make(halves), "float"),
        ],
    )
    assert list(harness.rows["storage"]) == [STORAGE_FLOAT, STORAGE_HALF, STORAGE_HALF]
    uv = _centres(4, 5)
    np.testing.assert_allclose(harness.lookup(0, uv)[:, 0], floats.ravel().astype(np.float32), rtol=0, atol=0)
    np.testing.assert_allclose(harness.lookup(1, uv)[:, 0], halves.ravel(), rtol=0, atol=0)
    # The bilinear blend of half texels is the blend of their exact values.
    points = rng.uniform(0.0, 1.0, (500, 2))
    np.testing.assert_allclose(
        harness.lookup(2, points)[:, 0], bilinear(halves, points, "repeat")[:, 0], atol=1e-5, rtol=0
    )


def test_emission_and_bands_storage_follows_the_stated_rule():
    """Spectral bands and emission RGB: half when the largest value lies in [2^-4, 65504] (each value then within a
    relative 2^-11 of itself) or when every value is a half already (a half OpenEXR: exact); float otherwise (a
    dark texture in float, whose values would fall below half's normal range; values beyond 65504)."""
    from spectrace.textures import spectral

    rng = np.random.default_rng(36)
    bands = np.arange(400.0, 701.0, 100.0)
    cases = {
        "bright": (rng.uniform(0.0, 0.9, (2, 3, 4)), STORAGE_HALF),
        "dark float": (rng.uniform(0.0, 0.03, (2, 3, 4)), STORAGE_FLOAT),
        "dark halves": (rng.uniform(0.0, 0.03, (2, 3, 4)).astype(np.float16).astype(np.float64), STORAGE_HALF),
    }
    rows = TextureRows(SpectrumTable(), [np.zeros((1, 4), np.float32)])
    for name, (values, expected) in cases.items():
        index = rows.add(spectral.make(values, bands), "spectrum")
        assert rows.array()["storage"][index] == expected, name
    index = rows.add(bitmap.make(np.full((2, 2, 3), 7e4)), "emission", basis=[0, 0, 0])
    assert rows.array()["storage"][index] == STORAGE_FLOAT


def test_a_texture_freed_after_its_row_was_added_does_not_lend_that_row_to_a_new_one(monkeypatch):
    """A texture's row is found again by the texture's identity. Textures made and dropped one after another, as a
    scene built in pieces may, reuse each other's memory and so, at times, their id(): each must still get a row of
    its own, with its own size. The interpreter reuses ids only at times, so the second half makes it certain: every
    texture's id() the same, as a freed texture's is for the next one."""
    import spectrace.textures
    from spectrace.textures import spectral

    bands = np.arange(400.0, 701.0, 100.0)

    def rows_of_dropped_textures() -> TextureRows:
        rows = TextureRows(SpectrumTable(), [np.zeros((1, 4), np.float32)])
        for width in range(1, 41):
            texture = spectral.make(np.full((2, width, 4), 0.5), bands)
            assert rows.add(texture, "spectrum") == width - 1
            del texture
        return rows

    assert list(rows_of_dropped_textures().array()["width"]) == list(range(1, 41))
    monkeypatch.setattr(spectrace.textures, "id", lambda _: 1, raising=False)
    assert list(rows_of_dropped_textures().array()["width"]) == list(range(1, 41))


def _lab(coefficients: np.ndarray, dimensionless_form: bool) -> np.ndarray:
    """CIELAB under D65 (colour-science's CMFs and illuminant, 1 nm) of sigmoid spectra S(poly)."""
    shape = colour.SpectralShape(360, 830, 1)
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"].copy().align(shape).values
    d65 = colour.SDS_ILLUMINANTS["D65"].copy().align(shape).values
    weights = cmfs * d65[:, None]
    weights /= weights[:, 1].sum()
    lam = np.arange(360.0, 831.0)
    x_of = (lam - 595.0) / 235.0 if dimensionless_form else lam
    c = np.asarray(coefficients, np.float64)
    x = (c[:, :1] * x_of + c[:, 1:2]) * x_of + c[:, 2:3]
    spectra = 0.5 + x / (2.0 * np.sqrt(1.0 + x * x))
    return colour.XYZ_to_Lab(spectra @ weights, colour.XYZ_to_xy(weights.sum(axis=0)))


def test_half_sigmoid_coefficients_are_within_the_stated_colour_difference():
    """The stated bound: a texel whose dimensionless coefficients are stored in half has its float texel's colour
    to within CIEDE2000 0.35 (measured at most 0.32 over 1.2 million colours of the RGB cube, table nodes, dark and
    saturated ones) — on random, dark and 8-bit-coded colours here. The same rounding of the coefficients in powers
    of λ in nm would not be: it misses by more than ΔE2000 1, which is why they are rewritten first."""
    rng = np.random.default_rng(33)
    rgb = np.concatenate(
        [rng.random((4000, 3)), rng.random((2000, 3)) * 0.02, srgb_decode(rng.integers(1, 255, (4000, 3)) / 255.0)]
    )
    nm = reflectance_coefficients(rgb)
    reference = _lab(nm.astype(np.float32), dimensionless_form=False)
    half = dimensionless(nm).astype(np.float16)
    assert np.all(np.isfinite(half))
    stored = colour.delta_E(reference, _lab(half, dimensionless_form=True), method="CIE 2000")
    assert stored.max() < 0.35
    naive = colour.delta_E(reference, _lab(nm.astype(np.float16), dimensionless_form=False), method="CIE 2000")
    assert naive.max() > 1.0


def _scene(texture, kind: str):
    from spectrace.scene.model import Camera, Scene

    material = spectrace.conductor("Au", roughness=texture) if kind == "float" else spectrace.diffuse(texture)
    return Scene(
        camera=Camera(origin=(0.0, 0.0, 3.0), target=(0.0, 0.0, 0.0)),
        width=4,
        height=4,
        shapes=[spectrace.shape("rectangle", material)],
    )


def test_the_budget_counts_compact_texels(monkeypatch):
    """With the budget set to 1000 bytes: a 24 × 24 raw 8-bit roughness map (576 bytes as 8-bit; 2304 as float)
    fits; a 40 × 40 one (1600 bytes) is refused with its amount before conversion; an RGB reflectance predicted in
    half (12 × 12 × 3 × 2 = 864 bytes) whose coefficients need float (1728 bytes) is refused once converted, with
    the float amount."""
    import spectrace.textures as textures
    from spectrace.engine.scene_buffers import build_scene_buffers

    monkeypatch.setattr(textures, "MAX_TEXTURE_BYTES", 1000)
    small = bitmap.make(np.random.default_rng(34).integers(0, 256, (24, 24)) / 255.0, raw=True)
    build_scene_buffers(_scene(small, "float"))
    large = bitmap.make(np.random.default_rng(35).integers(0, 256, (40, 40)) / 255.0, raw=True)
    with pytest.raises(SpectraceError, match=r"textures need 1\.6 KiB of device memory.*at most 1000 B"):
        build_scene_buffers(_scene(large, "float"))
    dark = np.full((12, 12, 3), 0.5)
    dark[0, 0] = [1e-9, 0.0, 0.0]
    with pytest.raises(SpectraceError, match=r"textures need 1\.7 KiB of device memory.*at most 1000 B"):
        build_scene_buffers(_scene(bitmap.make(dark), "spectrum"))
