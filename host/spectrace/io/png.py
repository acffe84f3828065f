"""PNG output: 8-bit sRGB (transfer curve applied, values clipped to [0, 1]) with metadata as text chunks.

Written here with zlib (PNG specification, 3rd edition, W3C 2025: chunks, IHDR, tEXt, IDAT, IEND) rather than
through Pillow: an 8-bit RGB image with text chunks is a few lines, and importing Pillow costs a small render's
start-up more than the encoding does. Pillow still reads images (io/images.py)."""

import struct
import zlib
from collections.abc import Iterator
from pathlib import Path

import numpy as np

from spectrace.io.atomic import write_atomically

SIGNATURE = b"\x89PNG\r\n\x1a\n"
_COMPRESSION_LEVEL = 6  # zlib's default: within a few per cent of the smallest size at a fraction of level 9's time


def _chunk(chunk_type: bytes, payload: bytes) -> bytes:
    crc = zlib.crc32(payload, zlib.crc32(chunk_type))
    return struct.pack(">I", len(payload)) + chunk_type + payload + struct.pack(">I", crc)


def _text_chunk(key: str, value: str) -> bytes:
    """tEXt holds Latin-1 without NUL; anything else goes in iTXt (UTF-8), as the specification asks."""
    keyword = key.encode("latin-1", "replace")[:79]
    try:
        text = value.encode("latin-1")
    except UnicodeEncodeError:
        return _chunk(b"iTXt", keyword + b"\x00\x00\x00\x00\x00" + value.encode("utf-8"))
    return _chunk(b"tEXt", keyword + b"\x00" + text)


def encode_png(pixels: np.ndarray, texts: dict[str, str], chunks: dict[bytes, bytes] | None = None) -> bytes:
    """The PNG file of (height, width, 3) uint8 RGB pixels: no interlacing, filter type 0 (none) on every row."""
    height, width, _ = pixels.shape
    header = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)  # 8 bits per channel, truecolour
    rows = np.zeros((height, 1 + 3 * width), np.uint8)  # each row opens with its filter type byte (0)
    rows[:, 1:] = np.ascontiguousarray(pixels, np.uint8).reshape(height, 3 * width)
    parts = [SIGNATURE, _chunk(b"IHDR", header)]
    parts += [_chunk(chunk_type, payload) for chunk_type, payload in (chunks or {}).items()]
    parts += [_text_chunk(key, value) for key, value in texts.items()]
    parts += [_chunk(b"IDAT", zlib.compress(rows.tobytes(), _COMPRESSION_LEVEL)), _chunk(b"IEND", b"")]
    return b"".join(parts)


def write_png(
    path: Path, encoded_srgb: np.ndarray, metadata: dict[str, str], chunks: dict[bytes, bytes] | None = None
) -> None:
    """chunks: extra PNG chunks by type (e.g. b"cICP" naming a colour space other than sRGB), before the pixels."""
    pixels = np.clip(np.rint(np.clip(encoded_srgb, 0.0, 1.0) * 255.0), 0, 255).astype(np.uint8)
    data = encode_png(pixels, {f"spectrace:{key}": str(value) for key, value in metadata.items()}, chunks)
    write_atomically(path, lambda temp: _write_file(temp, data))


def _write_file(path: Path, data: bytes) -> None:
    with open(path, "wb") as file:
        file.write(data)


def chunks(data: bytes) -> Iterator[tuple[bytes, bytes]]:
    """(type, payload) of each whole or cut chunk of the PNG bytes `data` (its signature first), to IEND."""
    position = len(SIGNATURE)
    while position + 8 <= len(data):
        (length,) = struct.unpack(">I", data[position : position + 4])
        kind = data[position + 4 : position + 8]
        yield kind, data[position + 8 : position + 8 + length]
        position += 12 + length
        if kind == b"IEND":
            return


def read_png_texts(path: Path, limit: int = 1 << 20) -> dict[str, str]:
    """The text chunks (tEXt, and uncompressed iTXt) before the pixels of a PNG, by keyword, from its first
    `limit` bytes (spectrace writes them there); {} for a file that is no PNG."""
    with open(path, "rb") as file:
        data = file.read(limit)
    if not data.startswith(SIGNATURE):
        return {}
    texts: dict[str, str] = {}
    for kind, payload in chunks(data):
        if kind in (b"IDAT", b"IEND"):
            break
        keyword, _, rest = payload.partition(b"\x00")
        if kind == b"tEXt":
            texts[keyword.decode("latin-1")] = rest.decode("latin-1")
        elif kind == b"iTXt" and rest[:1] == b"\x00":  # compression flag 0; then method, language, translation
            _, _, rest = rest[2:].partition(b"\x00")
            _, _, text = rest.partition(b"\x00")
            texts[keyword.decode("latin-1")] = text.decode("utf-8", "replace")
    return texts
