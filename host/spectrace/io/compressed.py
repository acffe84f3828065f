"""Every compressed input spectrace reads (gzip, bzip2 or xz mesh files, the zlib streams of Mitsuba's `.serialized`
meshes and of 16-bit PNG images) is inflated here, in chunks, never beyond a limit.

A compressed stream says nothing trustworthy about its inflated size: a megabyte of deflated zeros inflates to a
gigabyte, and a reader that inflates it whole takes that memory before any check can run. So every reader states
the most its format allows, from the header where the format declares sizes (a PLY header's element counts and
property types, a `.serialized` mesh's vertex and triangle counts and flags, a PNG's width, height and colour
type), and the inflation stops with one line naming the file as soon as the stream holds more. Where a format
declares nothing (ASCII PLY, OBJ), or declares more, the overall limit `max_inflated_bytes()` applies: 2 GiB, or
`SPECTRACE_MAX_INFLATED_MB` megabytes (MiB).

Formats: gzip (RFC 1952, members may be concatenated), zlib (RFC 1950), bzip2 and xz, through Python's own
decompressors, whose `max_length` bounds what each step may produce.
"""

import bz2
import lzma
import os
import zlib
from collections.abc import Callable
from pathlib import Path
from typing import BinaryIO

from spectrace.core.limits import format_bytes
from spectrace.errors import SpectraceError

# The overall limit: the largest inflated input accepted whatever its header says. 2 GiB of binary PLY is about
# 90 million triangles (12 bytes a float32 vertex, 13 a triangle), which spectrace holds on the host at about
# five times that size (float64 vertices, int64 faces, the BVH) — beyond what a workstation renders, while a
# hostile file would make it allocate that much for nothing.
MAX_INFLATED_BYTES = 2 << 30
MAX_INFLATED_ENVIRONMENT = "SPECTRACE_MAX_INFLATED_MB"
# Compressed bytes read from the source per step, and the most inflated bytes one step makes.
_CHUNK = 1 << 16
# Suffixes of single compressed files, and which decompressor each needs.
COMPRESSED_SUFFIXES = {".gz": "gzip", ".bz2": "bzip2", ".xz": "xz"}


def max_inflated_bytes() -> int:
    """The overall limit on what one compressed input may inflate to: SPECTRACE_MAX_INFLATED_MB MiB, else 2 GiB."""
    text = os.environ.get(MAX_INFLATED_ENVIRONMENT)
    if not text:
        return MAX_INFLATED_BYTES
    try:
        megabytes = float(text)
    except ValueError:
        megabytes = float("nan")
    if not 0 < megabytes < 1 << 40:
        raise SpectraceError(
            f"must be a positive number of MiB (default {MAX_INFLATED_BYTES >> 20}), got '{text[:60]}'",
            where=MAX_INFLATED_ENVIRONMENT,
        )
    return int(megabytes * (1 << 20))


def _decompressor(kind: str):
    if kind == "gzip":
        return zlib.decompressobj(wbits=16 + zlib.MAX_WBITS)
    if kind == "zlib":
        return zlib.decompressobj()
    if kind == "bzip2":
        return bz2.BZ2Decompressor()
    if kind == "xz":
        return lzma.LZMADecompressor()
    raise ValueError(f"unknown compression '{kind}'")


class BoundedInflater:
    """A compressed stream read as its inflated bytes, never more than `limit` of them: `read(n)` gives n bytes
    (fewer only where the stream ends), and raises `fail(message)` as soon as the stream would give more than the
    limit. `limit` may be lowered once a header has told the size (`declare`). gzip streams may hold several
    members, read one after the other (as gunzip does); a zlib stream ends where zlib says, and what follows it is
    not read."""

    def __init__(self, source: BinaryIO | bytes, kind: str, limit: int, fail: Callable[[str], Exception]):
        self._source = source
        self._offset = 0  # into `source` when it is bytes
        self._kind = kind
        self._inflater = _decompressor(kind)
        self._pending = b""  # compressed bytes the inflater has not taken yet
        self._ended = False
        self.limit = limit
        self.declared: str | None = None  # where the limit came from, for the message
        self.produced = 0  # inflated bytes given out
        self._fail = fail

    def declare(self, size: int, origin: str) -> None:
        """Lower the limit to what the header says the stream holds (`origin` says which header, for messages)."""
        if size < self.limit:
            self.limit, self.declared = size, origin
        if self.produced > self.limit:
            raise self._fail(self.too_much())

    def _compressed(self) -> bytes:
        if isinstance(self._source, bytes | bytearray | memoryview):
            chunk = bytes(self._source[self._offset : self._offset + _CHUNK])
            self._offset += len(chunk)
            return chunk
        try:
            return self._source.read(_CHUNK)
        except OSError as error:
            raise self._fail(f"cannot be read ({error.strerror or error})") from None

    def _input(self) -> bytes:
        """Compressed bytes to feed next: those zlib left last step, else those kept back, else the source's next."""
        data = getattr(self._inflater, "unconsumed_tail", b"") or self._pending or self._compressed()
        self._pending = b""
        return data

    def _step(self, wanted: int) -> bytes:
        """Up to `wanted` inflated bytes; b"" only at the end of the stream."""
        while not self._ended:
            inflater = self._inflater
            if inflater.eof:
                if self._kind != "gzip":
                    self._ended = True
                    break
                # Another member may follow; zero bytes padding a gzip file are skipped, as gunzip does.
                rest = (inflater.unused_data or self._pending).lstrip(b"\0")
                while not rest and (chunk := self._compressed()):
                    rest = chunk.lstrip(b"\0")
                if not rest:
                    self._ended = True
                    break
                self._inflater, self._pending = _decompressor(self._kind), rest
                continue
            # bzip2 and xz keep back input they have not inflated yet, and say when they need more.
            data = self._input() if getattr(inflater, "needs_input", True) else b""
            try:
                out = inflater.decompress(data, wanted)
            except (zlib.error, OSError, EOFError, lzma.LZMAError) as error:
                raise self._fail(f"its compressed data is damaged ({error})") from None
            if out:
                return out
            if not data and not inflater.eof and getattr(inflater, "needs_input", True):
                raise self._fail("is truncated: its compressed data ends early")
        return b""

    def read(self, size: int) -> bytes:
        """The next `size` inflated bytes, fewer only where the stream ends."""
        parts: list[bytes] = []
        got = 0
        while got < size:
            wanted = min(size - got, _CHUNK * 16, self.limit - self.produced + 1)
            chunk = self._step(wanted)
            if not chunk:
                break
            self.produced += len(chunk)
            if self.produced > self.limit:
                raise self._fail(self.too_much())
            parts.append(chunk)
            got += len(chunk)
        return b"".join(parts)

    def too_much(self) -> str:
        if self.declared is not None:
            size = format_bytes(self.limit)
            return f"inflates to more than the {size} {self.declared} (damaged, or a decompression bomb)"
        return (
            f"inflates to more than {format_bytes(self.limit)}, the limit on a compressed input "
            f"({MAX_INFLATED_ENVIRONMENT} sets it in MiB)"
        )

    def read_all(self) -> bytes:
        """Every remaining inflated byte, within the limit."""
        return self.read(self.limit - self.produced + 1)

    def ended(self) -> bool:
        """Whether the stream holds nothing more (reading one byte more to know; more is an error when it passes
        the limit)."""
        return not self.read(1)

    def copy_to(self, target: BinaryIO) -> int:
        """Write every remaining inflated byte to `target`; the number written."""
        total = 0
        while chunk := self.read(_CHUNK * 16):
            target.write(chunk)
            total += len(chunk)
        return total


def inflate(data: bytes, kind: str, limit: int, fail: Callable[[str], Exception], declared: str | None = None) -> bytes:
    """One whole compressed stream held in memory, inflated, refused beyond `limit` bytes (from the header that
    `declared` names, else the overall limit)."""
    inflater = BoundedInflater(data, kind, min(limit, max_inflated_bytes()), fail)
    if declared is not None and limit <= max_inflated_bytes():
        inflater.declared = declared
    return inflater.read_all()


def file_inflater(path: Path, source: BinaryIO, where: str, what: str = "file") -> BoundedInflater:
    """A BoundedInflater over an open compressed file (its kind from the suffix), whose errors are one line
    naming `what` and the file at `where`."""
    kind = COMPRESSED_SUFFIXES[path.suffix.lower()]

    def fail(message: str) -> SpectraceError:
        return SpectraceError(f"{what} '{path}' ({kind}) {message}", where=where)

    return BoundedInflater(source, kind, max_inflated_bytes(), fail)
