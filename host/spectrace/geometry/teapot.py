"""The Utah teapot: Martin Newell's 32 bicubic Bezier patches (1975), tessellated with the surface's own normals
and a texture parameterisation, so that a scene can show smooth shading and textures on an object every reader
knows without a downloaded file. The control points are public data (scenes/teapot/newell_teapot_patches.txt,
which names its source).

Each patch P(u, v) = sum_ij B_i(v) B_j(u) C_ij (cubic Bernstein polynomials B) becomes an n x n grid of quads,
two triangles each, wound so that (v1 - v0) x (v2 - v0) points along dP/du x dP/dv, which is outward for every
patch of this data set. Normals are dP/du x dP/dv at the vertex itself (exact, not averaged from faces); where it
vanishes (the lid's knob and the bottom's centre, where a patch edge collapses to a point) it is taken a hair
inside the patch, its limit there. Texture coordinates: the body's twelve patches (rim, upper and lower body, four
around each) share one image, u once around and v from the rim (top of the image) to the base; every other group
of four patches (handle, spout, lid, lid underside, bottom) maps the image once around itself.
"""

from functools import cache

import numpy as np

from spectrace.resources import scenes_dir

PATCH_COUNT = 32
CONTROL_POINT_COUNT = 306
BODY_PATCHES = 12  # rim, upper body, lower body: four patches around each
HEIGHT = 3.15  # of the data: base at z = 0, the lid's knob at z = 3.15
# Parameter distance from a collapsed patch edge at which its normal is taken (its limit at the edge).
_COLLAPSED_EDGE_OFFSET = 1e-4


@cache
def _patches() -> tuple[np.ndarray, np.ndarray]:
    """(32, 4, 4) control-point indices, [row along v][column along u]; (306, 3) control points."""
    path = scenes_dir() / "teapot" / "newell_teapot_patches.txt"
    rows = [line.split() for line in path.read_text(encoding="utf-8").splitlines() if line and line[0] != "#"]
    indices = np.array(rows[:PATCH_COUNT], dtype=np.int64).reshape(PATCH_COUNT, 4, 4)
    points = np.array(rows[PATCH_COUNT:], dtype=np.float64)
    if points.shape != (CONTROL_POINT_COUNT, 3):
        raise ValueError(f"{path}: expected {CONTROL_POINT_COUNT} control points, got {points.shape}")
    return indices, points


def _bernstein(t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Cubic Bernstein polynomials at t and their derivatives, each (len(t), 4)."""
    s = 1.0 - t
    values = np.stack([s**3, 3.0 * t * s * s, 3.0 * t * t * s, t**3], axis=-1)
    slopes = np.stack([-3.0 * s * s, 3.0 * s * s - 6.0 * t * s, 6.0 * t * s - 3.0 * t * t, 3.0 * t * t], axis=-1)
    return values, slopes


def newell_teapot(subdivisions: int = 8) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(vertices (N, 3), faces (M, 3), uvs (N, 2), normals (N, 3) unit) of the teapot, each patch cut into
    subdivisions x subdivisions quads: 32 (n + 1)^2 vertices and 64 n^2 triangles. z is up, as in the data."""
    indices, points = _patches()
    n = int(subdivisions)
    t = np.linspace(0.0, 1.0, n + 1)
    basis, slope = _bernstein(t)
    inner = np.clip(t, _COLLAPSED_EDGE_OFFSET, 1.0 - _COLLAPSED_EDGE_OFFSET)
    inner_basis, inner_slope = _bernstein(inner)
    controls = points[indices]  # (32, 4, 4, 3)
    vertices = np.einsum("vi,uj,pijc->pvuc", basis, basis, controls)
    normals = np.cross(
        np.einsum("vi,uj,pijc->pvuc", basis, slope, controls), np.einsum("vi,uj,pijc->pvuc", slope, basis, controls)
    )
    inside = np.cross(
        np.einsum("vi,uj,pijc->pvuc", inner_basis, inner_slope, controls),
        np.einsum("vi,uj,pijc->pvuc", inner_slope, inner_basis, controls),
    )
    length = np.linalg.norm(normals, axis=-1, keepdims=True)
    collapsed = length[..., 0] < 1e-9 * np.max(length)
    normals[collapsed] = inside[collapsed]
    normals /= np.linalg.norm(normals, axis=-1, keepdims=True)

    patch = np.arange(PATCH_COUNT)[:, None, None]
    u_grid, v_grid = np.meshgrid(t, t)  # [v][u]
    around = (patch % 4 + u_grid) / 4.0
    body_row = np.where(patch < BODY_PATCHES, patch // 4, 0)
    down = np.where(patch < BODY_PATCHES, (body_row + v_grid) / 3.0, v_grid)
    uvs = np.stack(np.broadcast_arrays(around, down), axis=-1)

    grid = np.arange((n + 1) ** 2).reshape(n + 1, n + 1)
    a, b, c, d = grid[:-1, :-1], grid[:-1, 1:], grid[1:, 1:], grid[1:, :-1]  # (v, u), (v, u+1), ...
    quads = np.stack([np.stack([a, b, c], -1), np.stack([a, c, d], -1)], axis=-2).reshape(-1, 3)
    faces = (quads[None] + (np.arange(PATCH_COUNT) * (n + 1) ** 2)[:, None, None]).reshape(-1, 3)
    return vertices.reshape(-1, 3), faces, uvs.reshape(-1, 2), normals.reshape(-1, 3)
