"""Image formats read for textures beyond what Pillow and OpenEXR give: Radiance HDR (.hdr), checked against files
Mitsuba 3 writes and reads (an independent writer and reader) and against bytes laid out by hand from the format's
description (Ward 1991, "Real Pixels"); 16-bit colour PNGs at their 16 bits, against Mitsuba's writer and files laid
out by hand with every PNG filter; bad files reported as one line naming the file and key."""

import numpy as np
import pytest
from tests.textures.test_texture_scenes import _scene

from cli_runner import run_in_process
from spectrace.io.images import read_environment_map
from spectrace.scene import load_scene
from spectrace.textures import bitmap


def _mitsuba(name: str):
    mi = pytest.importorskip("mitsuba", reason=f"Mitsuba 3 (a test extra) writes the reference {name} files")
    mi.set_variant("scalar_rgb")
    return mi


def _quantum(values: np.ndarray) -> np.ndarray:
    """One mantissa step of each pixel's shared exponent: 2^(e − 8) with 2^(e − 1) <= the largest channel < 2^e."""
    largest = values.max(axis=-1, keepdims=True)
    with np.errstate(divide="ignore"):
        exponent = np.floor(np.log2(np.where(largest > 0, largest, 1.0))) + 1
    return np.where(largest > 0, 2.0 ** (exponent - 8), 0.0)


def test_hdr_texture_is_what_mitsuba_reads(tmp_path):
    """A bitmap texture from a .hdr Mitsuba 3 wrote (values over 12 stops, constant rows and a black one, so that the
    writer's run-length encoding is exercised): each texel is what Mitsuba's own reader gives for the file, within
    one mantissa step below the value written (the writer truncates), as stored (not sRGB-decoded, even without
    raw); an `envmap` reads the same values."""
    mi = _mitsuba(".hdr")
    rng = np.random.default_rng(40)
    values = np.exp(rng.normal(0.0, 2.0, (37, 53, 3)))
    values[5:9] = 0.25
    values[10] = 0.0
    values[11, 3:40] = [1000.0, 0.002, 7.0]
    mi.Bitmap(values.astype(np.float32), mi.Bitmap.PixelFormat.RGB).write(str(tmp_path / "sky.hdr"))
    got = bitmap.make(tmp_path / "sky.hdr").values
    np.testing.assert_array_equal(got, np.asarray(mi.Bitmap(str(tmp_path / "sky.hdr")), np.float32))
    below = values.astype(np.float32) - got
    assert np.all(below >= 0.0) and np.all(below < _quantum(values) * (1 + 1e-6) + 1e-30)
    np.testing.assert_array_equal(read_environment_map(tmp_path / "sky.hdr", "scene.toml: lights[0].file"), got)


def _rgbe_file(resolution: bytes, pixels: bytes, format_line: bytes = b"FORMAT=32-bit_rle_rgbe\n") -> bytes:
    return b"#?RADIANCE\n# hand-made\n" + format_line + b"EXPOSURE=1.0\n\n" + resolution + b"\n" + pixels


def test_hand_made_hdr_texture_flat_and_run_length_rows(tmp_path):
    """Two rows of 10 pixels in a scene file: one flat (4 bytes a pixel), one run-length encoded (2, 2, width, then
    each component as runs: a count above 128 repeats the next byte, any other count is that many literals);
    m · 2^(e − 136), black where e = 0."""
    flat = bytes(np.array([[k, 2 * k, 127 - k, 129 if k else 0] for k in range(10)], np.uint8).ravel())
    red = bytes([128 + 10, 100])  # ten of 100
    green = bytes([4, 1, 2, 3, 4, 128 + 6, 50])  # four literals, six of 50
    blue = bytes([10]) + bytes(range(10))
    exponent = bytes([128 + 10, 129])  # 2^(129 − 136) = 1/128
    encoded = bytes([2, 2, 0, 10]) + red + green + blue + exponent
    (tmp_path / "hand.hdr").write_bytes(_rgbe_file(b"-Y 2 +X 10", flat + encoded))
    scene = load_scene(_scene(tmp_path, '{ texture = "bitmap", file = "hand.hdr", filter = "nearest" }'))
    values = scene.shapes[0].material.reflectance.values
    k = np.arange(10.0)
    first = np.stack([k, 2 * k, 127 - k], axis=-1) / 128.0
    first[0] = 0.0
    second = np.stack([np.full(10, 100.0), [1, 2, 3, 4] + [50] * 6, k], axis=-1) / 128.0
    np.testing.assert_array_equal(values, np.stack([first, second]).astype(np.float32))


@pytest.mark.parametrize(
    ("content", "words"),
    [
        (b"P6\n2 2\n255\n" + bytes(12), "is not a Radiance HDR image"),
        (_rgbe_file(b"-Y 2 +X 3", bytes(8)), "ends before its last row"),
        (_rgbe_file(b"-Y 1 +X 1", bytes(4), b"FORMAT=32-bit_rle_xyze\n"), "(only RGBE)"),
        (_rgbe_file(b"+X 1 -Y 1", bytes(4)), "only '-Y height +X width' images are read"),
        (_rgbe_file(b"-Y 1 +X 10", bytes([2, 2, 0, 10, 128 + 20, 1])), "a run overflows row 0"),
    ],
)
def test_bad_hdr_texture_is_one_line(tmp_path, monkeypatch, capsys, content, words):
    (tmp_path / "bad.hdr").write_bytes(content)
    scene = _scene(tmp_path, '{ texture = "bitmap", file = "bad.hdr" }')
    code, err = run_in_process(monkeypatch, capsys, ["render", str(scene), "-o", str(tmp_path / "x.png")])
    assert code != 0
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in err, err
    assert lines[0].startswith(f"error: {scene}: materials.m.reflectance.file: "), lines[0]
    assert words in lines[0] and "bad.hdr" in lines[0]


# ---------------------------------------------------------------- 16-bit colour PNGs


def _mitsuba_png16(path, samples: np.ndarray):
    mi = _mitsuba("16-bit PNG")
    formats = {2: mi.Bitmap.PixelFormat.YA, 3: mi.Bitmap.PixelFormat.RGB, 4: mi.Bitmap.PixelFormat.RGBA}
    mi.Bitmap(np.ascontiguousarray(samples, np.uint16), formats[samples.shape[-1]]).write(str(path))
    return path


def test_16_bit_rgb_gradient_keeps_its_65536_levels(tmp_path):
    """A 256 × 256 RGB gradient through every 16-bit code (red rising, green falling, blue constant), written by
    Mitsuba 3: read as a bitmap texture (raw), each sample is its code over 65535 exactly, 65536 distinct levels."""
    codes = np.arange(65536, dtype=np.uint16).reshape(256, 256)
    samples = np.stack([codes, 65535 - codes, np.full_like(codes, 12345)], axis=-1)
    _mitsuba_png16(tmp_path / "gradient.png", samples)
    scene = load_scene(_scene(tmp_path, '{ texture = "bitmap", file = "gradient.png", raw = true }'))
    values = scene.shapes[0].material.reflectance.values
    assert values.shape == (256, 256, 3)
    np.testing.assert_array_equal(values, (samples / 65535.0).astype(np.float32))
    assert len(np.unique(values[..., 0])) == 65536


@pytest.mark.parametrize("samples_per_pixel", [2, 4])
def test_16_bit_png_with_alpha_drops_it_at_full_precision(tmp_path, samples_per_pixel):
    """Grey + alpha and RGBA at 16 bits (random codes, Mitsuba's writer): the colour samples exactly, alpha dropped;
    sRGB-decoded unless raw (colour-science's decoding of the codes over 65535)."""
    import colour

    samples = np.random.default_rng(42).integers(0, 65536, (13, 21, samples_per_pixel)).astype(np.uint16)
    _mitsuba_png16(tmp_path / "a.png", samples)
    colour_samples = samples[..., :1] if samples_per_pixel == 2 else samples[..., :3]
    raw = load_scene(_scene(tmp_path, '{ texture = "bitmap", file = "a.png", raw = true }'))
    expected = (colour_samples / 65535.0).astype(np.float32)
    np.testing.assert_array_equal(raw.shapes[0].material.reflectance.values, expected)
    decoded = load_scene(_scene(tmp_path, '{ texture = "bitmap", file = "a.png" }'))
    np.testing.assert_allclose(
        decoded.shapes[0].material.reflectance.values,
        colour.cctf_decoding(colour_samples / 65535.0, function="sRGB"),
        atol=1e-6,
    )


def _filtered_row(row: bytes, above: bytes, kind: int, bpp: int) -> bytes:
    """One scanline filtered by PNG filter `kind` (W3C PNG, 3rd edition, section 7.3), from the definitions."""
    out = bytearray()
    for i, x in enumerate(row):
        a = row[i - bpp] if i >= bpp else 0
        b = above[i] if above else 0
        c = above[i - bpp] if above and i >= bpp else 0
        if kind == 0:
            predictor = 0
        elif kind == 1:
            predictor = a
        elif kind == 2:
            predictor = b
        elif kind == 3:
            predictor = (a + b) // 2
        else:
            p = a + b - c
            pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
            predictor = a if pa <= pb and pa <= pc else (b if pb <= pc else c)
        out.append((x - predictor) % 256)
    return bytes([kind]) + bytes(out)


def _hand_png16(samples: np.ndarray, interlace: bool) -> bytes:
    """A 16-bit RGB PNG laid out by hand: every filter type in turn, Adam7 passes when interlaced."""
    import struct
    import zlib

    height, width, _ = samples.shape
    passes = ((0, 0, 8, 8), (4, 0, 8, 8), (0, 4, 4, 8), (2, 0, 4, 4), (0, 2, 2, 4), (1, 0, 2, 2), (0, 1, 1, 2))
    images = [samples[y0::dy, x0::dx] for x0, y0, dx, dy in passes] if interlace else [samples]
    data, kind = b"", 0
    for image in images:
        if image.size == 0:
            continue
        above = b""
        for row in image:
            raw = row.astype(">u2").tobytes()
            data += _filtered_row(raw, above, kind % 5, 6)
            above, kind = raw, kind + 1

    def chunk(name: bytes, payload: bytes) -> bytes:
        return struct.pack(">I", len(payload)) + name + payload + struct.pack(">I", zlib.crc32(name + payload))

    header = struct.pack(">IIBBBBB", width, height, 16, 2, 0, 0, int(interlace))
    return b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", zlib.compress(data)) + chunk(b"IEND", b"")


@pytest.mark.parametrize("interlace", [False, True])
def test_16_bit_png_every_filter_and_adam7(tmp_path, interlace):
    """Scanlines filtered by each of the five filters in turn, plain and Adam7-interlaced (an odd size, so some passes
    are narrow): every sample read back exactly."""
    from spectrace.io.png16 import read_png16

    samples = np.random.default_rng(43).integers(0, 65536, (11, 13, 3)).astype(np.uint16)
    samples[4:7] = samples[3]  # repeated rows: Up and Paeth predict exactly there
    (tmp_path / "h.png").write_bytes(_hand_png16(samples, interlace))
    np.testing.assert_array_equal(read_png16(tmp_path / "h.png"), samples)


def test_bad_16_bit_png_is_one_line(tmp_path, monkeypatch, capsys):
    good = _hand_png16(np.zeros((4, 4, 3), np.uint16), False)
    (tmp_path / "cut.png").write_bytes(good[: len(good) // 2])
    scene = _scene(tmp_path, '{ texture = "bitmap", file = "cut.png" }')
    code, err = run_in_process(monkeypatch, capsys, ["render", str(scene), "-o", str(tmp_path / "x.png")])
    assert code != 0
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in err, err
    assert lines[0].startswith(f"error: {scene}: materials.m.reflectance.file: cannot read texture"), lines[0]
