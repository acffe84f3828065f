"""16-bit colour PNGs (RGB, RGBA, grey + alpha) at their full 16 bits, which Pillow reduces to 8.

PNG (W3C, 3rd edition) filters each scanline bytewise, and every filter (Sub, Up, Average, Paeth) predicts a byte
from bytes of the same position within a pixel: the one a pixel to the left, above, and above-left. So the high
bytes of a 16-bit image's samples form, with the scanlines' filter types, a valid 8-bit image of the same colour
type and size (one byte a sample), and so do the low bytes. Here the inflated data is split into those two 8-bit
images (interlaced files pass by pass, Adam7), which Pillow's C decoder unfilters, and the samples are
high · 256 + low. No new dependency, and the speed of Pillow's decoder (a pure-Python PNG reader unfilters
byte by byte).
"""

import io
import struct
import zlib
from pathlib import Path

import numpy as np

from spectrace.io.compressed import inflate
from spectrace.io.png import SIGNATURE as _SIGNATURE
from spectrace.io.png import chunks as _chunks

_CHANNELS = {2: 3, 4: 2, 6: 4}  # colour type -> samples a pixel: RGB, grey + alpha, RGBA
# Adam7: each pass's first column and row, and its steps.
_ADAM7 = ((0, 0, 8, 8), (4, 0, 8, 8), (0, 4, 4, 8), (2, 0, 4, 4), (0, 2, 2, 4), (1, 0, 2, 2), (0, 1, 1, 2))


class PngError(ValueError):
    """A malformed PNG; the message says how."""


def sixteen_bit_colour_header(head: bytes) -> tuple[int, int, int, int] | None:
    """(width, height, colour type, interlace) of a PNG whose first bytes are `head` when it is a 16-bit RGB, RGBA
    or grey + alpha image (what Pillow would read at 8 bits); None for any other file."""
    if not head.startswith(_SIGNATURE) or head[12:16] != b"IHDR" or len(head) < 33:
        return None
    width, height, depth, colour_type, _, _, interlace = struct.unpack(">IIBBBBB", head[16:29])
    if depth != 16 or colour_type not in _CHANNELS:
        return None
    return width, height, colour_type, interlace


def _passes(width: int, height: int, interlace: int) -> list[tuple[int, int]]:
    """(width, height) of each non-empty pass, in file order."""
    if not interlace:
        return [(width, height)]
    sizes = [(-(-(width - x0) // dx), -(-(height - y0) // dy)) for x0, y0, dx, dy in _ADAM7]
    return [(w, h) for w, h in sizes if w > 0 and h > 0]


def _png8(width: int, height: int, colour_type: int, interlace: int, filtered: bytes) -> bytes:
    def chunk(kind: bytes, payload: bytes) -> bytes:
        crc = zlib.crc32(payload, zlib.crc32(kind))
        return struct.pack(">I", len(payload)) + kind + payload + struct.pack(">I", crc)

    header = struct.pack(">IIBBBBB", width, height, 8, colour_type, 0, 0, interlace)
    # Level 1: the data is inflated again at once, so speed matters more than size.
    return _SIGNATURE + chunk(b"IHDR", header) + chunk(b"IDAT", zlib.compress(filtered, 1)) + chunk(b"IEND", b"")


def decode_png16(data: bytes) -> np.ndarray:
    """(height, width, samples) uint16 of a 16-bit RGB, RGBA or grey + alpha PNG's bytes."""
    from PIL import Image as PILImage

    header = sixteen_bit_colour_header(data[:33])
    if header is None:
        raise PngError("not a 16-bit RGB, RGBA or grey + alpha PNG")
    width, height, colour_type, interlace = header
    channels = _CHANNELS[colour_type]
    # The header fixes the inflated size (each scanline's filter byte and samples), so no more is inflated.
    size = sum(h * (1 + 2 * channels * w) for w, h in _passes(width, height, interlace))
    idat = b"".join(payload for kind, payload in _chunks(data) if kind == b"IDAT")
    inflated = inflate(idat, "zlib", size, PngError, "its header declares")
    raw = np.frombuffer(inflated, np.uint8)
    halves: list[list[np.ndarray]] = [[], []]
    position = 0
    for w, h in _passes(width, height, interlace):
        size = h * (1 + 2 * channels * w)
        if position + size > len(raw):
            raise PngError("its image data ends early")
        rows = raw[position : position + size].reshape(h, -1)
        position += size
        samples = rows[:, 1:].reshape(h, w * channels, 2)
        for i in range(2):  # 0: the high bytes, 1: the low ones, each after its row's filter type
            halves[i].append(np.concatenate([rows[:, :1], samples[..., i]], axis=1).ravel())
    planes = []
    for half in halves:
        png = _png8(width, height, colour_type, interlace, np.concatenate(half).tobytes())
        with PILImage.open(io.BytesIO(png)) as picture:
            planes.append(np.asarray(picture, np.uint16).reshape(height, width, channels))
    return planes[0] * np.uint16(256) + planes[1]


def read_png16(path: Path) -> np.ndarray:
    return decode_png16(path.read_bytes())
