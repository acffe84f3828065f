"""The tensor file format of Mitsuba (`TensorFile`), in which the RGL material database ships its measured BSDFs
(the `.bsdf` files; Dupuy & Jakob 2018): named n-dimensional arrays in one little-endian file.

Layout: the 12 bytes "tensor_file\\0", the version (two bytes, 1 and 0), the number of fields (uint32), then per
field its name (uint16 length, then the bytes), its number of dimensions (uint16), its type (uint8, the codes of
TYPES), the offset of its data from the file's start (uint64) and its shape (uint64 per dimension); each field's
data are C-ordered (the last dimension contiguous) at its offset.
"""

import struct
from pathlib import Path

import numpy as np

from spectrace.errors import SpectraceError
from spectrace.io.input_files import regular_file

MAGIC = b"tensor_file\0"
VERSION = (1, 0)
# The type codes of the format (Mitsuba's Struct types, 0 being "invalid").
TYPES: dict[int, np.dtype] = {
    code: np.dtype(name).newbyteorder("<")
    for code, name in enumerate(
        ("uint8", "int8", "uint16", "int16", "uint32", "int32", "uint64", "int64", "float16", "float32", "float64"),
        start=1,
    )
}
# More would be no measured material: a bound on what one header makes the reader allocate.
MAX_FIELDS = 1024
MAX_DIMENSIONS = 16


def read_tensor_file(path: str | Path, where: str | None = None, what: str = "tensor file") -> dict[str, np.ndarray]:
    """Every field of the tensor file at `path`, by name, as read-only arrays of the file's types. A file that is
    not in the format, or whose fields reach past its end, is refused in one line naming the file (and `where`)."""
    path = regular_file(path, where, what)
    try:
        data = path.read_bytes()
    except OSError as error:
        raise SpectraceError(f"cannot read {what} '{path}' ({error.strerror or error})", where=where) from None
    return parse_tensor_file(data, where or str(path), f"{what} '{path.name}'")


def parse_tensor_file(data: bytes, where: str, what: str = "tensor file") -> dict[str, np.ndarray]:
    """The fields of a tensor file's bytes (read_tensor_file)."""

    def bad(problem: str) -> SpectraceError:
        return SpectraceError(f"{what} is no tensor file: {problem}", where=where)

    view = memoryview(data)
    at = 0

    def take(fmt: str):
        nonlocal at
        size = struct.calcsize(fmt)
        if at + size > len(view):
            raise bad(f"its header ends early (byte {at} of {len(view)})")
        values = struct.unpack_from(fmt, view, at)
        at += size
        return values

    if bytes(view[: len(MAGIC)]) != MAGIC:
        raise bad("it does not begin with 'tensor_file'")
    at = len(MAGIC)
    version = take("<BB")
    if version != VERSION:
        raise bad(f"version {version[0]}.{version[1]}, where 1.0 is read")
    (count,) = take("<I")
    if count > MAX_FIELDS:
        raise bad(f"{count} fields, more than {MAX_FIELDS}")
    fields: dict[str, np.ndarray] = {}
    for _ in range(count):
        (length,) = take("<H")
        name = bytes(take(f"<{length}s")[0]).decode("utf-8", "replace")
        ndim, code, offset = take("<HBQ")
        if ndim > MAX_DIMENSIONS:
            raise bad(f"field '{name}' has {ndim} dimensions, more than {MAX_DIMENSIONS}")
        shape = take(f"<{ndim}Q") if ndim else ()
        if code not in TYPES:
            raise bad(f"field '{name}' has the unknown type code {code}")
        dtype = TYPES[code]
        size = int(np.prod(shape, dtype=object)) * dtype.itemsize
        if offset + size > len(view):
            raise bad(f"field '{name}' ({size} bytes at {offset}) reaches past the end ({len(view)} bytes)")
        array = np.frombuffer(data, dtype, int(np.prod(shape, dtype=object)), offset).reshape(shape)
        fields[name] = array
    return fields
