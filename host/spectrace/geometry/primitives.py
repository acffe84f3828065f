"""Built-in shapes, with Mitsuba 3's conventions so scenes port: rectangle, cube, sphere; and an equilateral prism
and the Utah teapot. BUILTIN_SHAPES lists them for the scene loader and the Python API.

All have outward (front-side) winding: the geometric normal (v1 - v0) x (v2 - v0) points away from the interior,
or along +z for the rectangle. All but the teapot (which stands on the origin) are centred on it.
"""

import functools

import numpy as np

from spectrace.errors import SpectraceError
from spectrace.geometry.mesh import TriangleMesh

# An icosphere with 8 subdivisions already has 1.3 million triangles.
MAX_SPHERE_SUBDIVISIONS = 8
# Quads per side of each of the teapot's 32 patches: 32 768 triangles, smooth to the eye at any size in the frame.
TEAPOT_SUBDIVISIONS = 16


def rectangle() -> TriangleMesh:
    """The square [-1, 1]^2 in the plane z = 0, facing +z (2 triangles, area 4). Texture coordinates show an
    image upright to a viewer on the +z side with +y up: u = (x + 1)/2, v = (1 - y)/2."""
    vertices = np.array([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]], dtype=np.float64)
    faces = np.array([[0, 1, 2], [0, 2, 3]], dtype=np.int64)
    uvs = np.array([[0, 1], [1, 1], [1, 0], [0, 0]], dtype=np.float64)
    return TriangleMesh(vertices=vertices, faces=faces, uvs=uvs)


def cube() -> TriangleMesh:
    """The cube [-1, 1]^3 with outward normals (12 triangles, area 24), flat-shaded. Each face has its own four
    corners so it can carry Mitsuba 3's cube's texture coordinates: the image once across each face, with u and v
    running along the face's axes as Mitsuba's own cube mesh has them (tests/interop measure them in Mitsuba)."""
    # Corner of [-1, 1]^3 by index = 4*(x>0) + 2*(y>0) + (z>0).
    corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], dtype=np.float64)
    # Each quad lists its corners counter-clockwise seen from outside, then the (axis, sign) that u and v each follow
    # across it: u = (1 + sign * coordinate[axis]) / 2, likewise v.
    quads = [
        ((0, 1, 3, 2), (1, 1), (2, 1)),  # x = -1
        ((4, 6, 7, 5), (1, 1), (2, -1)),  # x = +1
        ((0, 4, 5, 1), (2, 1), (0, 1)),  # y = -1
        ((2, 3, 7, 6), (0, -1), (2, -1)),  # y = +1
        ((0, 2, 6, 4), (1, -1), (0, 1)),  # z = -1
        ((1, 5, 7, 3), (1, 1), (0, 1)),  # z = +1
    ]
    vertices = np.concatenate([corners[list(quad)] for quad, _, _ in quads])
    uvs = np.concatenate(
        [
            np.stack(
                [(1 + u_sign * corners[list(quad), u_axis]) / 2, (1 + v_sign * corners[list(quad), v_axis]) / 2], 1
            )
            for quad, (u_axis, u_sign), (v_axis, v_sign) in quads
        ]
    )
    faces = np.array([(a, a + 1, a + 2) if t == 0 else (a, a + 2, a + 3) for a in range(0, 24, 4) for t in (0, 1)])
    return TriangleMesh(vertices=vertices, faces=faces.astype(np.int64), uvs=uvs)


def prism() -> TriangleMesh:
    """The equilateral triangular prism with outward normals (8 triangles): its cross-section in the xy plane has
    side 2, centroid at the origin, apex on +y at y = 2/√3 and base at y = −1/√3; it spans z ∈ [−1, 1]. The apex
    angle between the two slanted faces is 60°, as in a dispersing prism."""
    apex_y, base_y = 2.0 / np.sqrt(3.0), -1.0 / np.sqrt(3.0)
    corners = [(-1.0, base_y), (1.0, base_y), (0.0, apex_y)]  # counter-clockwise seen from +z
    vertices = np.array([[x, y, z] for z in (-1.0, 1.0) for x, y in corners], dtype=np.float64)
    # 0-2: back (z = -1), 3-5: front (z = +1).
    faces = [(0, 2, 1), (3, 4, 5)]
    for i in range(3):
        j = (i + 1) % 3
        faces += [(i, j, j + 3), (i, j + 3, i + 3)]  # side from corner i to j, counter-clockwise from outside
    return TriangleMesh(vertices=vertices, faces=np.array(faces, dtype=np.int64))


def sphere(subdivisions: int = 4) -> TriangleMesh:
    """Unit sphere at the origin: an icosphere with 20 * 4**subdivisions triangles (and a few more where its texture
    seam cuts them), vertices on the sphere (but those cuts, on chords), and the sphere's radial normals at its
    vertices, so it shades smoothly. Texture coordinates are Mitsuba 3's sphere's: u = φ / 2π with
    φ = atan2(y, x) in [0, 2π), v = θ / π with θ the angle from +z (v = 0 at the +z pole, the image's top row)."""
    _check_subdivisions(subdivisions)
    if subdivisions > _SPHERES_KEPT_UP_TO:
        vertices, faces, uvs, normals = _sphere_arrays.__wrapped__(subdivisions)
    else:  # copies: a caller may transform its mesh in place
        vertices, faces, uvs, normals = (array.copy() for array in _sphere_arrays(subdivisions))
    return TriangleMesh(vertices=vertices, faces=faces, uvs=uvs, normals=normals)


# Spheres up to this size are made once per process: cutting the seam walks the straddling triangles in Python
# (~5 ms at the default size, 4), and scenes, sessions and sweeps place spheres again and again; larger ones would
# keep tens of megabytes.
_SPHERES_KEPT_UP_TO = 5


@functools.lru_cache(maxsize=_SPHERES_KEPT_UP_TO + 1)
def _sphere_arrays(subdivisions: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    plain = icosphere(subdivisions)
    points, faces, normals = _cut_at_seam(plain.vertices, plain.faces)
    return _sphere_uvs(points, faces, normals)


def icosphere(subdivisions: int) -> TriangleMesh:
    """The unit icosphere: exactly 20 * 4**subdivisions triangles, vertices on the sphere with its radial normals,
    no texture coordinates (what the benchmarks count triangles on)."""
    import trimesh  # deferred: importing trimesh costs a noticeable fraction of a second

    _check_subdivisions(subdivisions)
    mesh = trimesh.creation.icosphere(subdivisions=subdivisions, radius=1.0)
    points = np.asarray(mesh.vertices, dtype=np.float64)
    points /= np.linalg.norm(points, axis=1, keepdims=True)
    return TriangleMesh(vertices=points, faces=np.asarray(mesh.faces, dtype=np.int64), normals=points.copy())


def _check_subdivisions(subdivisions: object) -> None:
    if (
        isinstance(subdivisions, bool)
        or not isinstance(subdivisions, int)
        or not (0 <= subdivisions <= MAX_SPHERE_SUBDIVISIONS)
    ):
        raise SpectraceError(
            f"sphere subdivisions must be an integer from 0 to {MAX_SPHERE_SUBDIVISIONS}, got {subdivisions!r}"
        )


def _cut_at_seam(points: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The triangles that cross the texture seam (the half-plane y = 0, x > 0, where u jumps from 1 back to 0) cut
    along it: each crossing edge gets a vertex where it meets the plane, shared by the triangles on both sides of
    the edge, so the surface is the same set of flat triangles and stays watertight. The new vertex's normal is
    its edge's normals interpolated, so smooth shading over the pieces is the shading over the whole triangle.
    Returns (points, faces, normals)."""
    normals = points / np.linalg.norm(points, axis=1, keepdims=True)
    side = np.where(np.abs(points[:, 1]) < 1e-12, 0, np.sign(points[:, 1])).astype(np.int64)
    new_points: list[np.ndarray] = []
    new_normals: list[np.ndarray] = []
    cut: dict[tuple[int, int], int | None] = {}

    def crossing(a: int, b: int) -> int | None:
        if side[a] * side[b] >= 0:
            return None
        key = (min(a, b), max(a, b))
        if key not in cut:
            t = points[a, 1] / (points[a, 1] - points[b, 1])
            point = points[a] + t * (points[b] - points[a])
            if point[0] <= 0.0:  # the plane's other half (u = 1/2) is no seam
                cut[key] = None
            else:
                point[1] = 0.0
                normal = normals[a] + t * (normals[b] - normals[a])
                cut[key] = len(points) + len(new_points)
                new_points.append(point)
                new_normals.append(normal / np.linalg.norm(normal))
        return cut[key]

    # Only triangles with corners on both sides of the plane can cross it; the rest are kept as they are.
    straddles = (side[faces] > 0).any(axis=1) & (side[faces] < 0).any(axis=1)
    out: list[tuple[int, int, int]] = []
    for face in faces[straddles]:
        corners = [int(i) for i in face]
        cuts = [crossing(corners[k], corners[(k + 1) % 3]) for k in range(3)]
        count = sum(c is not None for c in cuts)
        if count == 0:
            out.append((corners[0], corners[1], corners[2]))
            continue
        # Rotate the corners so that the first cut edge runs from a to b; winding is kept.
        k = next(k for k in range(3) if cuts[k] is not None)
        a, b, c = corners[k], corners[(k + 1) % 3], corners[(k + 2) % 3]
        ab, bc, ca = cuts[k], cuts[(k + 1) % 3], cuts[(k + 2) % 3]
        assert ab is not None
        if count == 1:  # c lies on the seam
            out += [(a, ab, c), (ab, b, c)]
        elif bc is not None:  # b alone on its side
            out += [(a, ab, c), (ab, bc, c), (ab, b, bc)]
        else:  # a alone on its side
            assert ca is not None
            out += [(a, ab, ca), (ab, b, c), (ab, c, ca)]
    if not new_points:
        return points, faces, normals
    kept = faces[~straddles]
    return (
        np.vstack([points, new_points]),
        np.vstack([kept, np.array(out, dtype=np.int64)]),
        np.vstack([normals, new_normals]),
    )


def _sphere_uvs(
    points: np.ndarray, faces: np.ndarray, normals: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(vertices, faces, uvs, normals) of a triangulated unit sphere cut at the seam, with Mitsuba's spherical
    coordinates of each vertex's direction. A vertex on the seam is u = 0 to the triangles on its y > 0 side and
    u = 1 to those on its y < 0 side, so it gets a copy; a pole has no azimuth, so each triangle meeting one gets its
    own copy there, at the mean u of its other two corners (the triangle's image is a thin wedge, as on a UV
    sphere). Vertices that every triangle sees alike stay shared."""
    direction = points / np.linalg.norm(points, axis=1, keepdims=True)
    phi = np.arctan2(direction[:, 1], direction[:, 0])
    u = np.where(phi < 0.0, phi + 2.0 * np.pi, phi) / (2.0 * np.pi)
    v = np.arccos(np.clip(direction[:, 2], -1.0, 1.0)) / np.pi
    pole = (np.hypot(direction[:, 0], direction[:, 1]) < 1e-9)[faces]
    on_seam = ((np.abs(direction[:, 1]) < 1e-12) & (direction[:, 0] > 0.0))[faces]
    below = (direction[:, 1] < -1e-12)[faces].any(axis=1)
    u = np.where((np.abs(direction[:, 1]) < 1e-12) & (direction[:, 0] > 0.0), 0.0, u)
    corner_u = np.where(on_seam & below[:, None], 1.0, u[faces])
    pole_u = np.nanmean(np.where(pole, np.nan, corner_u), axis=1)
    corner_u = np.where(pole, pole_u[:, None], corner_u)
    # Corners whose u is not their vertex's get vertices of their own, one per distinct (vertex, u).
    special = (on_seam & below[:, None]) | pole
    keys = np.stack([faces[special].astype(np.float64), corner_u[special]], axis=1)
    unique, inverse = np.unique(keys, axis=0, return_inverse=True)
    faces = faces.copy()
    faces[special] = len(points) + inverse.ravel()
    source = np.concatenate([np.arange(len(points)), unique[:, 0].astype(np.int64)])
    all_uvs = np.concatenate([np.stack([u, v], axis=1), np.stack([unique[:, 1], v[source[len(points) :]]], axis=1)])
    # Drop the vertices no corner uses any more (a pole's own, now one per triangle).
    used, compact = np.unique(faces, return_inverse=True)
    return (
        points[source[used]],
        compact.reshape(faces.shape).astype(np.int64),
        all_uvs[used],
        normals[source[used]],
    )


def teapot(subdivisions: int = TEAPOT_SUBDIVISIONS) -> TriangleMesh:
    """The Utah teapot (geometry/teapot.py), y up, standing on the origin: body radius 1, height 1.575, the spout
    towards +x; exact normals at its vertices (it shades smoothly) and texture coordinates around it."""
    from spectrace.geometry.teapot import newell_teapot

    vertices, faces, uvs, normals = newell_teapot(subdivisions)
    z_up_to_y_up = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]])  # (x, y, z) -> (x, z, -y)
    scale = 0.5  # the data's body radius is 2
    return TriangleMesh(
        vertices=scale * vertices @ z_up_to_y_up.T, faces=faces, uvs=uvs, normals=normals @ z_up_to_y_up.T
    )


# A shape's `type` in scene files and the Python API -> its mesh.
BUILTIN_SHAPES = {"rectangle": rectangle, "cube": cube, "sphere": sphere, "prism": prism, "teapot": teapot}
