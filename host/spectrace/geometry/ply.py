"""A direct reader for the common binary PLY triangle mesh: one `vertex` element of scalar properties and one `face`
element holding a vertex-index list of three per face and any scalar properties (what pbrt-v4's and Mitsuba 3's
exporters and most tools write). The whole body is read as two numpy record arrays, with no per-element Python work,
which makes a million triangles a fraction of a second where trimesh's general reader takes seconds. Anything else
(ASCII, quads, extra elements, unreferenced vertices beside texture coordinates) returns None and goes to trimesh.

Properties beyond positions, normals, texture coordinates and tangents are the mesh's attributes, named as Mitsuba 3's
PLY reader names them (`attributes`).

Format: Greg Turk's PLY description (paulbourke.net/dataformats/ply/). The result matches what spectrace's trimesh
path makes of the same file (a test compares both on written files), so the reader changes speed only.
"""

from dataclasses import dataclass

import numpy as np

_TYPES = {
    "char": "i1",
    "int8": "i1",
    "uchar": "u1",
    "uint8": "u1",
    "short": "i2",
    "int16": "i2",
    "ushort": "u2",
    "uint16": "u2",
    "int": "i4",
    "int32": "i4",
    "uint": "u4",
    "uint32": "u4",
    "float": "f4",
    "float32": "f4",
    "double": "f8",
    "float64": "f8",
}
_INTEGER_KINDS = "iu"
# Texture coordinate names in the order trimesh tries them (exporters disagree on the name).
_UV_NAMES = (("texture_u", "texture_v"), ("u", "v"), ("s", "t"))
_INDEX_NAMES = ("vertex_indices", "vertex_index")


@dataclass
class PlyTriangles:
    vertices: np.ndarray  # (N, 3) float64, as stored
    faces: np.ndarray  # (M, 3) int64
    normals: np.ndarray | None  # (N, 3) float64 unit (zero stays zero); None when the file has none
    uvs: np.ndarray | None  # (N, 2) float64 as stored (v up the image, as mesh files store it)
    # (N, 4) float64 tangents (tx, ty, tz, tw: glTF's xyz and handedness w, along +u) as stored; None when the file
    # has none. Only this reader takes them: a PLY file read through trimesh loses them.
    tangents: np.ndarray | None = None
    # Mitsuba 3's mesh attributes: "vertex_<name>" (N, C) and "face_<name>" (M, C), C 1 or 3 (mesh_attributes).
    attributes: dict[str, np.ndarray] | None = None


# The vertex properties the mesh itself reads; the others are attributes.
_GEOMETRY_NAMES = {"x", "y", "z", "nx", "ny", "nz", "tx", "ty", "tz", "tw"} | {n for pair in _UV_NAMES for n in pair}
# The suffixes that make consecutive properties `<prefix>_<suffix>` one attribute's channels (Mitsuba 3's ply.h):
# an attribute of r, g, b channels is named `<prefix>_color` (`color` alone without a prefix, as `r g b` or
# `red green blue` vertex colours are).
_CHANNEL_SUFFIXES: tuple[tuple[str, ...], ...] = (
    ("0", "1", "2"),
    ("x", "y", "z"),
    ("r", "g", "b"),
    ("red", "green", "blue"),
)
_COLOUR_SUFFIXES: tuple[tuple[str, ...], ...] = (("r", "g", "b"), ("red", "green", "blue"))


def mesh_attributes(element: str, names: list[str], columns) -> dict[str, np.ndarray]:
    """The attributes that properties `names` of a PLY element ("vertex" or "face") make, as Mitsuba 3 groups them:
    consecutive properties `<prefix>_<suffix>` with suffixes 0, 1, 2 (or x, y, z; r, g, b; red, green, blue) are one
    attribute `<element>_<prefix>` of as many channels (`<element>_<prefix>_color` for r, g, b), kept when it has 1
    or 3; a property with no such suffix is not an attribute (Mitsuba ignores it). Integer values are kept as they
    are stored (not normalised), as Mitsuba keeps them. `columns(keys)` gives the (count, len(keys)) values."""
    groups: list[tuple[str, tuple[str, ...], list[str]]] = []  # (prefix, suffix set, property names)
    for name in names:
        if name in _GEOMETRY_NAMES and element == "vertex":
            continue
        prefix, _, suffix = name.rpartition("_")
        suffixes = next((group for group in _CHANNEL_SUFFIXES if suffix in group), None)
        if suffixes is None:
            continue
        last = groups[-1] if groups else None
        if last is not None and last[:2] == (prefix, suffixes) and suffixes.index(suffix) == len(last[2]):
            last[2].append(name)
            continue
        if suffixes.index(suffix) == 0:
            groups.append((prefix, suffixes, [name]))
    attributes = {}
    for prefix, suffixes, members in groups:
        if len(members) not in (1, 3):
            continue
        if suffixes in _COLOUR_SUFFIXES:
            prefix = f"{prefix}_color" if prefix else "color"
        if prefix:
            attributes[f"{element}_{prefix}"] = columns(tuple(members))
    return attributes


# A PLY header is searched for this far into a file (real headers are a few hundred bytes).
HEADER_MAX_BYTES = 1 << 16


def declared_size(head: bytes) -> int | None:
    """The most bytes a binary PLY file whose first bytes are `head` may hold, from its header: the header, then
    each element's count times its record, a list property counted at the most entries its count type can state
    (255 for uchar). None for an ASCII file (numbers as text have no fixed size) or a header not found or not
    understood: the caller's overall limit applies then."""
    end = head.find(b"end_header", 0, HEADER_MAX_BYTES)
    newline = head.find(b"\n", end)
    if not head.startswith(b"ply") or end < 0 or newline < 0:
        return None
    try:
        lines = [line.split() for line in head[:end].decode("ascii").splitlines()[1:]]
    except UnicodeError:
        return None
    if not any(fields[:2] in (["format", "binary_little_endian"], ["format", "binary_big_endian"]) for fields in lines):
        return None
    total, count = newline + 1, 0
    for fields in lines:
        if len(fields) == 3 and fields[0] == "element" and fields[2].isdigit():
            count = int(fields[2])
        elif len(fields) == 3 and fields[0] == "property" and fields[1] in _TYPES:
            total += count * np.dtype(_TYPES[fields[1]]).itemsize
        elif len(fields) == 5 and fields[:2] == ["property", "list"] and {fields[2], fields[3]} <= set(_TYPES):
            counter, item = np.dtype(_TYPES[fields[2]]), np.dtype(_TYPES[fields[3]])
            if counter.kind not in _INTEGER_KINDS:
                return None
            most = np.iinfo(counter).max
            total += count * (counter.itemsize + int(most) * item.itemsize)
        elif fields and fields[0] not in ("format", "comment", "obj_info"):
            return None
    return total


def read_binary_ply(data: bytes) -> PlyTriangles | None:
    """The triangles of a binary PLY file's bytes, or None when the file is not of the simple kind this reads."""
    end = data.find(b"end_header", 0, 1 << 16)
    if not data.startswith(b"ply") or end < 0:
        return None
    body = data.index(b"\n", end) + 1
    try:
        lines = [line.split() for line in data[:end].decode("ascii").splitlines()[1:]]
    except UnicodeError:
        return None
    byte_order = None
    elements: list[tuple[str, int, list[list[str]]]] = []
    for fields in lines:
        if not fields or fields[0] in ("comment", "obj_info"):
            continue
        if fields[0] == "format" and len(fields) == 3:
            byte_order = {"binary_little_endian": "<", "binary_big_endian": ">"}.get(fields[1])
        elif fields[0] == "element" and len(fields) == 3 and fields[2].isdigit():
            elements.append((fields[1], int(fields[2]), []))
        elif fields[0] == "property" and elements:
            elements[-1][2].append(fields[1:])
        else:
            return None
    if byte_order is None or [e[0] for e in elements] != ["vertex", "face"]:
        return None
    (_, vertex_count, vertex_properties), (_, face_count, face_properties) = elements
    if vertex_count == 0 or face_count == 0 or sum(p[0] == "list" for p in face_properties) != 1:
        return None
    if any(len(p) != 2 or p[0] not in _TYPES for p in vertex_properties):
        return None
    names = [p[1] for p in vertex_properties]
    if len(set(names)) != len(names) or not {"x", "y", "z"} <= set(names):
        return None
    face = next(p for p in face_properties if p[0] == "list")
    if len(face) != 4 or face[3] not in _INDEX_NAMES:
        return None
    face_scalars = [p for p in face_properties if p is not face]
    if any(len(p) != 2 or p[0] not in _TYPES for p in face_scalars) or len({p[1] for p in face_scalars}) < len(
        face_scalars
    ):
        return None
    count_type, index_type = _TYPES.get(face[1]), _TYPES.get(face[2])
    if count_type is None or index_type is None or count_type[0] not in _INTEGER_KINDS:
        return None
    if index_type[0] not in _INTEGER_KINDS:
        return None
    vertex_type = np.dtype([(name, byte_order + _TYPES[kind]) for kind, name in vertex_properties])
    face_type = np.dtype(_face_fields(face_properties, face, byte_order, count_type, index_type))
    if len(data) < body + vertex_count * vertex_type.itemsize + face_count * face_type.itemsize:
        return None
    vertex_data = np.frombuffer(data, vertex_type, vertex_count, body)
    face_data = np.frombuffer(data, face_type, face_count, body + vertex_type.itemsize * vertex_count)
    if np.any(face_data["n"] != 3):
        return None
    faces = face_data["i"].astype(np.int64)
    if faces.min() < 0 or faces.max() >= vertex_count:
        return None  # trimesh's reading decides what the error says

    def columns(keys: tuple[str, ...]) -> np.ndarray:
        return np.column_stack([vertex_data[key] for key in keys]).astype(np.float64)

    uvs = next((columns(pair) for pair in _UV_NAMES if set(pair) <= set(names)), None)
    if uvs is not None and np.bincount(faces.ravel(), minlength=vertex_count).min() == 0:
        return None  # trimesh drops unreferenced vertices when a file has texture coordinates
    normals = None
    if {"nx", "ny", "nz"} <= set(names):
        # The same arithmetic as the trimesh path (its scene transform, identity here, then a division by the
        # length), so that both readers give the same bits, signed zeros included.
        stored = columns(("nx", "ny", "nz")) @ np.eye(3)
        length = np.linalg.norm(stored, axis=-1, keepdims=True)
        normals = np.divide(stored, length, out=np.zeros_like(stored), where=length > 0)
    tangents = columns(("tx", "ty", "tz", "tw")) if {"tx", "ty", "tz", "tw"} <= set(names) else None

    def face_columns(keys: tuple[str, ...]) -> np.ndarray:
        return np.column_stack([face_data[f"p_{key}"] for key in keys]).astype(np.float64)

    attributes = mesh_attributes("vertex", names, columns)
    attributes |= mesh_attributes("face", [p[1] for p in face_scalars], face_columns)
    return PlyTriangles(columns(("x", "y", "z")), faces, normals, uvs, tangents, attributes or None)


def _face_fields(properties: list[list[str]], face: list[str], byte_order: str, count_type: str, index_type: str):
    """The record of a face element whose vertex-index list (three per face) sits among scalar properties."""
    fields: list = []
    for p in properties:
        if p is face:
            fields += [("n", byte_order + count_type), ("i", byte_order + index_type, (3,))]
        else:
            fields.append((f"p_{p[1]}", byte_order + _TYPES[p[0]]))
    return fields
