"""The shading-normal rows of smooth triangles, with the tangents a mesh file supplies (glTF's TANGENT) beside them
(kernels/vertex_tangents.cl reads them). A triangle with vertex normals owns slot k of triangle_normals: its three
corner normals (x, y, z, 0). One that also has file tangents owns slots k and k + 1: the normals with w = its
handedness (±1) in the first corner's w, then its three corner tangents (x, y, z, w). A scene without file
tangents gets exactly the rows it had before: one slot per smooth triangle, every w 0."""

import numpy as np


def corner_tangents(parts: list[np.ndarray | None], counts: list[int]) -> np.ndarray | None:
    """(M, 3, 4) corner tangents of all shapes' triangles, zero for the shapes without; None when no shape has any
    (the usual case, which costs no host memory)."""
    if all(part is None for part in parts):
        return None
    return np.concatenate([np.zeros((n, 3, 4)) if part is None else part for part, n in zip(parts, counts)])


def smooth_rows(
    corner_normals: np.ndarray | None, tangents: np.ndarray | None, smooth: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """(slot of each triangle, -1 where flat; (K, 3, 4) float32 rows) of triangles whose corner normals are
    `corner_normals` (M, 3, 3) and tangents `tangents` (M, 3, 4, or None), `smooth` (M,) the triangles that shade
    with their normals. A triangle takes its tangents where all three are nonzero with a handedness."""
    count = int(smooth.sum())
    slots = np.full(len(smooth), -1, np.int32)
    if tangents is None:
        slots[smooth] = np.arange(count, dtype=np.int32)
        rows = np.zeros((count, 3, 4), np.float32)
        if corner_normals is not None:
            rows[:, :, :3] = corner_normals[smooth]
        return slots, rows
    assert corner_normals is not None  # a mesh has tangents only beside its normals (TriangleMesh.corner_tangents)
    usable = (np.linalg.norm(tangents[:, :, :3], axis=-1) > 0).all(axis=1) & (tangents[:, :, 3] != 0).all(axis=1)
    usable &= np.isfinite(tangents).all(axis=(1, 2))
    with_tangents = usable[smooth]
    widths = 1 + with_tangents.astype(np.int32)
    starts = np.cumsum(widths, dtype=np.int32) - widths
    slots[smooth] = starts
    rows = np.zeros((int(widths.sum()), 3, 4), np.float32)
    rows[starts, :, :3] = corner_normals[smooth]
    first = starts[with_tangents]
    chosen = tangents[smooth][with_tangents]
    # The triangle's handedness: its corners' (one value on any mesh a tangent generator wrote).
    rows[first, 0, 3] = np.where(chosen[:, :, 3].sum(axis=1) < 0, -1.0, 1.0)
    rows[first + 1] = chosen
    return slots, rows
