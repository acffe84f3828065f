"""Texture uplift (many colours at once, from the coefficient table) checked through colour-science's colorimetry."""

import itertools
import shutil
import subprocess
import sys
import textwrap

import colour
import numpy as np
import pytest

from spectrace.errors import SpectraceError
from spectrace.spectral import rgb_texture, uplift_table
from spectrace.spectral.colorimetry import XYZ_TO_LINEAR_SRGB, srgb_decode
from spectrace.spectral.grid import GRID_NM
from spectrace.spectral.illuminants import d65_normalised
from spectrace.spectral.rgb_texture import (
    illuminant_texture_coefficients,
    reflectance_coefficients,
    texture_illuminant_coefficients,
    texture_reflectance_coefficients,
)
from spectrace.spectral.uplift import sigmoid_polynomial_spectrum, uplift_reflectance

pytestmark = pytest.mark.filterwarnings("ignore:Aligning")  # colour-science resampling notices

CMFS = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
D65 = colour.SDS_ILLUMINANTS["D65"]
GRID_SHAPE = colour.SpectralShape(360, 830, 1)
SRGB_TO_XYZ = np.linalg.inv(XYZ_TO_LINEAR_SRGB)
# The white of colour-science's integration: a perfect reflector under D65 (Y = 1).
WHITE_XYZ = (
    colour.sd_to_XYZ(colour.SpectralDistribution(np.ones(GRID_NM.size), GRID_NM), CMFS, D65, method="Integration") / 100
)
WHITE_XY = colour.XYZ_to_xy(WHITE_XYZ)

# The Delta E (CIE 1976) the table reaches, measured over 10^5 random colours and the cube's edges (max 0.09 and
# 0.07; 0.15 at worst, near white); the limit leaves room for colour-science's integration (~0.005 apart).
TABLE_DELTA_E = 0.2
EMISSION_TOLERANCE = 2e-3  # of the brightest channel


def spectra(coefficients: np.ndarray) -> np.ndarray:
    """S(c0 lambda^2 + c1 lambda + c2) on the grid for rows of coefficients, via uplift's one-colour evaluation."""
    return np.array([sigmoid_polynomial_spectrum(row) for row in coefficients.reshape(-1, 3)])


def colour_science_delta_e(values: np.ndarray, rgb: np.ndarray) -> np.ndarray:
    """CIE 1976 Delta E between reflectances on our grid under D65 (colour-science's integration) and linear sRGB."""
    xyz = colour.colorimetry.sd_to_XYZ_integration(values, CMFS, D65, shape=GRID_SHAPE) / 100
    target = rgb.reshape(-1, 3) @ SRGB_TO_XYZ.T
    return colour.delta_E(colour.XYZ_to_Lab(xyz, WHITE_XY), colour.XYZ_to_Lab(target, WHITE_XY), method="CIE 1976")


def cube_edges(points_per_edge: int = 33) -> np.ndarray:
    corners = np.array(list(itertools.product([0.0, 1.0], repeat=3)))
    s = np.linspace(0.0, 1.0, points_per_edge)[:, None]
    edges = [
        corners[a] * (1 - s) + corners[b] * s
        for a, b in itertools.combinations(range(8), 2)
        if np.abs(corners[a] - corners[b]).sum() == 1
    ]
    return np.concatenate(edges)


@pytest.fixture(scope="module", autouse=True)
def cold_built_table(tmp_path_factory):
    """The real coefficient table, built here from an empty cache folder as on a fresh machine (and in CI), so that
    every test below uses what the build makes today rather than a table some older build left on disk."""
    folder = tmp_path_factory.mktemp("cold-cache")
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("SPECTRACE_CACHE_DIR", str(folder))
        uplift_table.coefficient_table.cache_clear()
        assert not uplift_table.table_path().exists()
        yield uplift_table.coefficient_table()
    uplift_table.coefficient_table.cache_clear()


@pytest.mark.slow
def test_cold_build_writes_the_table_it_returns(cold_built_table):
    path = uplift_table.table_path()
    assert path.is_file()
    np.testing.assert_array_equal(
        uplift_table._deserialise(path.read_bytes(), uplift_table.TABLE_RESOLUTION), cold_built_table
    )


@pytest.mark.slow
def test_table_nodes_are_the_one_colour_fits(cold_built_table):
    """Each node is fitted to the colorimetry `uplift_reflectance` fits one colour to: at nodes whose spectrum the
    colour pins down (not the darkest, where many spectra give one colour, nor next to white) both give the same
    spectrum, to the float32 rounding of the stored coefficients."""
    resolution = uplift_table.TABLE_RESOLUTION
    nodes = uplift_table.z_nodes(resolution)
    rng = np.random.default_rng(13)
    for _ in range(40):
        largest, z_index = rng.integers(0, 3), rng.integers(16, resolution)  # z from 0.07 up
        v_index, u_index = rng.integers(0, resolution - 2, size=2)  # u, v below 0.998
        rgb = uplift_table.node_colours(resolution, z_index)[largest, v_index, u_index]
        stored = cold_built_table[largest, z_index, v_index, u_index].astype(np.float64) / np.sqrt(nodes[z_index])
        table_spectrum = spectra(rgb_texture._dimensionless_to_nm(stored[None]))[0]
        fitted, _ = uplift_reflectance(rgb)
        assert np.abs(table_spectrum - fitted.values).max() < 2e-4, rgb


def test_array_integration_is_colour_science_sd_to_xyz():
    values = np.random.default_rng(3).random((3, GRID_NM.size))
    bulk = colour.colorimetry.sd_to_XYZ_integration(values, CMFS, D65, shape=GRID_SHAPE)
    for row, xyz in zip(values, bulk):
        sd = colour.SpectralDistribution(row, GRID_NM)
        np.testing.assert_allclose(xyz, colour.sd_to_XYZ(sd, CMFS, D65, method="Integration"), rtol=1e-12)


def test_random_colours_round_trip():
    rgb = np.random.default_rng(1).random((4000, 3))
    rgb[:1000] *= 0.02  # dark colours, where the coefficients grow fastest
    values = spectra(reflectance_coefficients(rgb))
    assert values.min() >= 0.0 and values.max() <= 1.0
    delta_e = colour_science_delta_e(values, rgb)
    assert delta_e.max() < TABLE_DELTA_E


@pytest.mark.parametrize("kind", ["near white", "saturated"])
def test_hard_colours_round_trip(kind):
    rng = np.random.default_rng(14)
    if kind == "near white":
        rgb = 1.0 - 0.02 * rng.random((1500, 3))
    else:
        rgb = rng.random((1500, 3))
        rgb[np.arange(len(rgb)), rng.integers(0, 3, len(rgb))] *= 0.01
    values = spectra(reflectance_coefficients(rgb))
    assert values.min() >= 0.0 and values.max() <= 1.0
    assert colour_science_delta_e(values, rgb).max() < TABLE_DELTA_E


def test_corners_and_edges_round_trip():
    rgb = cube_edges()
    coefficients = reflectance_coefficients(rgb)
    values = spectra(coefficients)
    assert values.min() >= 0.0 and values.max() <= 1.0
    assert colour_science_delta_e(values, rgb).max() < TABLE_DELTA_E
    # Black and white are uplift_reflectance's saturated constants (0 and 1 to 2.5e-13; exact in float32).
    for rgb in (np.zeros(3), np.ones(3)):
        np.testing.assert_array_equal(reflectance_coefficients(rgb), uplift_reflectance(rgb)[1])
        assert np.abs(spectra(reflectance_coefficients(rgb)) - rgb[0]).max() < 1e-12


def test_image_shape_is_kept():
    rgb = np.random.default_rng(2).random((5, 7, 3))
    coefficients = reflectance_coefficients(rgb)
    assert coefficients.shape == (5, 7, 3) and coefficients.dtype == np.float64
    np.testing.assert_array_equal(coefficients[3, 4], reflectance_coefficients(rgb[3, 4]))


@pytest.mark.parametrize("seed", range(3))
def test_agrees_with_the_one_colour_fit(seed):
    rgb = np.random.default_rng(10 + seed).random((8, 3))
    table_spectra = spectra(reflectance_coefficients(rgb))
    for colour_rgb, table_spectrum in zip(rgb, table_spectra):
        fitted, _ = uplift_reflectance(colour_rgb)
        # Delta E ~0.05 apart: the same spectrum up to a small change of shape.
        assert np.abs(fitted.values - table_spectrum).max() < 0.005


def test_a_colour_gives_the_same_bits_alone_or_in_any_batch():
    rng = np.random.default_rng(4)
    rgb = rng.random((2000, 3))
    together = reflectance_coefficients(rgb)
    np.testing.assert_array_equal(reflectance_coefficients(rgb.copy()), together)
    for index in (0, 777, 1999):
        np.testing.assert_array_equal(reflectance_coefficients(rgb[index]), together[index])
    shuffled = rng.permutation(len(rgb))
    np.testing.assert_array_equal(reflectance_coefficients(rgb[shuffled]), together[shuffled])


def test_repeated_colours_are_computed_once_with_the_same_bits(monkeypatch):
    rng = np.random.default_rng(12)
    palette = rng.random((200, 3))
    texture = palette[rng.integers(0, len(palette), (256, 160))]  # 40960 texels, 200 colours
    computed = []
    original = rgb_texture._distinct_reflectance_rows
    monkeypatch.setattr(
        rgb_texture, "_distinct_reflectance_rows", lambda rgb: computed.append(len(rgb)) or original(rgb)
    )
    coefficients = reflectance_coefficients(texture)
    assert computed == [len(np.unique(texture.reshape(-1, 3), axis=0))]
    one_by_one = np.array([reflectance_coefficients(colour_rgb) for colour_rgb in palette])
    index = np.array([[np.flatnonzero((palette == texel).all(axis=1))[0] for texel in row] for row in texture[:4]])
    np.testing.assert_array_equal(coefficients[:4], one_by_one[index])
    # A noise-like texture (every texel its own colour) is not grouped; a hash collision falls back to no grouping.
    computed.clear()
    noise = rng.random((40000, 3))
    expected = reflectance_coefficients(noise)
    monkeypatch.setattr(rgb_texture, "_colour_keys", lambda rgb: np.zeros(len(rgb), dtype=np.uint64))
    np.testing.assert_array_equal(reflectance_coefficients(noise), expected)
    np.testing.assert_array_equal(reflectance_coefficients(texture), coefficients)
    assert computed == [40000, 40000, texture.shape[0] * texture.shape[1]]


@pytest.mark.parametrize(
    "bad, message",
    [
        (np.array([[0.2, 1.2, 0.3]]), "must lie in"),
        (np.array([[0.2, -0.1, 0.3]]), "negative"),
        (np.array([[0.2, np.nan, 0.3]]), "finite"),
        (np.ones((4, 2)), "three channels"),
        ("red", "array of numbers"),
    ],
)
def test_invalid_reflectance_raises_naming_where(bad, message):
    with pytest.raises(SpectraceError, match=message) as error:
        reflectance_coefficients(bad, where="scene.toml: textures.wall.file")
    assert error.value.where == "scene.toml: textures.wall.file"


def test_emission_reproduces_its_rgb():
    rgb = np.random.default_rng(5).random((44, 3))
    rgb[20:40] *= 12.0  # brighter than a reflectance can be
    rgb[40:] = [[1.0, 1.0, 1.0], [0.0, 0.0, 0.0], [0.0, 0.0, 3.0], [2.0, 2.0, 0.0]]
    coefficients, multiplier = illuminant_texture_coefficients(rgb)
    assert coefficients.shape == rgb.shape and multiplier.shape == rgb.shape[:1]
    emission = multiplier[:, None] * spectra(coefficients) * d65_normalised().values
    assert emission.min() >= 0.0
    # Film colour: colour-science's equal-energy normalisation (no illuminant) is the film's XYZ.
    xyz = colour.colorimetry.sd_to_XYZ_integration(emission, CMFS, shape=GRID_SHAPE) / 100
    film_rgb = xyz @ XYZ_TO_LINEAR_SRGB.T
    assert np.all(np.abs(film_rgb - rgb) <= EMISSION_TOLERANCE * rgb.max(axis=1, keepdims=True))
    assert multiplier[41] == 0.0


def test_negative_emission_raises():
    with pytest.raises(SpectraceError, match="negative"):
        illuminant_texture_coefficients(np.array([[1.0, -0.5, 0.0]]), where="lights[0].texture")


# ---------------------------------------------------------------- sRGB decoding


def test_every_8_bit_code_decodes_as_colour_science():
    codes = np.arange(256, dtype=np.uint8)
    expected = colour.cctf_decoding(codes / 255.0, function="sRGB")
    np.testing.assert_allclose(srgb_decode(codes, bits=8), expected, rtol=1e-14, atol=0)
    image = np.random.default_rng(6).integers(0, 256, (4, 5, 3), dtype=np.uint8)
    np.testing.assert_array_equal(srgb_decode(image, bits=8), srgb_decode(codes, bits=8)[image])


def test_16_bit_codes_decode_as_colour_science():
    codes = np.unique(np.concatenate([np.arange(0, 65536, 97), np.arange(0, 300), [65534, 65535]])).astype(np.uint16)
    expected = colour.cctf_decoding(codes / 65535.0, function="sRGB")
    np.testing.assert_allclose(srgb_decode(codes, bits=16), expected, rtol=1e-14, atol=0)
    assert srgb_decode(np.array([65535], dtype=np.uint16), bits=16)[0] == 1.0


def test_float_images_decode_as_colour_science():
    encoded = np.random.default_rng(7).random((6, 3))
    np.testing.assert_allclose(srgb_decode(encoded), colour.cctf_decoding(encoded, function="sRGB"), rtol=1e-14)


@pytest.mark.parametrize(
    "codes, bits",
    [(np.array([1.5]), 8), (np.array([256]), 8), (np.array([-1]), 16), (np.array([3], dtype=np.uint8), 12)],
)
def test_bad_codes_are_refused(codes, bits):
    with pytest.raises(ValueError):
        srgb_decode(codes, bits=bits)


# ---------------------------------------------------------------- the table's cache file

SMALL = 6  # a table this coarse builds in a second or two: enough for the cache file's behaviour


@pytest.fixture
def cache_folder(tmp_path, monkeypatch):
    monkeypatch.setenv("SPECTRACE_CACHE_DIR", str(tmp_path))
    return tmp_path


def test_table_is_written_then_read_back(cache_folder):
    built = uplift_table.load_or_build_table(SMALL)
    path = uplift_table.table_path(SMALL)
    assert path.is_relative_to(cache_folder) and path.is_file()
    before = path.stat().st_mtime_ns
    np.testing.assert_array_equal(uplift_table.load_or_build_table(SMALL), built)
    assert path.stat().st_mtime_ns == before  # read, not rebuilt


@pytest.mark.parametrize(
    "damage",
    [
        lambda blob: blob[: len(blob) // 2],  # truncated
        lambda blob: blob[:-9] + bytes([blob[-9] ^ 0x40]) + blob[-8:],  # one flipped bit in the values
        lambda blob: b"not a table at all",
        lambda blob: blob.replace(b'"format": %d' % uplift_table._FORMAT, b'"format": 99'),  # another version
        lambda blob: b"",
    ],
)
def test_damaged_table_file_is_rebuilt(cache_folder, damage):
    built = uplift_table.load_or_build_table(SMALL)
    path = uplift_table.table_path(SMALL)
    blob = path.read_bytes()
    damaged = damage(blob)
    assert damaged != blob
    path.write_bytes(damaged)
    np.testing.assert_array_equal(uplift_table.load_or_build_table(SMALL), built)
    # The file is whole again: the next load reads it.
    assert uplift_table._deserialise(path.read_bytes(), SMALL) is not None


def test_unwritable_cache_folder_still_gives_the_table(tmp_path, monkeypatch):
    blocker = tmp_path / "a file"
    blocker.write_text("")
    monkeypatch.setenv("SPECTRACE_CACHE_DIR", str(blocker))
    with pytest.warns(UserWarning, match="could not cache"):
        table = uplift_table.load_or_build_table(SMALL)
    assert table.shape == (3, SMALL, SMALL, SMALL, 3) and np.all(np.isfinite(table))


# ---------------------------------------------------------------- the per-texture cache


@pytest.fixture
def texture_cache(tmp_path, monkeypatch):
    """A fresh cache folder holding a copy of the real coefficient table (a subprocess would otherwise build it)."""
    uplift_table.coefficient_table()
    table_file = uplift_table.table_path()
    monkeypatch.setenv("SPECTRACE_CACHE_DIR", str(tmp_path))
    if table_file.is_file():
        uplift_table.table_path().parent.mkdir(parents=True)
        shutil.copyfile(table_file, uplift_table.table_path())
    rgb_texture._cache.clear_memory()
    yield tmp_path / "uplift" / "textures"
    rgb_texture._cache.clear_memory()


def _refuse_to_fit(monkeypatch):
    def refuse(rgb):
        raise AssertionError("refitted a cached texture")

    monkeypatch.setattr(rgb_texture, "_reflectance_rows", refuse)


def test_texture_is_fitted_once_per_process(texture_cache, monkeypatch):
    image = np.random.default_rng(8).random((16, 16, 3))
    first = texture_reflectance_coefficients(image)
    np.testing.assert_array_equal(first, reflectance_coefficients(image))
    assert not first.flags.writeable
    _refuse_to_fit(monkeypatch)
    assert texture_reflectance_coefficients(image.copy()) is first


def test_texture_fitted_in_another_process_is_read_from_disk(texture_cache, monkeypatch):
    script = textwrap.dedent(
        """
        import numpy as np
        from spectrace.spectral.rgb_texture import texture_reflectance_coefficients
        image = np.random.default_rng(9).random((16, 16, 3))
        np.save("expected.npy", texture_reflectance_coefficients(image))
        """
    )
    folder = texture_cache.parent.parent  # the cache folder, a scratch folder of this test's own
    subprocess.run([sys.executable, "-c", script], cwd=folder, check=True, timeout=600)
    assert len(list(texture_cache.glob("*.bin"))) == 1
    _refuse_to_fit(monkeypatch)
    image = np.random.default_rng(9).random((16, 16, 3))
    np.testing.assert_array_equal(texture_reflectance_coefficients(image), np.load(folder / "expected.npy"))


def test_a_different_texture_is_not_mistaken_for_a_cached_one(texture_cache):
    image = np.random.default_rng(10).random((8, 8, 3))
    texture_reflectance_coefficients(image)
    changed = image.copy()
    changed[3, 3, 1] = np.nextafter(changed[3, 3, 1], 0.0)
    np.testing.assert_array_equal(texture_reflectance_coefficients(changed), reflectance_coefficients(changed))
    # An emission texture of the same pixels is another entry.
    coefficients, multiplier = texture_illuminant_coefficients(image)
    expected = illuminant_texture_coefficients(image)
    np.testing.assert_array_equal(coefficients, expected[0])
    np.testing.assert_array_equal(multiplier, expected[1])


def test_damaged_texture_cache_file_is_recomputed(texture_cache):
    image = np.random.default_rng(11).random((8, 8, 3))
    expected = texture_reflectance_coefficients(image)
    (path,) = texture_cache.glob("*.bin")
    blob = path.read_bytes()
    path.write_bytes(blob[:-3] + bytes([blob[-3] ^ 1]) + blob[-2:])
    rgb_texture._cache.clear_memory()
    np.testing.assert_array_equal(texture_reflectance_coefficients(image), expected)
    assert rgb_texture._deserialise(path.read_bytes(), path.stem, [image.shape]) is not None


def test_texture_caches_are_bounded(texture_cache, monkeypatch):
    images = [np.random.default_rng(20 + k).random((8, 8, 3)) for k in range(4)]
    one_entry = images[0].nbytes
    monkeypatch.setattr(rgb_texture, "MEMORY_CACHE_BYTES", 2 * one_entry)
    monkeypatch.setattr(rgb_texture, "DISK_CACHE_BYTES", 2 * (one_entry + 400))
    for image in images:
        texture_reflectance_coefficients(image)
    assert len(rgb_texture._cache._memory) == 2
    files = list(texture_cache.glob("*.bin"))
    assert len(files) == 2 and sum(f.stat().st_size for f in files) <= 2 * (one_entry + 400)
    # The newest two stayed.
    _refuse_to_fit(monkeypatch)
    rgb_texture._cache.clear_memory()
    texture_reflectance_coefficients(images[3])
    texture_reflectance_coefficients(images[2])
