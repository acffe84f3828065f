"""Built-in shapes, with Mitsuba 3's conventions so scenes port: rectangle, cube, sphere; and an equilateral prism
and the Utah teapot. BUILTIN_SHAPES lists them for the scene loader and the Python API.

All have outward (front-side) winding: the geometric normal (v1 - v0) x (v2 - v0) points away from the interior,
or along +z for the rectangle. All but the teapot (which stands on the origin) are centred on it.
"""

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
    """The cube [-1, 1]^3 with outward normals (12 triangles, area 24)."""
    # Corner index = 4*(x>0) + 2*(y>0) + (z>0).
    vertices = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], dtype=np.float64)
    # Each quad lists its corners counter-clockwise seen from outside.
    quads = [
        (0, 1, 3, 2),  # x = -1
        (4, 6, 7, 5),  # x = +1
        (0, 4, 5, 1),  # y = -1
        (2, 3, 7, 6),  # y = +1
        (0, 2, 6, 4),  # z = -1
        (1, 5, 7, 3),  # z = +1
    ]
    faces = np.array([tri for a, b, c, d in quads for tri in ((a, b, c), (a, c, d))], dtype=np.int64)
    return TriangleMesh(vertices=vertices, faces=faces)


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
    """Unit sphere at the origin: an icosphere with 20 * 4**subdivisions triangles, vertices on the sphere, and the
    sphere's exact radial normals at its vertices, so it shades smoothly."""
    import trimesh  # deferred: importing trimesh costs a noticeable fraction of a second

    if (
        isinstance(subdivisions, bool)
        or not isinstance(subdivisions, int)
        or not (0 <= subdivisions <= MAX_SPHERE_SUBDIVISIONS)
    ):
        raise SpectraceError(
            f"sphere subdivisions must be an integer from 0 to {MAX_SPHERE_SUBDIVISIONS}, got {subdivisions!r}"
        )
    icosphere = trimesh.creation.icosphere(subdivisions=subdivisions, radius=1.0)
    vertices = np.asarray(icosphere.vertices, dtype=np.float64)
    normals = vertices / np.linalg.norm(vertices, axis=1, keepdims=True)
    return TriangleMesh(vertices=vertices, faces=np.asarray(icosphere.faces), normals=normals)


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
