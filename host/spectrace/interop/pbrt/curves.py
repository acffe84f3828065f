"""pbrt-v4's `curve` shape as spectrace's curve (docs/scene-format.md, "Curves"): `P` the control points of
`degree` 3 (default) or 2 in the `basis` "bezier" (default: spans sharing their end points) or "bspline"; `width`
(default 1) or `width0` and `width1`, its diameter, varying linearly along the whole curve, in object space (so
scaled with the transform). A tube ends where pbrt's does, without a cap (open_ends).

pbrt's `type`s map onto spectrace's curve types: `cylinder` (pbrt shades a strip as a tube) onto the true tube,
`flat` (the default: a strip facing each ray) and `ribbon` (a strip oriented by `N`, one normal per Bézier or
B-spline segment's end, interpolated by slerp along each) onto the strips of the same names (kernels/curve_ribbon.cl);
a ribbon's normals are turned by the transform's inverse transpose and given at every point of its polyline.
`splitdepth` is pbrt's own recursion depth for its strip test, which spectrace's exact segment tests have no use
for; it is read and ignored. A cubic B-spline of constant width that is not a ribbon is written as its control
points (basis "bspline"); any other curve as the polyline that stands for it within 1 % of its radius
(geometry/curves.py polynomial_pieces).
"""

from __future__ import annotations

import numpy as np

from spectrace.geometry.analytic import similarity_problem
from spectrace.geometry.curves import BSPLINE_TOLERANCE, polynomial_pieces
from spectrace.interop.pbrt.context import Context
from spectrace.interop.pbrt.graphics_state import Shape
from spectrace.interop.pbrt.parser import error, shown

# Power-form matrices of each (basis, degree): a span's coefficients of 1, t, t², t³ are M @ its control points.
_SPANS = {
    ("bezier", 3): np.array([[1, 0, 0, 0], [-3, 3, 0, 0], [3, -6, 3, 0], [-1, 3, -3, 1]], float),
    ("bezier", 2): np.array([[1, 0, 0], [-2, 2, 0], [1, -2, 1], [0, 0, 0]], float),
    ("bspline", 3): np.array([[1, 4, 1, 0], [-3, 0, 3, 0], [3, -6, 3, 0], [-1, 3, -3, 1]], float) / 6.0,
    ("bspline", 2): np.array([[1, 1, 0], [-2, 2, 0], [1, -2, 1], [0, 0, 0]], float) / 2.0,
}


def curve_geometry(context: Context, shape: Shape, matrix: np.ndarray) -> dict:
    """The spectrace curve table (type, points, basis, open_ends) of a pbrt `curve`, placed by `matrix` (spectrace's
    world from the curve's object space)."""
    entity = shape.entity
    basis = str(context.string(entity, "basis", "bezier"))
    degree = context.integer(entity, "degree", 3)
    if (basis, degree) not in _SPANS:
        raise error(
            entity.location,
            f'curve: basis "{shown(str(basis))}" of degree {degree} (pbrt-v4 has "bezier" '
            'and "bspline" of degree 2 and 3)',
        )
    points = context.floats(entity, "P", None, "point3", "point")
    if points is None:
        raise error(entity.location, 'a curve needs "point3 P"')
    control = np.array(points, float).reshape(-1, 3)
    order = degree + 1
    if basis == "bezier":
        if len(control) < order or (len(control) - 1) % degree:
            raise error(
                entity.location,
                f"a Bézier curve of degree {degree} needs {degree}k + 1 points (k >= 1), got {len(control)}",
            )
        starts = range(0, len(control) - 1, degree)
    else:
        if len(control) < order:
            raise error(entity.location, f"a B-spline curve of degree {degree} needs at least {order} points")
        starts = range(len(control) - degree)
    width = context.one(entity, "width", 1.0)
    width0, width1 = context.one(entity, "width0", width), context.one(entity, "width1", width)
    if not (width0 > 0 and width1 > 0):
        raise error(entity.location, f"a curve's widths must be > 0, got {width0:g} and {width1:g}")
    kind = context.string(entity, "type", "flat")
    if kind not in ("flat", "cylinder", "ribbon"):
        raise error(entity.location, f'curve: type "{shown(str(kind))}" (pbrt-v4 has "flat", "cylinder", "ribbon")')
    curve_type = "tube" if kind == "cylinder" else kind
    given_normals = context.floats(entity, "N", None, "normal3", "normal")
    segment_count = len(starts)
    normals = np.zeros((0, 3))
    if kind == "ribbon":
        if given_normals is None:
            raise error(entity.location, 'a ribbon curve needs "normal N", one per segment end')
        normals = np.array(given_normals, float).reshape(-1, 3)
        if len(normals) != segment_count + 1:
            raise error(
                entity.location,
                f'a ribbon curve of {segment_count} segments needs {segment_count + 1} normals "N", got {len(normals)}',
            )
        if not np.all(np.isfinite(normals)) or not np.all(np.linalg.norm(normals, axis=1) > 0.0):
            raise error(entity.location, 'a ribbon curve\'s normals "N" must be finite and non-zero')
    elif given_normals is not None:
        context.warn(entity.location, f'"N" orients a "ribbon" curve; this one is "{kind}": ignored')
    entity.find("splitdepth", "integer")  # pbrt's own subdivision of its ribbon test: nothing to split here
    if shape.area_light is not None:
        raise error(entity.location, "an area light on a curve: spectrace's curves cannot emit")
    placed = np.c_[control, np.ones(len(control))] @ matrix.T
    linear = matrix[:3, :3]
    if similarity_problem(linear) is not None:
        context.warn(entity.location, "curve under a non-uniform scale: its width scaled by the mean scale")
    scale = float(abs(np.linalg.det(linear)) ** (1.0 / 3.0))
    radius0, radius1 = 0.5 * width0 * scale, 0.5 * width1 * scale
    typed = {} if curve_type == "tube" else {"curve_type": curve_type}
    if basis == "bspline" and degree == 3 and width0 == width1 and kind != "ribbon":
        rows = np.c_[placed[:, :3], np.full(len(control), radius0)]
        return {"type": "curve", "points": rows.tolist(), "basis": "bspline"} | typed
    spans = []
    count = segment_count
    for i, start in enumerate(starts):
        coefficients = np.zeros((4, 4))
        coefficients[:, :3] = _SPANS[basis, degree] @ placed[start : start + order, :3]
        # The width runs linearly over the whole curve: over span i, from u = i / count to (i + 1) / count.
        r_start = radius0 + (radius1 - radius0) * i / count
        r_end = radius0 + (radius1 - radius0) * (i + 1) / count
        coefficients[:2, 3] = r_start, r_end - r_start
        spans.append(coefficients)
    polyline, parameters = polynomial_pieces(spans, BSPLINE_TOLERANCE)
    table = {"type": "curve", "points": polyline.tolist(), "basis": "linear", "open_ends": True} | typed
    if kind == "ribbon":
        table["curve_normals"] = _ribbon_normals(normals, parameters, linear).tolist()
    return table


def _ribbon_normals(normals: np.ndarray, parameters: np.ndarray, linear: np.ndarray) -> np.ndarray:
    """The normal at each polyline point of curve parameter (segment index + t): pbrt's slerp of the segment's two
    end normals, turned into spectrace's world by the inverse transpose of `linear`."""
    unit = normals / np.linalg.norm(normals, axis=1, keepdims=True)
    segment = np.minimum(np.floor(parameters).astype(int), len(unit) - 2)
    t = (parameters - segment)[:, None]
    n0, n1 = unit[segment], unit[segment + 1]
    angle = np.arctan2(np.linalg.norm(np.cross(n0, n1), axis=1), np.sum(n0 * n1, axis=1))[:, None]
    with np.errstate(invalid="ignore", divide="ignore"):
        slerped = (np.sin((1.0 - t) * angle) * n0 + np.sin(t * angle) * n1) / np.sin(angle)
    slerped = np.where(angle > 1e-6, slerped, (1.0 - t) * n0 + t * n1)
    turned = slerped @ np.linalg.inv(linear)
    return turned / np.linalg.norm(turned, axis=1, keepdims=True)
