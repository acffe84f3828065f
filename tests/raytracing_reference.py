"""Brute-force closest-hit reference for tests: every ray against every triangle, Möller–Trumbore in float64.

Independent of the BVH and the kernels on purpose (Möller & Trumbore 1997, "Fast, minimum storage
ray-triangle intersection"). Triangles are two-sided; a hit on an edge or a vertex counts (within 1e-12 in
barycentric coordinates, so rays aimed exactly at shared edges never slip through).
"""

import numpy as np

# Ray-triangle pairs evaluated per chunk: bounds the temporaries to some tens of MB.
_PAIRS_PER_CHUNK = 1 << 19
# |det| below this fraction of |e1| |e2| |d| means the ray runs in the triangle's plane (or it is degenerate).
_PARALLEL_RELATIVE_DET = 1e-12
# Barycentric slack: a ray aimed exactly at an edge shared by two triangles can round to just outside both;
# this closes such cracks, and moves a triangle's boundary by a negligible 1e-12 of its size.
_EDGE_TOLERANCE = 1e-12


def brute_force_closest_hit(
    origins: np.ndarray,
    directions: np.ndarray,
    v0: np.ndarray,
    v1: np.ndarray,
    v2: np.ndarray,
    *,
    t_min: float = 0.0,
) -> tuple[np.ndarray, np.ndarray]:
    """Closest hit with t > t_min of each ray o + t d: (t (R,), triangle index (R,)), inf and -1 for a miss.

    origins, directions: (R, 3); v0, v1, v2: (M, 3). Among hits at exactly equal t the lowest index wins."""
    origins, directions = (np.asarray(a, dtype=np.float64).reshape(-1, 3) for a in (origins, directions))
    v0, v1, v2 = (np.asarray(a, dtype=np.float64).reshape(-1, 3) for a in (v0, v1, v2))
    ray_count, triangle_count = len(origins), len(v0)
    t_hit = np.full(ray_count, np.inf)
    triangle = np.full(ray_count, -1, dtype=np.int64)
    if ray_count == 0 or triangle_count == 0:
        return t_hit, triangle

    e1, e2 = (v1 - v0).T, (v2 - v0).T  # (3, M) rows
    corner = v0.T
    edge_lengths = np.linalg.norm(e1, axis=0) * np.linalg.norm(e2, axis=0)
    rays_per_chunk = max(1, _PAIRS_PER_CHUNK // triangle_count)
    for begin in range(0, ray_count, rays_per_chunk):
        chunk = slice(begin, min(begin + rays_per_chunk, ray_count))
        t = _moller_trumbore(origins[chunk], directions[chunk], corner, e1, e2, edge_lengths, t_min)
        nearest = np.argmin(t, axis=1)
        nearest_t = t[np.arange(len(nearest)), nearest]
        hit = np.isfinite(nearest_t)
        t_hit[chunk] = nearest_t
        triangle[chunk] = np.where(hit, nearest, -1)
    return t_hit, triangle


def _moller_trumbore(
    origins: np.ndarray,
    directions: np.ndarray,
    corner: np.ndarray,
    e1: np.ndarray,
    e2: np.ndarray,
    edge_lengths: np.ndarray,
    t_min: float,
) -> np.ndarray:
    """(n, M) hit distance of each ray-triangle pair, inf where the ray misses."""
    ox, oy, oz = (origins[:, k : k + 1] for k in range(3))
    dx, dy, dz = (directions[:, k : k + 1] for k in range(3))
    # p = d x e2, det = e1 . p
    px, py, pz = dy * e2[2] - dz * e2[1], dz * e2[0] - dx * e2[2], dx * e2[1] - dy * e2[0]
    det = e1[0] * px + e1[1] * py + e1[2] * pz
    # s = o - v0, q = s x e1
    sx, sy, sz = ox - corner[0], oy - corner[1], oz - corner[2]
    qx, qy, qz = sy * e1[2] - sz * e1[1], sz * e1[0] - sx * e1[2], sx * e1[1] - sy * e1[0]
    with np.errstate(divide="ignore", invalid="ignore"):
        inverse_det = 1.0 / det
        u = (sx * px + sy * py + sz * pz) * inverse_det
        v = (dx * qx + dy * qy + dz * qz) * inverse_det
        t = (e2[0] * qx + e2[1] * qy + e2[2] * qz) * inverse_det
        direction_lengths = np.linalg.norm(directions, axis=1, keepdims=True)
        not_parallel = np.abs(det) > _PARALLEL_RELATIVE_DET * edge_lengths * direction_lengths
        inside = (u >= -_EDGE_TOLERANCE) & (v >= -_EDGE_TOLERANCE) & (u + v <= 1.0 + _EDGE_TOLERANCE)
        hit = not_parallel & inside & (t > t_min)
    return np.where(hit, t, np.inf)
