"""Signed-distance grids: Mitsuba 3's `sdfgrid` shape, intersected exactly by the kernels (kernels/shape_sdf_grid.cl).

A grid of nx × ny × nz samples (x fastest; at least 2 along each axis) sits at the corners of the voxels that fill
the unit cube of object space: sample (i, j, k) at (i/(nx−1), j/(ny−1), k/(nz−1)), as Mitsuba 3 places them (unlike
its `gridvolume`, whose values sit at voxel centres). The surface is the zero set of the trilinear interpolant in
the voxels whose corners take both signs, its outside where the samples are positive; `to_world` places the cube.
The shading normal is the interpolant's gradient ("analytic") or the blend of the neighbouring voxels' gradients
("smooth", Mitsuba's default; the kernel file cites the method). There are no texture coordinates and no area
sampling, so an SDF grid cannot emit (Mitsuba's limits too).

The samples go into the analytic shapes' device buffer after its rows (append_grid_blocks), where each grid's row
finds them relative to itself, so an instanced object's grid is read through the same row as a placed one.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from spectrace.core.contract import ANALYTIC_SHAPE_DTYPE, SHAPE_TYPES
from spectrace.errors import SpectraceError
from spectrace.geometry.analytic import AnalyticSurface
from spectrace.geometry.grid_volume import MAX_VOXELS, read_vol
from spectrace.geometry.mesh import TriangleMesh
from spectrace.geometry.transforms import apply_transform

SDF_NORMALS = ("smooth", "analytic")
_ROW_FLOATS = ANALYTIC_SHAPE_DTYPE.itemsize // 4
_HEADER_WORDS = 4  # nx, ny, nz, smooth (kernels/shape_sdf_grid.cl)


@dataclass(frozen=True, eq=False)
class SdfGridSurface(AnalyticSurface):
    """An SDF grid placed by `to_world` (kind "sdfgrid"): `values` float32 (nz, ny, nx), `normals` one of
    SDF_NORMALS."""

    values: np.ndarray = None  # type: ignore[assignment]  # always given (make_sdf_grid)
    normals: str = "smooth"

    def occupied(self) -> np.ndarray:
        """(nz−1, ny−1, nx−1): the voxels whose corners take both signs (f ≥ 0 and f ≤ 0 among them)."""
        v = self.values
        nz, ny, nx = v.shape
        stack = np.stack(
            [v[z : z + nz - 1, y : y + ny - 1, x : x + nx - 1] for z in (0, 1) for y in (0, 1) for x in (0, 1)]
        )
        return np.asarray((stack >= 0).any(axis=0) & (stack <= 0).any(axis=0))

    def object_box(self) -> tuple[np.ndarray, np.ndarray]:
        """The object-space box of the occupied voxels (where the surface can be)."""
        z, y, x = np.nonzero(self.occupied())
        cells = np.array(self.values.shape[::-1], float) - 1.0
        lo = np.array([x.min(), y.min(), z.min()], float) / cells
        hi = (np.array([x.max(), y.max(), z.max()], float) + 1.0) / cells
        return lo, hi

    def object_area(self) -> float:
        return 0.0

    def area(self) -> float:
        return 0.0

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """The world box of the occupied voxels' box, widened by a relative 1e-6 against float32 rounding."""
        lo, hi = self.object_box()
        corners = np.array([[x, y, z, 1.0] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])
        world = corners @ np.asarray(self.to_world, float).T
        lo, hi = world[:, :3].min(axis=0), world[:, :3].max(axis=0)
        pad = 1e-6 * (np.abs(lo).max() + np.abs(hi).max() + (hi - lo).max())
        return lo - pad, hi + pad

    def device_row(self) -> np.ndarray:
        """The AnalyticShape row; its block offset is set by append_grid_blocks."""
        matrix = np.asarray(self.to_world, float)
        row = np.zeros((), ANALYTIC_SHAPE_DTYPE)
        row["to_world"] = matrix[:3]
        row["to_object"] = np.linalg.inv(matrix)[:3]
        row["type"] = SHAPE_TYPES.index("sdfgrid")
        row["abs_det"] = abs(np.linalg.det(self.linear))
        return row

    def block(self) -> np.ndarray:
        """The grid's block as float32 words: the header (as int bits), then the samples."""
        nz, ny, nx = self.values.shape
        header = np.array([nx, ny, nz, int(self.normals == "smooth")], np.int32).view(np.float32)
        return np.concatenate([header, self.values.ravel().astype(np.float32)])

    def tessellation(self) -> TriangleMesh:
        """Triangles on the zero set (marching tetrahedra over the voxels, world space), for what reads triangles:
        bounds checks, statistics, the Mitsuba export."""
        return apply_transform(zero_set_mesh(self.values), self.to_world)


def make_sdf_grid(values, to_world, normals: str = "smooth", where: str | None = None) -> SdfGridSurface:
    """A checked SdfGridSurface from samples shaped (nz, ny, nx) (or (nz, ny, nx, 1), a .vol file's shape)."""
    try:
        array = np.asarray(values, np.float64)
    except (TypeError, ValueError):
        raise SpectraceError("the SDF grid's values must be a 3-D array of numbers", where=where) from None
    if array.ndim == 4 and array.shape[3] == 1:
        array = array[..., 0]
    if array.ndim != 3 or min(array.shape) < 2:
        raise SpectraceError(
            f"an SDF grid needs a 3-D grid of at least 2 samples along each axis, got shape {array.shape}", where=where
        )
    if array.size > MAX_VOXELS:
        raise SpectraceError(f"the SDF grid has {array.size} samples, more than the {MAX_VOXELS} allowed", where=where)
    if not np.all(np.isfinite(array)):
        raise SpectraceError("the SDF grid holds values that are not finite", where=where)
    if normals not in SDF_NORMALS:
        raise SpectraceError(f"normals must be 'smooth' or 'analytic', got {normals!r}", where=where)
    matrix = np.asarray(to_world, np.float64)
    if matrix.shape != (4, 4) or not np.all(np.isfinite(matrix)) or abs(np.linalg.det(matrix[:3, :3])) < 1e-12:
        raise SpectraceError("the SDF grid's placement must be an invertible 4×4 transform", where=where)
    surface = SdfGridSurface("sdfgrid", matrix, values=np.ascontiguousarray(array, np.float32), normals=normals)
    if not surface.occupied().any():
        raise SpectraceError("the SDF grid has no surface: no voxel has samples of both signs", where=where)
    return surface


def read_sdf_grid(path: Path, where: str) -> np.ndarray:
    """The samples (nz, ny, nx) of a one-channel Mitsuba volume file (its bounding box is not used: Mitsuba's
    sdfgrid fills the unit cube)."""
    values, _, _ = read_vol(path, where)
    if values.shape[3] != 1:
        raise SpectraceError(
            f"an SDF grid's volume file has one channel, '{Path(path).name}' has {values.shape[3]}", where=where
        )
    return values[..., 0]


def append_grid_blocks(rows: np.ndarray, surfaces: list) -> np.ndarray:
    """The AnalyticShape rows with the SDF grids' blocks appended (as whole rows of floats) and each grid row's
    offset to its block set; `surfaces[k]` is row k's surface. Rows without grids are returned as they are."""
    grids = [(k, s) for k, s in enumerate(surfaces) if isinstance(s, SdfGridSurface)]
    if not grids:
        return rows
    start = len(rows) * _ROW_FLOATS
    rows = rows.copy()
    blocks = []
    for k, surface in grids:
        block = surface.block()
        offset = start - k * _ROW_FLOATS  # floats from row k's start
        sphere = rows["sphere"][k].copy()
        sphere.view(np.int32)[0] = offset
        rows["sphere"][k] = sphere
        blocks.append(block)
        start += len(block)
    data = np.concatenate(blocks)
    data = np.concatenate([data, np.zeros(-len(data) % _ROW_FLOATS, np.float32)])
    words = [rows.view(np.float32).reshape(len(rows), _ROW_FLOATS), data.reshape(-1, _ROW_FLOATS)]
    return np.concatenate(words).reshape(-1).view(ANALYTIC_SHAPE_DTYPE)


# Marching tetrahedra: each voxel cut into six tetrahedra around its main diagonal (corner 0 to corner 7), corners
# numbered as in the kernel (x + 2y + 4z).
_TETRAHEDRA = np.array([[0, 1, 3, 7], [0, 3, 2, 7], [0, 2, 6, 7], [0, 6, 4, 7], [0, 4, 5, 7], [0, 5, 1, 7]])
_CORNERS = np.array([[x, y, z] for z in (0, 1) for y in (0, 1) for x in (0, 1)], float)


def zero_set_mesh(values: np.ndarray) -> TriangleMesh:
    """Triangles close to the zero set of the samples' interpolant in the unit cube (linear along the tetrahedra's
    edges), wound to face the positive side, with texture coordinates (0, 0); a grid's exact surface is the
    kernels'."""
    nz, ny, nx = values.shape
    cells = np.array([nx - 1, ny - 1, nz - 1], float)
    z, y, x = np.nonzero(SdfGridSurface("sdfgrid", np.eye(4), values=values).occupied())
    base = np.stack([x, y, z], axis=1)
    corner_f = np.stack([values[z + int(c[2]), y + int(c[1]), x + int(c[0])] for c in _CORNERS], axis=1).astype(
        np.float64
    )
    triangles: list[np.ndarray] = []
    for tet in _TETRAHEDRA:
        f = corner_f[:, tet]
        p = base[:, None, :] + _CORNERS[tet][None]
        inside = f < 0
        count = inside.sum(axis=1)
        for n_in in (1, 2, 3):
            sel = count == n_in
            if not sel.any():
                continue
            fs, ps, ins = f[sel], p[sel], inside[sel]
            order = np.argsort(~ins, axis=1, kind="stable")  # the corners inside first
            fo = np.take_along_axis(fs, order, 1)
            po = np.take_along_axis(ps, order[..., None], 1)

            def cut(a, b, fo=fo, po=po):
                t = fo[:, a] / (fo[:, a] - fo[:, b])
                return po[:, a] + t[:, None] * (po[:, b] - po[:, a])

            if n_in == 1:
                triangles.append(np.stack([cut(0, 1), cut(0, 2), cut(0, 3)], axis=1))
            elif n_in == 3:
                triangles.append(np.stack([cut(0, 3), cut(1, 3), cut(2, 3)], axis=1))
            else:
                a, b, c, d = cut(0, 2), cut(0, 3), cut(1, 3), cut(1, 2)
                triangles.append(np.stack([a, b, c], axis=1))
                triangles.append(np.stack([a, c, d], axis=1))
    tris = np.concatenate(triangles) / cells if triangles else np.zeros((0, 3, 3))
    # Wind each triangle to face the outside: along the samples' gradient (central differences) at its centre.
    grad = np.stack(list(np.gradient(values.astype(np.float64), axis=(2, 1, 0))), axis=-1) * cells
    centre = tris.mean(axis=1) * cells
    index = np.clip(np.rint(centre).astype(int), 0, np.array([nx, ny, nz]) - 1)
    outward = grad[index[:, 2], index[:, 1], index[:, 0]]
    normal = np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0])
    flip = np.einsum("ij,ij->i", normal, outward) < 0
    tris[flip] = tris[flip][:, ::-1]
    area = np.linalg.norm(normal, axis=1) > 0
    tris = tris[area]
    vertices = tris.reshape(-1, 3)
    faces = np.arange(len(vertices)).reshape(-1, 3)
    # Texture coordinates all (0, 0), as the kernels give an SDF grid's hits (Mitsuba's sdfgrid has none).
    return TriangleMesh(vertices=vertices, faces=faces, uvs=np.zeros((len(vertices), 2)))
