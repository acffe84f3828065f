"""Mesh primitives (glTF 2.0, 3.7.2): triangles, strips and fans with their positions, normals, first texture
coordinates and tangents, as the PLY files an import writes beside its TOML. glTF puts v = 0 at the top of the image, as
spectrace does; a PLY's v runs up (spectrace's reader turns it), so v is written as 1 − v."""

from __future__ import annotations

import numpy as np

from spectrace.interop.gltf.document import GltfDocument
from spectrace.interop.pbrt.meshes import MeshData

TRIANGLES, TRIANGLE_STRIP, TRIANGLE_FAN = 4, 5, 6
MODE_NAMES = {0: "points", 1: "lines", 2: "line loops", 3: "line strips"}
# Attributes read, and those whose meaning spectrace has no place for (each named once in a warning).
READ_ATTRIBUTES = ("POSITION", "NORMAL", "TEXCOORD_0", "TANGENT")


def triangle_indices(mode: int, indices: np.ndarray) -> np.ndarray:
    """(m, 3) triangles of a primitive's vertex sequence, wound as glTF's first triangle is."""
    n = len(indices)
    if mode == TRIANGLES:
        return indices[: n - n % 3].reshape(-1, 3)
    if n < 3:
        return np.zeros((0, 3), dtype=np.int64)
    i = np.arange(n - 2)
    if mode == TRIANGLE_STRIP:  # every second triangle reversed, to keep one winding (glTF 2.0, 3.7.2.1)
        even = i % 2 == 0
        first = np.where(even, indices[i], indices[i + 1])
        second = np.where(even, indices[i + 1], indices[i])
        return np.column_stack([first, second, indices[i + 2]])
    return np.column_stack([np.full(n - 2, indices[0]), indices[i + 1], indices[i + 2]])  # fan


def primitive_mesh(doc: GltfDocument, primitive: dict, pointer: str) -> MeshData | None:
    """The primitive's triangles (None for points and lines, which have no area)."""
    mode = doc.index(primitive, "mode", pointer)
    mode = TRIANGLES if mode is None else mode
    if mode in MODE_NAMES:
        return None
    if mode not in (TRIANGLES, TRIANGLE_STRIP, TRIANGLE_FAN):
        raise doc.fail(f"{pointer}/mode", f"unknown primitive mode {mode}")
    attributes = doc.obj(primitive, "attributes", pointer)
    if "POSITION" not in attributes:
        raise doc.fail(f"{pointer}/attributes", "needs a POSITION accessor")
    for name in ("KHR_draco_mesh_compression",):
        if doc.extension(primitive, name, pointer) is not None:
            raise doc.fail(f"{pointer}/extensions/{name}", f"compressed with {name}, which spectrace does not decode")

    def read(name: str, width: int) -> np.ndarray:
        values = doc.accessor(attributes[name], f"{pointer}/attributes/{name}").astype(np.float64)
        if values.shape[1] != width:
            raise doc.fail(f"{pointer}/attributes/{name}", f"{name} must have {width} components")
        return values

    positions = read("POSITION", 3)
    count = len(positions)
    if "indices" in primitive:
        where = f"{pointer}/indices"
        indices = doc.accessor(primitive["indices"], where)
        if indices.dtype.kind != "i" or indices.shape[1] != 1:
            raise doc.fail(where, "indices must be unsigned integer scalars")
        indices = indices[:, 0]
        if len(indices) and (indices.min() < 0 or indices.max() >= count):
            raise doc.fail(where, f"index {int(indices.max())} beyond the {count} vertices")
    else:
        indices = np.arange(count)
    faces = triangle_indices(mode, indices)
    normals = uvs = tangents = None
    for name, width in (("NORMAL", 3), ("TEXCOORD_0", 2), ("TANGENT", 4)):
        if name in attributes:
            values = read(name, width)
            if len(values) != count:
                raise doc.fail(f"{pointer}/attributes/{name}", f"has {len(values)} elements, POSITION {count}")
            if name == "NORMAL":
                normals = values
            elif name == "TANGENT":
                tangents = values
            else:
                uvs = np.column_stack([values[:, 0], 1.0 - values[:, 1]])
    # Without normals the supplied tangents are ignored (glTF 2.0, 3.7.2.1: flat normals are computed then).
    return MeshData(positions, faces.astype(np.int64), normals, uvs, tangents if normals is not None else None)


def unread_attributes(primitive: dict) -> list[str]:
    return [name for name in primitive["attributes"] if name not in READ_ATTRIBUTES]
