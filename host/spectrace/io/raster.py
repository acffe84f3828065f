"""Display images for ordinary viewers: PNG (8 or 16 bits), JPEG, TIFF (8 or 16 bits), and PFM (linear float).

8-bit PNG, JPEG and 8-bit TIFF are written by Pillow (importing it costs about 30 ms, against some 3.4 s for the
smallest render from the command line). Pillow writes no 16-bit RGB (its RGB mode has 8 bits a sample) and PFM only
in grey, so those three are written here: 16-bit PNG with zlib (spectrace.io.png's chunks), an uncompressed
baseline TIFF (TIFF 6.0, Part 1, with the ICC tag 34675 of the ICC specification's Annex B), and PFM
(Portable Float Map: "PF", width and height, a negative scale for little-endian, rows bottom to top).

The files of a space other than sRGB carry its ICC profile (spectrace.film.icc_profile); PNGs also a cICP chunk.
Every file is written atomically.
"""

from __future__ import annotations

import io
import json
import struct
import zlib
from pathlib import Path

import numpy as np

from spectrace.io.atomic import write_atomically
from spectrace.io.png import SIGNATURE, make_chunk, text_chunk

# Suffix -> format; `DISPLAY_FORMATS` hold display-encoded numbers in [0, 1], PFM linear ones.
DISPLAY_FORMATS = {".png": "PNG", ".jpg": "JPEG", ".jpeg": "JPEG", ".tif": "TIFF", ".tiff": "TIFF"}
LINEAR_FORMATS = {".pfm": "PFM"}
SIXTEEN_BIT_FORMATS = ("PNG", "TIFF")
JPEG_QUALITY = 95  # visually lossless for renders; Pillow's default of 75 shows blocks in smooth gradients


def quantise(encoded: np.ndarray, bit_depth: int) -> np.ndarray:
    top = (1 << bit_depth) - 1
    values = np.rint(np.clip(np.asarray(encoded, np.float64), 0.0, 1.0) * top)
    return values.astype(np.uint8 if bit_depth == 8 else np.uint16)


def write_display_image(
    path: Path,
    encoded: np.ndarray,
    metadata: dict[str, str],
    *,
    bit_depth: int = 8,
    icc_profile: bytes | None = None,
    png_chunks: dict[bytes, bytes] | None = None,
) -> None:
    """Write (height, width, 3) display-encoded RGB (clipped to [0, 1]) in the format of path's suffix."""
    kind = DISPLAY_FORMATS[path.suffix.lower()]
    pixels = quantise(encoded, bit_depth)
    if kind == "PNG" and bit_depth == 16:
        data = _png16(pixels, metadata, icc_profile, png_chunks or {})
    elif kind == "TIFF" and bit_depth == 16:
        data = _tiff16(pixels, metadata, icc_profile)
    else:
        data = _pillow(kind, pixels, metadata, icc_profile, png_chunks or {})
    write_atomically(path, lambda temp: temp.write_bytes(data))


def _pillow(kind: str, pixels: np.ndarray, metadata: dict[str, str], icc: bytes | None, chunks) -> bytes:
    from PIL import Image as PILImage

    picture = PILImage.fromarray(np.ascontiguousarray(pixels), "RGB")
    options: dict = {"icc_profile": icc} if icc else {}
    if kind == "PNG":
        from PIL.PngImagePlugin import PngInfo

        info = PngInfo()
        for key, value in metadata.items():  # tEXt, or iTXt for text beyond Latin-1
            info.add_text(f"spectrace:{key}", value)
        options.update(pnginfo=info, compress_level=6)
    elif kind == "JPEG":
        options.update(quality=JPEG_QUALITY, subsampling=0, comment=_description(metadata))
    else:
        options.update(description=_description(metadata), compression="tiff_deflate")
    buffer = io.BytesIO()
    picture.save(buffer, format=kind, **options)
    data = buffer.getvalue()
    return _before_image_data(data, chunks) if kind == "PNG" and chunks else data


def _before_image_data(data: bytes, chunks: dict[bytes, bytes]) -> bytes:
    """The PNG `data` with `chunks` placed before its first IDAT, as cICP must be: Pillow writes public chunks it
    does not know of (cICP before Pillow 11) nowhere, so they are added here for every release alike."""
    first = len(SIGNATURE)
    while data[first + 4 : first + 8] != b"IDAT":  # chunk by chunk: a text chunk may hold the letters "IDAT"
        (length,) = struct.unpack(">I", data[first : first + 4])
        first += 12 + length
    added = b"".join(make_chunk(chunk_type, payload) for chunk_type, payload in chunks.items())
    return data[:first] + added + data[first:]


def _description(metadata: dict[str, str]) -> str:
    return json.dumps({f"spectrace:{key}": value for key, value in metadata.items()}, ensure_ascii=True)


def _png16(pixels: np.ndarray, metadata: dict[str, str], icc: bytes | None, chunks: dict[bytes, bytes]) -> bytes:
    height, width, _ = pixels.shape
    header = struct.pack(">IIBBBBB", width, height, 16, 2, 0, 0, 0)  # 16 bits per sample, truecolour
    rows = np.zeros((height, 1 + 6 * width), np.uint8)  # filter type 0 (none) opens each row
    rows[:, 1:] = np.ascontiguousarray(pixels.astype(">u2")).view(np.uint8).reshape(height, 6 * width)
    parts = [SIGNATURE, make_chunk(b"IHDR", header)]
    if icc:  # iCCP: a profile name, NUL, compression method 0, the zlib-compressed profile
        parts.append(make_chunk(b"iCCP", b"ICC profile\x00\x00" + zlib.compress(icc)))
    parts += [make_chunk(chunk_type, payload) for chunk_type, payload in chunks.items()]
    parts += [text_chunk(f"spectrace:{key}", value) for key, value in metadata.items()]
    parts += [make_chunk(b"IDAT", zlib.compress(rows.tobytes(), 6)), make_chunk(b"IEND", b"")]
    return b"".join(parts)


def _tiff16(pixels: np.ndarray, metadata: dict[str, str], icc: bytes | None) -> bytes:
    """A little-endian baseline RGB TIFF, one uncompressed strip of 16-bit samples."""
    height, width, _ = pixels.shape
    strip = np.ascontiguousarray(pixels.astype("<u2")).tobytes()
    description = _description(metadata).encode("ascii") + b"\x00"
    # (tag, type, count, value or bytes): type 3 SHORT, 4 LONG, 2 ASCII, 7 UNDEFINED; in ascending tag order.
    extra: list[tuple[int, int, int, bytes]] = [(258, 3, 3, struct.pack("<3H", 16, 16, 16)), (270, 2, 0, description)]
    if icc:
        extra.append((34675, 7, 0, icc))
    header_size, entry_count = 8, 11 + len(extra)
    data_start = header_size + 2 + 12 * entry_count + 4
    blobs, offsets = b"", {}
    for tag, _, _, value in extra:
        offsets[tag] = data_start + len(blobs)
        blobs += value + b"\x00" * (len(value) % 2)  # values start on word boundaries
    strip_offset = data_start + len(blobs)
    entries = {
        256: (4, 1, width),
        257: (4, 1, height),
        259: (3, 1, 1),  # no compression
        262: (3, 1, 2),  # RGB
        273: (4, 1, strip_offset),
        277: (3, 1, 3),  # samples per pixel
        278: (4, 1, height),  # rows per strip: all
        279: (4, 1, len(strip)),
        282: (5, 1, 0),  # resolution: 72/1, written below
        283: (5, 1, 0),
        296: (3, 1, 2),  # inches
    }
    resolution = struct.pack("<II", 72, 1)
    offsets[282] = strip_offset + len(strip)
    offsets[283] = offsets[282]
    for tag, kind, count, value in extra:
        entries[tag] = (kind, count or len(value), offsets[tag])
    table = struct.pack("<H", len(entries))
    for tag in sorted(entries):
        kind, count, value_or_offset = entries[tag]
        if kind == 3 and count == 1:
            table += struct.pack("<HHIHH", tag, kind, count, value_or_offset, 0)
        else:
            table += struct.pack("<HHII", tag, kind, count, value_or_offset if kind != 5 else offsets[tag])
    table += struct.pack("<I", 0)  # no next IFD
    return b"II*\x00" + struct.pack("<I", header_size) + table + blobs + strip + resolution


def write_pfm(path: Path, linear_rgb: np.ndarray) -> None:
    """Linear (height, width, 3) values as 32-bit floats, unclipped."""
    height, width, _ = linear_rgb.shape
    rows = np.ascontiguousarray(np.asarray(linear_rgb, "<f4")[::-1])  # PFM stores the bottom row first
    data = f"PF\n{width} {height}\n-1.0\n".encode("ascii") + rows.tobytes()
    write_atomically(path, lambda temp: temp.write_bytes(data))
