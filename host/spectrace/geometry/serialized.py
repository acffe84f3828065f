"""Mitsuba's `.serialized` meshes: indexed triangle meshes in zlib-compressed streams, several to a file.

The format, as Mitsuba 3's plugin reference ("Serialized mesh loader") documents it, all little-endian:
each mesh is a uint16 format identifier 0x041C and a uint16 version (3 or 4), then one zlib stream holding a
uint32 of flags (0x0001 vertex normals, 0x0002 texture coordinates, 0x0008 vertex colours, 0x0010 face normals,
0x1000 single, 0x2000 double precision), in version 4 the mesh's name as a NUL-terminated string, the uint64
vertex and triangle counts, the positions (x, y, z per vertex), the normals, texture coordinates (u, v) and
colours (r, g, b) when flagged, in the file's precision, and the triangles' corner indices as uint32. Meshes are
concatenated; the file ends with each mesh's byte offset (uint64 in version 4, uint32 in version 3) and the uint32
mesh count, so one mesh is found without reading the others.

Mitsuba 3 ignores the face-normals flag (only the plugin's `face_normals` parameter counts) and the colours; so does
this reader. Texture coordinates are stored v upward, as in other mesh files, and come out v down the image as
every spectrace mesh's (spectrace.geometry.mesh).
"""

import struct
from pathlib import Path

import numpy as np

from spectrace.errors import SpectraceError
from spectrace.io.compressed import BoundedInflater, max_inflated_bytes
from spectrace.io.input_files import regular_file

# (vertices (N, 3), faces (M, 3), texture coordinates (N, 2) v down or None, vertex normals (N, 3) or None)
MeshArrays = tuple[np.ndarray, np.ndarray, np.ndarray | None, np.ndarray | None]

FORMAT_ID = 0x041C
VERSIONS = (3, 4)
HAS_NORMALS, HAS_TEXCOORDS, HAS_COLORS = 0x0001, 0x0002, 0x0008
DOUBLE_PRECISION = 0x2000
# A mesh name longer than this is taken as a missing terminator (Mitsuba writes shape names: tens of bytes).
_MAX_NAME_BYTES = 1 << 16


def read_serialized(path: Path, shape_index: int, where: str) -> MeshArrays:
    """The arrays of mesh number `shape_index` (from 0) of a `.serialized` file (spectrace.geometry.mesh.load_mesh
    makes them a TriangleMesh); every failure raises SpectraceError naming `where`."""
    path = regular_file(path, where, what="mesh file")
    try:
        data = path.read_bytes()
    except OSError as error:
        raise SpectraceError(f"cannot read mesh file '{path}' ({error.strerror or error})", where=where) from None

    def fail(message: str) -> SpectraceError:
        return SpectraceError(f"mesh file '{path}': {message}", where=where)

    if len(data) < 8:
        raise fail("too short for a Mitsuba serialized mesh")
    format_id, version = struct.unpack_from("<HH", data, 0)
    if format_id != FORMAT_ID:
        raise fail(f"not a Mitsuba serialized mesh (format identifier 0x{format_id:04X}, expected 0x{FORMAT_ID:04X})")
    if version not in VERSIONS:
        raise fail(f"serialized format version {version} is not supported (versions 3 and 4 are)")
    (count,) = struct.unpack_from("<I", data, len(data) - 4)
    offset_type, offset_size = ("<Q", 8) if version == 4 else ("<I", 4)
    if not 0 < count <= (len(data) - 4) // offset_size:
        raise fail(f"its table of meshes is damaged (count {count})")
    if not 0 <= shape_index < count:
        raise fail(f"shape_index {shape_index} is out of range: the file holds {count} mesh(es), 0 to {count - 1}")
    (offset,) = struct.unpack_from(offset_type, data, len(data) - 4 - offset_size * (count - shape_index))
    if offset + 4 > len(data) or struct.unpack_from("<HH", data, offset) != (FORMAT_ID, version):
        raise fail(f"mesh {shape_index} does not start where the file's table says (byte {offset})")
    # One mesh's zlib stream ends where zlib says; what follows it (the next mesh) is not read. It is inflated in
    # steps, each bounded by what the mesh's own header has declared so far (spectrace.io.compressed).
    stream = BoundedInflater(data[offset + 4 :], "zlib", max_inflated_bytes(), fail)
    return _parse_mesh(stream, version, fail)


def _parse_mesh(stream: BoundedInflater, version: int, fail) -> MeshArrays:
    def take(size: int) -> bytes:
        chunk = stream.read(size)
        if len(chunk) < size:
            raise fail("its data ends early")
        return chunk

    (flags,) = struct.unpack("<I", take(4))
    if version == 4:
        text = b""
        while not text.endswith(b"\0"):  # NUL-terminated
            byte = stream.read(1)
            if not byte:
                raise fail("its mesh name is not terminated")
            text += byte
            if len(text) > _MAX_NAME_BYTES:
                raise fail(f"its mesh name is not terminated within {_MAX_NAME_BYTES} bytes")
    vertex_count, triangle_count = struct.unpack("<QQ", take(16))
    if vertex_count == 0 or triangle_count == 0:
        raise fail("contains no triangles")
    if vertex_count >= 2**32:
        raise fail(f"{vertex_count} vertices: more than 32-bit indices address")
    real = np.dtype("<f8") if flags & DOUBLE_PRECISION else np.dtype("<f4")
    columns_per_vertex = 3 + 3 * bool(flags & HAS_NORMALS) + 2 * bool(flags & HAS_TEXCOORDS)
    columns_per_vertex += 3 * bool(flags & HAS_COLORS)
    body = vertex_count * columns_per_vertex * real.itemsize + triangle_count * 12
    stream.declare(stream.produced + body, "its header's counts and flags declare")

    def array(columns: int) -> np.ndarray:
        size = vertex_count * columns * real.itemsize
        return np.frombuffer(take(size), real).reshape(vertex_count, columns).astype(np.float64)

    vertices = array(3)
    normals = array(3) if flags & HAS_NORMALS else None
    uvs = array(2) if flags & HAS_TEXCOORDS else None
    if flags & HAS_COLORS:
        array(3)
    faces = np.frombuffer(take(triangle_count * 12), "<u4").reshape(triangle_count, 3).astype(np.int64)
    stream.ended()  # refuses a stream holding more than its header declared: damage, or a decompression bomb
    if faces.max() >= vertex_count:
        raise fail("has faces that index missing vertices")
    for name, rows in (("vertices", vertices), ("vertex normals", normals), ("texture coordinates", uvs)):
        if rows is not None and not np.isfinite(rows).all():
            raise fail(f"has {name} with NaN or infinite components")
    if uvs is not None:
        uvs = np.column_stack([uvs[:, 0], 1.0 - uvs[:, 1]])
    return vertices, faces, uvs, normals
