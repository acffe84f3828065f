"""Meshes an import writes: pbrt's inline meshes and the shapes spectrace has no exact surface for (partial
spheres, disks and cylinders, tessellated here until spectrace has analytic ones), as binary PLY files beside the
TOML; and pbrt-v4's Area() of a whole analytic shape, which an area light's `power` divides by.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

TESSELLATION_SEGMENTS = 128  # disk and cylinder: the polygon's area is 0.9996 of the circle's


@dataclass
class MeshData:
    vertices: np.ndarray  # (n, 3) object space
    faces: np.ndarray  # (m, 3) int, winding = front (pbrt's rules applied)
    normals: np.ndarray | None = None
    uvs: np.ndarray | None = None  # pbrt's (u, v) as stored
    tangents: np.ndarray | None = None  # (n, 4) glTF's tangents (xyz along +u, w the handedness), with normals

    def world_area(self, matrix: np.ndarray) -> float:
        points = self.vertices @ matrix[:3, :3].T
        a, b, c = (points[self.faces[:, i]] for i in range(3))
        return float(0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1).sum())


def disk_mesh(height: float, radius: float, inner: float, phimax_degrees: float) -> MeshData:
    """pbrt's disk (the z = height plane, facing +z) as a ring of triangles, uv = (φ/φmax, (r - ri)/(r_max... ))."""
    segments = max(3, int(math.ceil(TESSELLATION_SEGMENTS * min(phimax_degrees, 360.0) / 360.0)))
    phi = np.linspace(0.0, math.radians(min(phimax_degrees, 360.0)), segments + 1)
    rings = np.array([radius, inner])
    xy = np.stack([np.cos(phi), np.sin(phi)], axis=1)
    vertices = np.concatenate([np.column_stack([r * xy, np.full(len(phi), height)]) for r in rings])
    n = len(phi)
    i = np.arange(segments)
    outer, inner_ring = i, i + n
    # pbrt's v runs from the outer edge (0) to the inner one (1).
    faces = np.concatenate(
        [np.stack([outer, outer + 1, inner_ring + 1], 1), np.stack([outer, inner_ring + 1, inner_ring], 1)]
    )
    uvs = np.column_stack([np.tile(phi / phi[-1], 2), np.repeat([0.0, 1.0], n)])
    if inner <= 0.0:  # the inner ring collapses to the centre: keep its fan, drop the degenerate triangles
        faces = faces[:segments]
    normals = np.tile([0.0, 0.0, 1.0], (len(vertices), 1))
    return MeshData(vertices, faces, normals, uvs)


def sphere_mesh(radius: float, zmin: float, zmax: float, phimax_degrees: float) -> MeshData:
    """pbrt's (partial) sphere about z as a grid of triangles facing outward, with radial normals and pbrt's uv:
    u = φ/φmax, v = (θ − θ(zmin)) / (θ(zmax) − θ(zmin)), θ = acos(z/r)."""
    phimax = math.radians(min(max(phimax_degrees, 0.0), 360.0))
    segments = max(3, int(math.ceil(TESSELLATION_SEGMENTS * phimax / (2 * math.pi))))
    theta_start, theta_end = (
        math.acos(max(-1.0, min(1.0, zmin / radius))),
        math.acos(max(-1.0, min(1.0, zmax / radius))),
    )
    rings = max(2, int(math.ceil(TESSELLATION_SEGMENTS / 2 * abs(theta_start - theta_end) / math.pi)))
    u = np.linspace(0.0, 1.0, segments + 1)
    v = np.linspace(0.0, 1.0, rings + 1)
    uu, vv = np.meshgrid(u, v)  # rows: v, from zmin up to zmax
    phi, theta = uu * phimax, theta_start + vv * (theta_end - theta_start)
    normals = np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)], -1).reshape(-1, 3)
    columns = segments + 1
    i, j = np.meshgrid(np.arange(rings), np.arange(segments), indexing="ij")
    a = (i * columns + j).ravel()
    b, c, d = a + 1, a + columns + 1, a + columns
    # (a, b, c) winds with dp/dφ × dp/dz, outward, as pbrt's sphere faces.
    faces = np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)])
    vertices = radius * normals
    area = 0.5 * np.linalg.norm(
        np.cross(vertices[faces[:, 1]] - vertices[faces[:, 0]], vertices[faces[:, 2]] - vertices[faces[:, 0]]), axis=1
    )
    faces = faces[area > 1e-12 * radius * radius]  # the poles' degenerate triangles
    return MeshData(vertices, faces, normals, np.stack([uu.ravel(), vv.ravel()], 1))


def cylinder_mesh(radius: float, zmin: float, zmax: float, phimax_degrees: float) -> MeshData:
    """pbrt's cylinder (about z, open, facing outward) as a band of triangles with radial normals."""
    zmin, zmax = min(zmin, zmax), max(zmin, zmax)
    segments = max(3, int(math.ceil(TESSELLATION_SEGMENTS * min(phimax_degrees, 360.0) / 360.0)))
    phi = np.linspace(0.0, math.radians(min(phimax_degrees, 360.0)), segments + 1)
    xy = np.stack([np.cos(phi), np.sin(phi)], axis=1)
    n = len(phi)
    vertices = np.concatenate([np.column_stack([radius * xy, np.full(n, z)]) for z in (zmin, zmax)])
    i = np.arange(segments)
    bottom, top = i, i + n
    faces = np.concatenate([np.stack([bottom, bottom + 1, top + 1], 1), np.stack([bottom, top + 1, top], 1)])
    normals = np.concatenate([np.column_stack([xy, np.zeros(n)])] * 2)
    uvs = np.column_stack([np.tile(phi / phi[-1], 2), np.repeat([0.0, 1.0], n)])
    return MeshData(vertices, faces, normals, uvs)


def vertex_normals(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Unit vertex normals: the sum of the area-weighted normals of the faces around each vertex."""
    a, b, c = (vertices[faces[:, i]] for i in range(3))
    face_normals = np.cross(b - a, c - a)
    normals = np.zeros_like(vertices, dtype=np.float64)
    for corner in range(3):
        np.add.at(normals, faces[:, corner], face_normals)
    length = np.linalg.norm(normals, axis=1, keepdims=True)
    return np.divide(normals, length, out=np.zeros_like(normals), where=length > 0)


def with_default_uvs(mesh: MeshData, kind: str) -> MeshData:
    """The mesh with pbrt's texture coordinates for meshes without any: (0, 0), (1, 0), (1, 1) at each triangle's
    corners; a bilinear patch's (0, 0)..(1, 1) at its corners (its second triangle p00, p11, p01). Each corner gets a
    vertex of its own."""
    count = len(mesh.faces)
    corners = np.tile([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]], (count, 1, 1))
    if kind == "bilinearmesh":  # faces: the patches' first triangles, then their second ones
        corners[count // 2 :] = [[0.0, 0.0], [1.0, 1.0], [0.0, 1.0]]
    return MeshData(
        mesh.vertices[mesh.faces.ravel()],
        np.arange(3 * count).reshape(count, 3),
        None if mesh.normals is None else mesh.normals[mesh.faces.ravel()],
        corners.reshape(-1, 2),
    )


def write_ply(path: Path, mesh: MeshData) -> None:
    """A binary PLY spectrace's mesh reader takes: positions, optional normals and texture coordinates (v as pbrt
    stores it, up the image; the reader turns it into spectrace's) and tangents with normals (tx, ty, tz, tw)."""
    columns = [mesh.vertices]
    names = ["x", "y", "z"]
    if mesh.normals is not None:
        columns.append(mesh.normals)
        names += ["nx", "ny", "nz"]
    if mesh.uvs is not None:
        columns.append(mesh.uvs)
        names += ["u", "v"]
    if mesh.tangents is not None and mesh.normals is not None:
        columns.append(mesh.tangents)
        names += ["tx", "ty", "tz", "tw"]
    vertex_data = np.ascontiguousarray(np.column_stack(columns), dtype="<f4")
    face_data = np.zeros(len(mesh.faces), dtype=[("n", "u1"), ("i", "<i4", (3,))])
    face_data["n"] = 3
    face_data["i"] = mesh.faces
    header = [
        "ply",
        "format binary_little_endian 1.0",
        "comment written by spectrace import-pbrt",
        f"element vertex {len(mesh.vertices)}",
        *(f"property float {name}" for name in names),
        f"element face {len(mesh.faces)}",
        "property list uchar int vertex_indices",
        "end_header",
    ]
    with open(path, "wb") as handle:
        handle.write(("\n".join(header) + "\n").encode("ascii"))
        handle.write(vertex_data.tobytes())
        handle.write(face_data.tobytes())
