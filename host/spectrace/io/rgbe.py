"""Radiance HDR (RGBE, `.hdr` / `.rgbe`) images: Greg Ward's format, which Mitsuba 3 and pbrt read for environment
maps. A header of text lines ("#?RADIANCE", "FORMAT=32-bit_rle_rgbe", ...) ends with an empty line and the size line
"-Y height +X width" (rows top to bottom, the only orientation written in practice); then each row, flat (4 bytes a
pixel) or run-length encoded per channel (a row starting 2, 2, width >> 8, width & 255). A pixel's value is
mantissa · 2^(exponent − 136), 0 where the exponent is 0 (Ward's `colr_color` adds ½ to the mantissa; readers such
as Mitsuba's and stb_image do not, and neither does this one). The size is checked against the image limit before
any pixel is decoded."""

from pathlib import Path

import numpy as np

from spectrace.core import limits
from spectrace.errors import SpectraceError
from spectrace.io.input_files import regular_file

_MAX_HEADER_LINES = 1000


def _size_line(data: bytes, path: Path, where: str) -> tuple[int, int, int]:
    """(width, height, offset of the first row) after the header."""
    position = 0
    for number in range(_MAX_HEADER_LINES):
        end = data.find(b"\n", position)
        if end < 0:
            break
        line = data[position:end].strip()
        position = end + 1
        if number == 0 and not line.startswith(b"#?"):
            raise SpectraceError(f"'{path}' is not a Radiance HDR image (no '#?' first line)", where=where)
        if line.startswith(b"FORMAT=") and line != b"FORMAT=32-bit_rle_rgbe":
            raise SpectraceError(f"'{path}': format {line[7:].decode(errors='replace')} (only RGBE)", where=where)
        if not line and number > 0:
            end = data.find(b"\n", position)
            parts = data[position:end].split() if end >= 0 else []
            if len(parts) != 4 or parts[0] != b"-Y" or parts[2] != b"+X" or not (parts[1] + parts[3]).isdigit():
                raise SpectraceError(f"'{path}': only '-Y height +X width' images are read", where=where)
            return int(parts[3]), int(parts[1]), end + 1
    raise SpectraceError(f"'{path}': the header does not end", where=where)


def read_rgbe(path: Path, where: str, what: str = "image") -> np.ndarray:
    """(height, width, 3) float32 linear values of a Radiance HDR file; every failure one line naming the file."""
    regular_file(path, where, what=what)
    data = path.read_bytes()
    width, height, position = _size_line(data, path, where)
    if problem := limits.image_size_problem(width, height):
        raise SpectraceError(f"{what} '{path}': {problem}", where=where)
    pixels = np.zeros((height, width, 4), np.uint8)
    buffer = np.frombuffer(data, np.uint8)
    truncated = SpectraceError(f"{what} '{path}' ends before its last row", where=where)
    for row in range(height):
        head = buffer[position : position + 4]
        if len(head) < 4:
            raise truncated
        if 8 <= width < 32768 and head[0] == 2 and head[1] == 2 and (int(head[2]) << 8 | int(head[3])) == width:
            position += 4
            for channel in range(4):
                column = 0
                while column < width:
                    if position >= len(buffer):
                        raise truncated
                    count = int(buffer[position])
                    if count > 128:  # a run: one byte repeated
                        count -= 128
                        if column + count > width or position + 1 >= len(buffer):
                            raise SpectraceError(f"{what} '{path}': a run overflows row {row}", where=where)
                        pixels[row, column : column + count, channel] = buffer[position + 1]
                        position += 2
                    else:  # literal bytes
                        if count == 0 or column + count > width or position + 1 + count > len(buffer):
                            raise SpectraceError(f"{what} '{path}': bad literal run in row {row}", where=where)
                        pixels[row, column : column + count, channel] = buffer[position + 1 : position + 1 + count]
                        position += 1 + count
                    column += count
        else:
            if head[0] == 1 and head[1] == 1 and head[2] == 1:
                raise SpectraceError(f"{what} '{path}': old-style run-length rows are not read", where=where)
            flat = buffer[position : position + 4 * width]
            if len(flat) < 4 * width:
                raise truncated
            pixels[row] = flat.reshape(width, 4)
            position += 4 * width
    exponent = pixels[..., 3].astype(np.int32)
    scale = np.where(exponent > 0, np.ldexp(1.0, exponent - 136), 0.0)
    return (pixels[..., :3] * scale[..., None]).astype(np.float32)
