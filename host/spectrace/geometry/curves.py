"""Curves (hair, fur, grass, wires): tubes of varying radius along polylines or uniform cubic B-splines, each a
run of linear swept-sphere segments (kernels/curve.cl) that the kernels intersect exactly as analytic shapes, one
BVH primitive per segment (kernels/shape_curve.cl).

Control points are (x, y, z, radius) in scene units. A linear curve is the sphere swept from point to point, its
radius varying linearly: cylinders with rounded joints and ends (Mitsuba 3's `linearcurve`). A B-spline curve of n
points has n − 3 spans, span i the uniform cubic B-spline of points i..i+3 for both the centre and the radius
(Mitsuba 3's `bsplinecurve`, pbrt-v4's `curve` with basis "bspline"), open at its ends as Mitsuba's (Embree's) are
(no end sphere: the tube ends where its cone does); it is rendered as linear segments, each span
cut into enough pieces that the surface of the segments lies within BSPLINE_TOLERANCE of the radius of the true
swept surface (bspline_polyline). A transform moves the points and leaves the radii as they are, as Mitsuba 3 does
(pbrt-v4 scales its widths with the transform; its importer does so before handing them on).

A curve's `curve_type` says what each segment is: "tube" the swept sphere above; "flat" and "ribbon" pbrt-v4's
strips of the same width with no thickness (kernels/curve_ribbon.cl), a flat strip turned to face each ray, a ribbon
oriented by a normal at each point, interpolated by slerp along the curve as pbrt-v4 does (a segment whose end normals
differ by more than RIBBON_MAX_TURN is cut into pieces so that each is its bilinear patch within a fraction of a
percent of its width: ribbon_pieces).

Texture coordinates at a hit are pbrt-v4's by default: u along each curve from 0 to 1, v = (1 + h) / 2 across
it, h the ray's signed offset from the fibre's axis over the radius, which the hair BSDF reads (kernels/bsdf_hair.cl).
With Mitsuba 3's (pbrt_uv false) u runs around the fibre in turns and v along all the curves together,
(segment index + position within the segment) / segment count, a B-spline's segment being its span, and the hair
BSDF takes h from the geometry, as Mitsuba's does. Either way dp/du runs along the fibre.
"""

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from spectrace.core.contract import ANALYTIC_SHAPE_DTYPE, CURVE_TYPES, SHAPE_CURVE
from spectrace.core.equality import fields_equal, identity_hash
from spectrace.errors import SpectraceError
from spectrace.geometry.mesh import TriangleMesh

# How far the surface of a B-spline's linear segments may lie from the true swept surface, as a fraction of the
# local radius: the bound |Δc| + |Δr| on the distance between the two surfaces holds at every parameter.
BSPLINE_TOLERANCE = 0.01
# At most this many linear pieces per B-spline span, whatever the tolerance asks (a span bent within a radius or two
# of its own length is not hair; it is then drawn coarser than the tolerance).
MAX_PIECES_PER_SPAN = 64

# The most a ribbon's normal turns along one segment: a bilinear patch's width at the middle of a segment whose
# normal turns by θ is cos(θ/2) of the slerped strip's, 0.4 % short at 10°.
RIBBON_MAX_TURN = np.radians(10.0)

# The uniform cubic B-spline basis: span points P0..P3, c(t) = [1 t t² t³] M [P0 P1 P2 P3]ᵀ, t in [0, 1].
_BSPLINE = np.array([[1.0, 4.0, 1.0, 0.0], [-3.0, 0.0, 3.0, 0.0], [3.0, -6.0, 3.0, 0.0], [-1.0, 3.0, -3.0, 1.0]]) / 6


def bspline_evaluate(points: np.ndarray, t: np.ndarray) -> np.ndarray:
    """The uniform cubic B-spline of one span's four control points (4, k) at parameters t in [0, 1]: (len(t), k)."""
    t = np.asarray(t, float)
    powers = np.stack([np.ones_like(t), t, t * t, t * t * t], axis=-1)
    return powers @ _BSPLINE @ np.asarray(points, float)


def bspline_polyline(points: np.ndarray, tolerance: float = BSPLINE_TOLERANCE) -> np.ndarray:
    """The polyline (m, 4) of (x, y, z, radius) that stands for a B-spline curve's control points (n >= 4, 4): its
    spans (points i..i+3) cut by polynomial_polyline."""
    return bspline_pieces(points, tolerance)[0]


def bspline_pieces(points: np.ndarray, tolerance: float = BSPLINE_TOLERANCE) -> tuple[np.ndarray, np.ndarray]:
    """bspline_polyline with each point's curve parameter (m,): span index + the span's own parameter t."""
    points = np.asarray(points, float)
    return polynomial_pieces([_BSPLINE @ points[i : i + 4] for i in range(len(points) - 3)], tolerance)


def polynomial_polyline(spans: list[np.ndarray], tolerance: float = BSPLINE_TOLERANCE) -> np.ndarray:
    """The polyline of polynomial_pieces."""
    return polynomial_pieces(spans, tolerance)[0]


def polynomial_pieces(spans: list[np.ndarray], tolerance: float = BSPLINE_TOLERANCE) -> tuple[np.ndarray, np.ndarray]:
    """The polyline (m, 4) of (x, y, z, radius) that stands for consecutive polynomial spans, each given by its
    coefficients (4, 4) of 1, t, t², t³ for t in [0, 1]: each span cut uniformly in t into k pieces, k the least
    for which linear interpolation errs by at most tolerance × the span's smallest radius: on [t0, t0 + h] the
    interpolant of a C² function f errs by at most h² max|f''| / 8, and f'' of a cubic is linear in t, so its
    largest size over the span is at an end; the bound is applied to |c''| + |r''| together. Returns the points
    and each point's parameter, span index + t."""
    pieces, parameters = [], []
    for i, coefficients in enumerate(spans):
        second = np.array([[0.0, 0.0, 2.0, 0.0], [0.0, 0.0, 2.0, 6.0]]) @ coefficients  # f''(0), f''(1)
        curvature = float((np.linalg.norm(second[:, :3], axis=1) + np.abs(second[:, 3])).max())
        radius = max(float(_power_evaluate(coefficients, np.linspace(0.0, 1.0, 9))[:, 3].min()), 1e-12)
        k = int(np.ceil(np.sqrt(curvature / (8.0 * tolerance * radius)))) if curvature > 0 else 1
        k = min(max(k, 1), MAX_PIECES_PER_SPAN)
        t = np.linspace(0.0, 1.0, k + 1)
        pieces.append(_power_evaluate(coefficients, t if i == 0 else t[1:]))
        parameters.append(i + (t if i == 0 else t[1:]))
    return np.concatenate(pieces), np.concatenate(parameters)


def _power_evaluate(coefficients: np.ndarray, t: np.ndarray) -> np.ndarray:
    t = np.asarray(t, float)
    return np.stack([np.ones_like(t), t, t * t, t * t * t], axis=-1) @ coefficients


def read_curve_file(path: Path, where: str, minimum: int) -> list[np.ndarray]:
    """The curves of a Mitsuba 3 curve file: one control point per line, `x y z radius`; a blank line ends a curve.
    Each curve needs `minimum` points (2 linear, 4 B-spline). Raises SpectraceError naming the line."""
    try:
        text = Path(path).read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as error:
        raise SpectraceError(f"cannot read curve file {path}: {error}", where=where) from None
    curves: list[np.ndarray] = []
    current: list[list[float]] = []
    first_line = 0

    def finish(line_number: int) -> None:
        if current and len(current) < minimum:
            raise SpectraceError(
                f"{path}, line {first_line}: a curve needs at least {minimum} control points, this one has "
                f"{len(current)}",
                where=where,
            )
        if current:
            curves.append(np.array(current, float))
        current.clear()

    for number, line in enumerate(text.splitlines(), start=1):
        fields = line.split()
        if not fields:
            finish(number)
            continue
        if not current:
            first_line = number
        try:
            values = [float(f) for f in fields]
        except ValueError:
            values = []
        if len(values) != 4 or not np.all(np.isfinite(values)):
            raise SpectraceError(f"{path}, line {number}: expected 4 finite numbers `x y z radius`", where=where)
        if not values[3] > 0.0:
            raise SpectraceError(f"{path}, line {number}: a control point's radius must be > 0", where=where)
        current.append(values)
    finish(len(text.splitlines()) + 1)
    if not curves:
        raise SpectraceError(f"{path}: no control points", where=where)
    return curves


@dataclass(frozen=True, eq=False)
class CurveSurface:
    """Linear swept-sphere segments in world space, as the kernels intersect them (AnalyticShape rows of type
    SHAPE_CURVE): segment k from (a[k], ra[k]) to (b[k], rb[k]), its texture u running from u0[k] to u1[k]."""

    __eq__ = fields_equal  # by value (arrays too), hashed by identity
    __hash__ = identity_hash

    a: np.ndarray  # (n, 3)
    ra: np.ndarray  # (n,)
    b: np.ndarray
    rb: np.ndarray
    u0: np.ndarray
    u1: np.ndarray
    # Whether the end sphere at a (at b) is part of the surface: a B-spline's ends have none.
    cap_a: np.ndarray | None = None  # (n,) bool; None: all
    cap_b: np.ndarray | None = None
    # (n, 4, 4): the two points (x, y, z, radius) before a and the two after b along the curve, in order, radius 0
    # where there is none; None: none anywhere.
    neighbours: np.ndarray | None = None
    kind: str = "curve"
    flip_normals: bool = False
    pbrt_uv: bool = True
    partial: bool = False
    curve_type: str = "tube"  # CURVE_TYPES
    # (n, 2, 3): a ribbon's unit normals at a and at b; None for a tube or a flat strip
    ribbon_normals: np.ndarray | None = None

    @classmethod
    def from_polylines(
        cls,
        polylines: list[np.ndarray],
        open_ends: bool = False,
        along: list[np.ndarray] | None = None,
        curve_type: str = "tube",
        normals: list[np.ndarray] | None = None,
    ) -> "CurveSurface":
        """Segments joining consecutive (x, y, z, radius) points of each polyline; u along each from 0 to 1 by arc
        length of the centre, or, given `along` (each polyline's points' coordinate along the curves), Mitsuba 3's
        texture coordinates with v = along (pbrt_uv false); open_ends: no sphere closes a polyline's first and last
        point (the tube ends where its cone does). Each segment knows the two points before and after it
        (`neighbours`), so that the kernels drop the parts of its surface inside the two segments on either side (at
        a joint, the inner side of the bend), where a ray that entered the tube (a hair's transmission, a look into
        an open end) would meet them. Segments one of whose end spheres holds the other add nothing to the surface
        and are left out. curve_type "flat" or "ribbon": strips (no caps, no neighbours), a ribbon oriented by
        `normals`, one (x, y, z) per point of each polyline."""
        parts, normal_parts = [], []
        strip = curve_type != "tube"
        for index, line in enumerate(polylines):
            line = np.asarray(line, float)
            lengths = np.linalg.norm(np.diff(line[:, :3], axis=0), axis=1)
            keep = lengths > (0.0 if strip else np.abs(line[:-1, 3] - line[1:, 3]) * (1 + 1e-6))
            if normals is not None:
                unit = np.asarray(normals[index], float)
                unit = unit / np.linalg.norm(unit, axis=1, keepdims=True)
                normal_parts.append(np.stack([unit[:-1], unit[1:]], axis=1)[keep])
            total = lengths.sum()
            u = np.concatenate([[0.0], np.cumsum(lengths)]) / total if total > 0 else np.linspace(0, 1, len(line))
            if along is not None:
                u = np.asarray(along[index], float)
            n = len(lengths)
            caps = np.ones((n, 2))
            if open_ends or strip:
                caps[0, 0] = caps[-1, 1] = 0.0
            # The two points before each segment's a and after its b, radius 0 where there is none.
            padded = np.concatenate([np.zeros((2, 4)), line, np.zeros((2, 4))])
            around = [padded[k : k + n] for k in (0, 1)] + [padded[k : k + n] for k in (4, 5)]
            parts.append(np.concatenate([line[:-1], line[1:], u[:-1, None], u[1:, None], caps, *around], axis=1)[keep])
        rows = np.concatenate(parts) if parts else np.zeros((0, 28))
        return cls(
            rows[:, 0:3],
            rows[:, 3],
            rows[:, 4:7],
            rows[:, 7],
            rows[:, 8],
            rows[:, 9],
            rows[:, 10] > 0.5,
            rows[:, 11] > 0.5,
            None if strip else rows[:, 12:28].reshape(-1, 4, 4),
            pbrt_uv=along is None,
            curve_type=curve_type,
            ribbon_normals=np.concatenate(normal_parts) if normal_parts else None,
        )

    @property
    def count(self) -> int:
        return len(self.ra)

    def polylines(self) -> list[np.ndarray]:
        """The segments as runs of joined (x, y, z, radius) points, a run ending where the next segment does not
        start at its b: the curves as linear ones (what a scene file's curve of basis "linear" takes back)."""
        starts = np.ones(self.count, bool)
        starts[1:] = ~(np.all(self.a[1:] == self.b[:-1], axis=1) & (self.ra[1:] == self.rb[:-1]))
        runs = np.split(np.arange(self.count), np.nonzero(starts)[0][1:])
        return [
            np.concatenate([np.c_[self.a[run], self.ra[run]], np.c_[self.b[run[-1:]], self.rb[run[-1:]]]])
            for run in runs
            if len(run)
        ]

    @property
    def open_ends(self) -> bool:
        """Whether the curves stop at their ends without a sphere (a B-spline's, pbrt's)."""
        return self.cap_a is not None and self.count > 0 and not bool(self.cap_a[0])

    def bounds_array(self) -> np.ndarray:
        """(n, 2, 3): each segment's box (both end spheres'), widened by a relative 1e-6 against float32 rounding."""
        lo = np.minimum(self.a - self.ra[:, None], self.b - self.rb[:, None])
        hi = np.maximum(self.a + self.ra[:, None], self.b + self.rb[:, None])
        pad = 1e-6 * (np.abs(lo).max(axis=1) + np.abs(hi).max(axis=1) + (hi - lo).max(axis=1))
        return np.stack([lo - pad[:, None], hi + pad[:, None]], axis=1)

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        boxes = self.bounds_array()
        return boxes[:, 0].min(axis=0), boxes[:, 1].max(axis=0)

    def device_rows(self) -> np.ndarray:
        """The AnalyticShape rows (kernels/shape_curve.cl): sphere = (a, ra), to_world[0] = (b, rb),
        to_world[1] = (u0, u1, 1 if the sphere at a is surface else 0, the same for b); the neighbours in
        to_object[0], [1] (before a) and to_object[2], to_world[2] (after b)."""
        rows = np.zeros(self.count, ANALYTIC_SHAPE_DTYPE)
        rows["type"] = SHAPE_CURVE
        rows["sphere"][:, :3], rows["sphere"][:, 3] = self.a, self.ra
        rows["to_world"][:, 0, :3], rows["to_world"][:, 0, 3] = self.b, self.rb
        rows["to_world"][:, 1, 0], rows["to_world"][:, 1, 1] = self.u0, self.u1
        rows["to_world"][:, 1, 2] = 1.0 if self.cap_a is None else self.cap_a
        rows["to_world"][:, 1, 3] = 1.0 if self.cap_b is None else self.cap_b
        if self.neighbours is not None:
            rows["to_object"] = self.neighbours[:, :3]
            rows["to_world"][:, 2] = self.neighbours[:, 3]
        rows["cut_min"] = CURVE_TYPES.index(self.curve_type)
        if self.ribbon_normals is not None:
            rows["to_object"][:, 0, :3] = self.ribbon_normals[:, 0]
            rows["to_object"][:, 1, :3] = self.ribbon_normals[:, 1]
        rows["abs_det"] = 1.0
        rows["object_area"] = 1.0
        rows["pbrt_uv"] = int(self.pbrt_uv)
        return rows

    def area(self) -> float:
        """The segments' lateral (cone) areas: a measure for statistics, joints counted once."""
        slant = np.sqrt(np.sum((self.b - self.a) ** 2, axis=1) + (self.ra - self.rb) ** 2)
        return float(np.sum(np.pi * (self.ra + self.rb) * slant))

    def tessellation(self) -> TriangleMesh:
        """A coarse stand-in for what reads triangles (bounds, statistics, the Mitsuba export's fallback): each
        segment as a triangular prism about its axis, with the texture coordinates of the hits (v = ½)."""
        n = self.count
        if n == 0:
            return TriangleMesh(np.zeros((3, 3)), np.array([[0, 1, 2]]), uvs=np.zeros((3, 2)))
        axis = self.b - self.a
        axis /= np.linalg.norm(axis, axis=1, keepdims=True)
        helper = np.where(np.abs(axis[:, :1]) < 0.9, [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]])
        e1 = np.cross(axis, helper)
        e1 /= np.linalg.norm(e1, axis=1, keepdims=True)
        e2 = np.cross(axis, e1)
        angles = 2.0 * np.pi * np.arange(3) / 3
        ring = np.cos(angles)[None, :, None] * e1[:, None] + np.sin(angles)[None, :, None] * e2[:, None]  # (n, 3, 3)
        vertices = np.concatenate(
            [self.a[:, None] + self.ra[:, None, None] * ring, self.b[:, None] + self.rb[:, None, None] * ring], axis=1
        )  # (n, 6, 3): the ring at a, then at b
        uvs = np.zeros((n, 6, 2))
        uvs[:, :3, 0], uvs[:, 3:, 0], uvs[:, :, 1] = self.u0[:, None], self.u1[:, None], 0.5
        quads = [(i, (i + 1) % 3, 3 + (i + 1) % 3, 3 + i) for i in range(3)]
        local = np.array([f for a, b, c, d in quads for f in ((a, b, c), (a, c, d))])
        faces = (local[None] + 6 * np.arange(n)[:, None, None]).reshape(-1, 3)
        return TriangleMesh(vertices.reshape(-1, 3), faces, uvs=uvs.reshape(-1, 2))


def ribbon_pieces(points: np.ndarray, normals: np.ndarray, max_turn: float = RIBBON_MAX_TURN):
    """A ribbon's polyline (m, 4) and its normals (m, 3) with every segment whose end normals differ by more than
    max_turn (radians) cut evenly into as many pieces as keep each within it: points and radii linear along the
    segment, normals by slerp, as pbrt-v4 interpolates them."""
    points, normals = np.asarray(points, float), np.asarray(normals, float)
    normals = normals / np.linalg.norm(normals, axis=1, keepdims=True)
    out_points, out_normals = [points[:1]], [normals[:1]]
    for i in range(len(points) - 1):
        n0, n1 = normals[i], normals[i + 1]
        angle = float(np.arctan2(np.linalg.norm(np.cross(n0, n1)), np.dot(n0, n1)))
        k = max(1, int(np.ceil(angle / max_turn - 1e-9)))
        t = np.linspace(0.0, 1.0, k + 1)[1:, None]
        out_points.append((1.0 - t) * points[i] + t * points[i + 1])
        if angle > 0.0:
            slerped = (np.sin((1.0 - t) * angle) * n0 + np.sin(t * angle) * n1) / np.sin(angle)
        else:
            slerped = np.repeat(n0[None], k, axis=0)
        out_normals.append(slerped)
    return np.concatenate(out_points), np.concatenate(out_normals)


def curve_surface(
    curves: list[np.ndarray],
    basis: str,
    matrix: np.ndarray | None = None,
    tolerance: float = BSPLINE_TOLERANCE,
    open_ends: bool | None = None,
    uv_convention: str = "pbrt",
    curve_type: str = "tube",
    normals: list[np.ndarray] | None = None,
) -> CurveSurface:
    """The segments of curves given by control points (each (n, 4): x, y, z, radius) in the basis "linear" or
    "bspline", their points placed by the 4 x 4 `matrix` (radii unchanged); open_ends (default: a B-spline's):
    the tubes stop at their ends without a sphere; uv_convention "pbrt" or "mitsuba": whose texture coordinates
    (Mitsuba 3's v counts the segments of all the curves, a B-spline's spans, in order); curve_type "tube",
    "flat" or "ribbon", a ribbon's `normals` one per control point of each (linear) curve, turned by the matrix's
    inverse transpose."""
    spans_before = 3 if basis == "bspline" else 1
    segment_count = sum(len(points) - spans_before for points in curves)
    placed, along, placed_normals = [], [], []
    segments_before = 0
    for index, points in enumerate(curves):
        points = np.array(points, float)
        if matrix is not None:
            points[:, :3] = points[:, :3] @ matrix[:3, :3].T + matrix[:3, 3]
        line, parameter = (
            bspline_pieces(points, tolerance) if basis == "bspline" else (points, np.arange(len(points), dtype=float))
        )
        if curve_type == "ribbon" and normals is not None:
            turned = np.asarray(normals[index], float)
            if matrix is not None:
                turned = turned @ np.linalg.inv(matrix[:3, :3])
            line, turned = ribbon_pieces(line, turned)
            placed_normals.append(turned)
        placed.append(line)
        along.append((segments_before + parameter) / segment_count)
        segments_before += len(points) - spans_before
    return CurveSurface.from_polylines(
        placed,
        open_ends=basis == "bspline" if open_ends is None else open_ends,
        along=along if uv_convention == "mitsuba" else None,
        curve_type=curve_type,
        normals=placed_normals if curve_type == "ribbon" else None,
    )


CURVE_BASES = ("linear", "bspline")
MINIMUM_POINTS = {"linear": 2, "bspline": 4}


def checked_curves(curves, basis: str, where: str) -> list[np.ndarray]:
    """Control points as given (one curve's (n, 4) rows, or a list of curves) made a list of float arrays, checked:
    the basis known, every point 4 finite numbers with radius > 0, every curve long enough for its basis. Raises
    SpectraceError naming `where`."""
    if basis not in CURVE_BASES:
        raise SpectraceError(f"basis must be one of {', '.join(CURVE_BASES)}, got {basis!r}", where=where)
    try:
        as_array = np.asarray(curves, float)
        listed = [as_array] if as_array.ndim == 2 else [np.asarray(c, float) for c in curves]
    except (TypeError, ValueError):
        try:
            listed = [np.asarray(c, float) for c in curves]
        except (TypeError, ValueError):
            raise SpectraceError("curve points must be rows of 4 numbers: x, y, z, radius", where=where) from None
    if not listed:
        raise SpectraceError("a curve shape needs at least one curve", where=where)
    for i, points in enumerate(listed):
        if points.ndim != 2 or points.shape[1] != 4:
            raise SpectraceError(f"curve {i}: points must be rows of 4 numbers: x, y, z, radius", where=where)
        if len(points) < MINIMUM_POINTS[basis]:
            raise SpectraceError(
                f"curve {i}: a {basis} curve needs at least {MINIMUM_POINTS[basis]} points, got {len(points)}",
                where=where,
            )
        if not np.all(np.isfinite(points)) or not np.all(points[:, 3] > 0.0):
            raise SpectraceError(f"curve {i}: coordinates must be finite and radii > 0", where=where)
    return listed


def checked_curve_type(curve_type: str, curves: list[np.ndarray], normals, basis: str, uv_convention: str, where):
    """A curve shape's type and, for a ribbon, its normals (one (x, y, z) per control point of each curve, rows as
    `curves`; None otherwise) checked: raises SpectraceError naming `where(key)` (key "curve_type", "curve_normals",
    "uv_convention" or "basis")."""
    if curve_type not in CURVE_TYPES:
        raise SpectraceError(
            f"curve_type must be one of {', '.join(CURVE_TYPES)}, got {curve_type!r}", where=where("curve_type")
        )
    if curve_type != "tube" and uv_convention == "mitsuba":
        raise SpectraceError(
            f"a {curve_type} curve has pbrt-v4's texture coordinates only (Mitsuba 3 has no {curve_type} curves)",
            where=where("uv_convention"),
        )
    if curve_type != "ribbon":
        if normals is not None:
            raise SpectraceError(
                f"curve_normals orient a ribbon; this curve is a {curve_type}", where=where("curve_normals")
            )
        return None
    if normals is None:
        raise SpectraceError("a ribbon curve needs curve_normals, one per control point", where=where("curve_normals"))
    if basis != "linear":
        raise SpectraceError('a ribbon curve takes basis "linear" (its normals are per point)', where=where("basis"))
    try:
        as_array = np.asarray(normals, float)
        listed = [as_array] if as_array.ndim == 2 else [np.asarray(n, float) for n in normals]
    except (TypeError, ValueError):
        raise SpectraceError("curve_normals must be rows of 3 numbers", where=where("curve_normals")) from None
    if len(listed) != len(curves):
        raise SpectraceError(
            f"curve_normals has {len(listed)} curves' normals for {len(curves)} curves", where=where("curve_normals")
        )
    for i, (points, unit) in enumerate(zip(curves, listed)):
        if unit.shape != (len(points), 3) or not np.all(np.isfinite(unit)):
            raise SpectraceError(
                f"curve {i}: curve_normals needs {len(points)} rows of 3 finite numbers (one per point)",
                where=where("curve_normals"),
            )
        axis = np.diff(points[:, :3], axis=0)
        axis = axis / np.maximum(np.linalg.norm(axis, axis=1, keepdims=True), 1e-300)
        length = np.linalg.norm(unit, axis=1)
        across = np.concatenate(
            [np.linalg.norm(np.cross(unit[:-1], axis), axis=1), np.linalg.norm(np.cross(unit[1:], axis), axis=1)]
        )
        if not np.all(length > 0.0) or not np.all(across > 1e-6 * np.concatenate([length[:-1], length[1:]])):
            raise SpectraceError(
                f"curve {i}: a ribbon's normals must be non-zero and not along the curve", where=where("curve_normals")
            )
    return listed
