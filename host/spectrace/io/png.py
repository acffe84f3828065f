"""PNG chunks (PNG specification, 3rd edition, W3C 2025: chunks, tEXt, iTXt, IEND): writing one, reading a file's
chunks and its text. Pillow writes 8-bit PNGs (spectrace.io.raster); the 16-bit RGB ones it cannot write are made
from these chunks there."""

import struct
import zlib
from collections.abc import Iterator
from pathlib import Path

SIGNATURE = b"\x89PNG\r\n\x1a\n"


def make_chunk(chunk_type: bytes, payload: bytes) -> bytes:
    crc = zlib.crc32(payload, zlib.crc32(chunk_type))
    return struct.pack(">I", len(payload)) + chunk_type + payload + struct.pack(">I", crc)


def text_chunk(key: str, value: str) -> bytes:
    """tEXt holds Latin-1 without NUL; anything else goes in iTXt (UTF-8), as the specification asks."""
    keyword = key.encode("latin-1", "replace")[:79]
    try:
        text = value.encode("latin-1")
    except UnicodeEncodeError:
        return make_chunk(b"iTXt", keyword + b"\x00\x00\x00\x00\x00" + value.encode("utf-8"))
    return make_chunk(b"tEXt", keyword + b"\x00" + text)


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
