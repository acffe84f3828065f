"""Analytic shapes: Mitsuba 3's sphere, disk and cylinder, intersected exactly by the kernels (kernels/shapes.cl).

In object space (Mitsuba 3's plugins, checked against Mitsuba itself in tests/geometry/test_analytic_shapes.py):
- sphere: radius 1 at the origin; u = φ/2π with φ = atan2(y, x) in [0, 2π), v = θ/π with θ the angle from +z;
- disk: radius 1 in the plane z = 0, facing +z (one face); u = r, v = φ/2π;
- cylinder: radius 1 around the z axis from z = 0 to z = 1, open (no caps), facing outward; u = φ/2π, v = z.
A partial shape (pbrt-v4's phimax, zmin/zmax, innerradius; kernels/shape_partial.cl) keeps the azimuths φ in
[0, phi_max] (radians), the sphere's object z in `z_range`, the disk's radii in [inner_radius, 1]; its texture
coordinates are pbrt's with pbrt_uv (u = φ/φmax, ...), else the whole shape's.
`to_world` places the shape: any affine map for the disk and cylinder (intersected in object space, normals by the
inverse transpose, so a non-uniform scale gives an exact elliptic disk or cylinder); a similarity for the sphere
(translation, rotation, uniform scale), whose centre and radius the kernels use in world space.

Each shape also keeps a tessellation (`mesh`) for what reads triangles: bounds, the Mitsuba export fallback, scene
statistics.
"""

from dataclasses import dataclass

import numpy as np

from spectrace.core.contract import ANALYTIC_SHAPE_DTYPE, SHAPE_TYPES
from spectrace.core.equality import fields_equal, identity_hash
from spectrace.geometry.mesh import TriangleMesh
from spectrace.geometry.transforms import apply_transform

# ("sphere", "disk", "cylinder"): the quadrics, scene types that are analytic unless tessellated; the device's other
# shape, the SDF grid, is geometry/sdf_grid.py's.
ANALYTIC_SHAPES = SHAPE_TYPES[:3]
OBJECT_AREA = {"sphere": 4.0 * np.pi, "disk": np.pi, "cylinder": 2.0 * np.pi}
# A sphere's map is a similarity when its linear part's columns are orthogonal and of equal length to this relative
# tolerance (a float transform built from rotations and a uniform scale is far within it).
_SIMILARITY_TOLERANCE = 1e-6
# Azimuth steps for the cylinder's area under a non-uniform scale (the trapezoid rule on a smooth periodic integrand
# converges geometrically: 1024 steps are exact to float precision for any reasonable ellipse).
_AREA_STEPS = 1024


def similarity_problem(matrix: np.ndarray) -> str | None:
    """Why an analytic sphere cannot take this map (it would not stay a sphere), or None."""
    linear = np.asarray(matrix, float)[:3, :3]
    gram = linear.T @ linear
    scale2 = np.trace(gram) / 3.0
    if not scale2 > 0 or np.abs(gram - scale2 * np.eye(3)).max() > _SIMILARITY_TOLERANCE * scale2:
        return "an analytic sphere's transform must scale uniformly (no shear or non-uniform scale)"
    return None


class CutError(ValueError):
    """A partial shape's key that does not fit: `key` names it."""

    def __init__(self, key: str, message: str):
        super().__init__(message)
        self.key = key


def cut_parameters(
    kind: str,
    phi_max: float | None = None,
    z_min: float | None = None,
    z_max: float | None = None,
    inner_radius: float | None = None,
    radius: float = 1.0,
) -> dict:
    """AnalyticSurface's keywords of a partial shape from the scene keys (phi_max in degrees; a sphere's z_min,
    z_max heights in [-radius, radius], as pbrt's; a disk's inner_radius a fraction of its radius 1); {} for the
    whole shape.
    Raises CutError naming the key that does not fit."""
    cuts: dict = {}
    if phi_max is not None:
        if not 0.0 < phi_max <= 360.0:
            raise CutError("phi_max", f"phi_max must be in (0, 360] degrees, got {phi_max:g}")
        if phi_max < 360.0:
            cuts["phi_max"] = float(np.radians(phi_max))
    if (z_min is not None or z_max is not None) and kind != "sphere":
        raise CutError("z_min", f"z_min and z_max cut a sphere, not a {kind} (a cylinder's height is its transform's)")
    if inner_radius is not None and kind != "disk":
        raise CutError("inner_radius", f"inner_radius is a disk's, not a {kind}'s")
    if kind == "sphere" and (z_min is not None or z_max is not None):
        lo = -radius if z_min is None else z_min
        hi = radius if z_max is None else z_max
        if not -radius <= lo < hi <= radius:
            raise CutError("z_min", f"z_min < z_max must lie in [-radius, radius] = [{-radius:g}, {radius:g}]")
        if (lo, hi) != (-radius, radius):
            cuts["z_range"] = (lo / radius, hi / radius)
    if inner_radius is not None:
        if not 0.0 <= inner_radius < 1.0:
            raise CutError(
                "inner_radius",
                f"inner_radius must be in [0, 1) (a fraction of the disk's radius), got {inner_radius:g}",
            )
        if inner_radius > 0.0:
            cuts["inner_radius"] = float(inner_radius)
    return cuts


@dataclass(frozen=True, eq=False)
class AnalyticSurface:
    __eq__ = fields_equal  # by value (arrays too), hashed by identity
    __hash__ = identity_hash

    kind: str  # "sphere", "disk" or "cylinder"
    to_world: np.ndarray  # (4, 4) object -> world
    flip_normals: bool = False  # the front (normal, emitting side) inward, or the disk's -z side
    # Texture coordinates as pbrt-v4 gives them (kernels/shapes.cl, shape_uv_from_mitsuba): the disk's u = φ/2π,
    # v = 1 - r, the sphere's v = 1 - θ/π; Mitsuba's otherwise (the cylinders agree).
    pbrt_uv: bool = False
    phi_max: float = 2.0 * np.pi  # radians, in (0, 2π]
    z_range: tuple[float, float] = (-1.0, 1.0)  # the sphere's object z kept
    inner_radius: float = 0.0  # the disk's object radius below which it is cut away

    @property
    def partial(self) -> bool:
        return self.phi_max < 2.0 * np.pi or tuple(self.z_range) != (-1.0, 1.0) or self.inner_radius > 0.0

    def cut_keys(self) -> dict:
        """The scene keys of a partial shape in its object space (cut_parameters' inverse); {} for a whole one."""
        keys: dict = {}
        if self.phi_max < 2.0 * np.pi:
            keys["phi_max"] = float(np.degrees(self.phi_max))
        if tuple(self.z_range) != (-1.0, 1.0):
            keys["z_min"], keys["z_max"] = (float(z) for z in self.z_range)
        if self.inner_radius > 0.0:
            keys["inner_radius"] = float(self.inner_radius)
        return keys

    def object_area(self) -> float:
        """Object-space area of the (partial) surface."""
        if self.kind == "sphere":
            return float(self.phi_max * (self.z_range[1] - self.z_range[0]))
        if self.kind == "disk":
            return float(0.5 * self.phi_max * (1.0 - self.inner_radius**2))
        return float(self.phi_max)

    @property
    def linear(self) -> np.ndarray:
        return np.asarray(self.to_world, float)[:3, :3]

    def normal_stretch(self, object_normals: np.ndarray) -> np.ndarray:
        """World area per object area at points with these unit object-space normals: |det M| |M⁻ᵀ n|."""
        inverse_transpose = np.linalg.inv(self.linear).T
        return abs(np.linalg.det(self.linear)) * np.linalg.norm(object_normals @ inverse_transpose.T, axis=-1)

    def area(self) -> float:
        """World-space area, scene units²."""
        if self.kind == "disk":
            return float(self.object_area() * self.normal_stretch(np.array([[0.0, 0.0, 1.0]]))[0])
        if self.kind == "sphere":
            return float(self.object_area() * abs(np.linalg.det(self.linear)) ** (2.0 / 3.0))
        # The midpoint rule over [0, φmax]; exact to float precision for the whole period, and for a part to
        # O(1/steps²) of the stretch's variation.
        phi = self.phi_max * (np.arange(_AREA_STEPS) + 0.5) / _AREA_STEPS
        normals = np.stack([np.cos(phi), np.sin(phi), np.zeros_like(phi)], axis=1)
        return float(self.object_area() * self.normal_stretch(normals).mean())

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """The exact axis-aligned box (lower, upper corner) of the placed shape, widened by a relative 1e-6 so that
        float32 rounding never cuts it."""
        matrix = np.asarray(self.to_world, float)
        if self.kind == "sphere":
            centre, radius = self.sphere_centre_radius()
            lo, hi = centre - radius, centre + radius
        else:
            # A circle of radius 1 in the object's xy plane spans ±|row i of M's first two columns| along axis i.
            half = np.hypot(matrix[:3, 0], matrix[:3, 1])
            ends = [matrix[:3, 3]] + ([matrix[:3, 3] + matrix[:3, 2]] if self.kind == "cylinder" else [])
            lo, hi = np.min(ends, axis=0) - half, np.max(ends, axis=0) + half
        pad = 1e-6 * (np.abs(lo).max() + np.abs(hi).max() + (hi - lo).max())
        return lo - pad, hi + pad

    def sphere_centre_radius(self) -> tuple[np.ndarray, float]:
        matrix = np.asarray(self.to_world, float)
        return matrix[:3, 3].copy(), float(abs(np.linalg.det(self.linear)) ** (1.0 / 3.0))

    def device_row(self) -> np.ndarray:
        """The AnalyticShape row (kernels/types.h)."""
        matrix = np.asarray(self.to_world, float)
        row = np.zeros((), ANALYTIC_SHAPE_DTYPE)
        row["to_world"] = matrix[:3]
        row["to_object"] = np.linalg.inv(matrix)[:3]
        row["type"] = SHAPE_TYPES.index(self.kind)
        row["abs_det"] = abs(np.linalg.det(self.linear))
        row["object_area"] = OBJECT_AREA[self.kind]
        row["flip_normals"] = int(self.flip_normals)
        row["pbrt_uv"] = int(self.pbrt_uv)
        if self.partial:  # whole shapes keep phi_max = 0, and with it shapes.cl's own arithmetic
            row["object_area"] = self.object_area()
            row["phi_max"] = self.phi_max
            row["cut_min"] = self.z_range[0] if self.kind == "sphere" else self.inner_radius
            row["cut_max"] = self.z_range[1]
        if self.kind == "sphere":
            centre, radius = self.sphere_centre_radius()
            row["sphere"] = (*centre, radius)
        return row

    def tessellation(self) -> TriangleMesh:
        """Triangles close to the surface, in world space, facing as the surface does, with its normals and texture
        coordinates."""
        if self.partial:
            mesh = apply_transform(self.partial_tessellation(), self.to_world)
            return mesh.flipped() if self.flip_normals else mesh
        mesh = apply_transform(object_tessellation(self.kind), self.to_world)
        if self.pbrt_uv:
            mesh = TriangleMesh(
                mesh.vertices, mesh.faces, uvs=pbrt_uv_from_mitsuba(self.kind, mesh.uvs), normals=mesh.normals
            )
        if self.flip_normals:
            mesh = mesh.flipped()
        return mesh

    def parameters_uv(self, phi, q):
        """The shape's texture coordinates at azimuth φ and q (θ of the sphere, r of the disk, z of the cylinder) as
        kernels/shape_partial.cl gives them for a partial shape."""
        phi, q = np.asarray(phi, float), np.asarray(q, float)
        if not self.pbrt_uv:
            if self.kind == "disk":
                return np.stack([q, phi / (2 * np.pi)], axis=-1)
            return np.stack([phi / (2 * np.pi), q / np.pi if self.kind == "sphere" else q], axis=-1)
        u = phi / self.phi_max
        if self.kind == "sphere":
            theta_min, theta_max = np.arccos(np.clip(self.z_range, -1.0, 1.0))
            return np.stack([u, (q - theta_min) / (theta_max - theta_min)], axis=-1)
        if self.kind == "disk":
            return np.stack([u, (1.0 - q) / (1.0 - self.inner_radius)], axis=-1)
        return np.stack([u, q], axis=-1)

    def partial_tessellation(self) -> TriangleMesh:
        """A partial shape in object space as a grid of quads over (φ, q), with its normals and texture
        coordinates."""
        sectors = max(2, int(np.ceil(64 * self.phi_max / (2 * np.pi))))
        rings = {"sphere": 32, "disk": 8, "cylinder": 1}[self.kind]
        phi = np.linspace(0.0, self.phi_max, sectors + 1)
        if self.kind == "sphere":
            theta_top, theta_bottom = (float(np.arccos(np.clip(z, -1.0, 1.0))) for z in self.z_range[::-1])
            q = np.linspace(theta_top, theta_bottom, rings + 1)
        else:
            q = np.linspace(self.inner_radius if self.kind == "disk" else 0.0, 1.0, rings + 1)
        pp, qq = np.meshgrid(phi, q, indexing="ij")
        c, s = np.cos(pp), np.sin(pp)
        if self.kind == "sphere":
            points = np.stack([np.sin(qq) * c, np.sin(qq) * s, np.cos(qq)], axis=-1)
            normals = points
        elif self.kind == "disk":
            points = np.stack([qq * c, qq * s, np.zeros_like(qq)], axis=-1)
            normals = np.broadcast_to([0.0, 0.0, 1.0], points.shape)
        else:
            points = np.stack([c, s, qq], axis=-1)
            normals = np.stack([c, s, np.zeros_like(qq)], axis=-1)
        return _grid_mesh(points, np.array(normals), self.parameters_uv(pp, qq))


def pbrt_uv_from_mitsuba(kind: str, uvs):
    """pbrt-v4's texture coordinates of the whole disk and sphere from Mitsuba 3's (kernels/shapes.cl)."""
    uvs = np.asarray(uvs, float)
    if kind == "disk":  # (φ/2π, 1 - r) from (r, φ/2π)
        return np.stack([uvs[..., 1], 1.0 - uvs[..., 0]], axis=-1)
    if kind == "sphere":  # v = 1 - θ/π
        return np.stack([uvs[..., 0], 1.0 - uvs[..., 1]], axis=-1)
    return uvs


def object_tessellation(kind: str) -> TriangleMesh:
    """The shape in object space as triangles: the built-in icosphere for the sphere, a polar grid for the disk, a
    ring of quads for the cylinder (vertex normals and Mitsuba's texture coordinates at the vertices)."""
    if kind == "sphere":
        from spectrace.geometry.primitives import sphere

        return sphere()
    sectors, rings = 64, 8 if kind == "disk" else 1
    u, v = np.meshgrid(np.linspace(0.0, 1.0, rings + 1), np.linspace(0.0, 1.0, sectors + 1), indexing="ij")
    if kind == "disk":  # u = r, v = φ/2π
        phi = 2.0 * np.pi * v
        points = np.stack([u * np.cos(phi), u * np.sin(phi), np.zeros_like(u)], axis=-1)
        normals = np.broadcast_to([0.0, 0.0, 1.0], points.shape)
        uvs = np.stack([u, v], axis=-1)
    else:  # u = φ/2π, v = z
        phi = 2.0 * np.pi * v
        points = np.stack([np.cos(phi), np.sin(phi), u], axis=-1)
        normals = np.stack([np.cos(phi), np.sin(phi), np.zeros_like(u)], axis=-1)
        uvs = np.stack([v, u], axis=-1)
    return _grid_mesh(points, normals, uvs)


def _grid_mesh(points, normals, uvs) -> TriangleMesh:
    """Triangles over a grid of points (two per cell), wound to face along the normals; cells of no area dropped."""
    index = np.arange(points.shape[0] * points.shape[1]).reshape(points.shape[:2])
    a, b, c, d = index[:-1, :-1], index[1:, :-1], index[1:, 1:], index[:-1, 1:]
    faces = np.concatenate([np.stack([a, b, c], -1).reshape(-1, 3), np.stack([a, c, d], -1).reshape(-1, 3)])
    vertices, normals, uvs = points.reshape(-1, 3), np.array(normals).reshape(-1, 3), uvs.reshape(-1, 2)
    v0, v1, v2 = (vertices[faces[:, k]] for k in range(3))
    face_normals = np.cross(v1 - v0, v2 - v0)
    keep = np.linalg.norm(face_normals, axis=1) > 1e-12
    faces, face_normals = faces[keep], face_normals[keep]
    inward = np.einsum("ij,ij->i", face_normals, normals[faces[:, 0]] + normals[faces[:, 1]] + normals[faces[:, 2]])
    faces[inward < 0] = faces[inward < 0][:, ::-1]
    return TriangleMesh(vertices=vertices, faces=faces, uvs=uvs, normals=normals)
