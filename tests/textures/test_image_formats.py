"""Image formats read for textures beyond what Pillow and OpenEXR give: Radiance HDR (.hdr), checked against files
Mitsuba 3 writes and reads (an independent writer and reader) and against bytes laid out by hand from the format's
description (Ward 1991, "Real Pixels"); bad files reported as one line naming the file and key."""

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
