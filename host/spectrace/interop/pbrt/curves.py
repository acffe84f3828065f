"""pbrt-v4's `curve` shape as spectrace's curve (docs/scene-format.md, "Curves"): `P` the control points of
`degree` 3 (default) or 2 in the `basis` "bezier" (default: spans sharing their end points) or "bspline"; `width`
(default 1) or `width0` and `width1`, its diameter, varying linearly along the whole curve, in object space (so
scaled with the transform). A tube ends where pbrt's does, without a cap (open_ends).

pbrt intersects a curve as a ribbon: `cylinder` (shaded as a tube), `flat` (facing the ray) and `ribbon` (oriented
by `N`); spectrace's curve is a true tube, the same silhouette as all three, so `flat` and `ribbon` are imported as
tubes with a warning. `splitdepth` is pbrt's own recursion depth for its ribbon test, which spectrace's exact
segment test has no use for; it is read and ignored. A cubic B-spline of constant width is written as its control
points (basis "bspline"); any other curve as the polyline that stands for it within 1 % of its radius
(geometry/curves.py polynomial_polyline).
"""

from __future__ import annotations

import numpy as np

from spectrace.geometry.analytic import similarity_problem
from spectrace.geometry.curves import BSPLINE_TOLERANCE, polynomial_polyline
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
    if kind != "cylinder":
        context.warn(entity.location, f'curve type "{kind}" imported as a tube ("cylinder": the same silhouette)')
    entity.find("N", "normal3", "normal")  # a ribbon's orientation: a tube has none
    entity.find("splitdepth", "integer")  # pbrt's own subdivision of its ribbon test: nothing to split here
    if shape.area_light is not None:
        raise error(entity.location, "an area light on a curve: spectrace's curves cannot emit")
    placed = np.c_[control, np.ones(len(control))] @ matrix.T
    linear = matrix[:3, :3]
    if similarity_problem(linear) is not None:
        context.warn(entity.location, "curve under a non-uniform scale: its width scaled by the mean scale")
    scale = float(abs(np.linalg.det(linear)) ** (1.0 / 3.0))
    radius0, radius1 = 0.5 * width0 * scale, 0.5 * width1 * scale
    if basis == "bspline" and degree == 3 and width0 == width1:
        rows = np.c_[placed[:, :3], np.full(len(control), radius0)]
        return {"type": "curve", "points": rows.tolist(), "basis": "bspline"}
    spans = []
    count = len(starts)
    for i, start in enumerate(starts):
        coefficients = np.zeros((4, 4))
        coefficients[:, :3] = _SPANS[basis, degree] @ placed[start : start + order, :3]
        # The width runs linearly over the whole curve: over span i, from u = i / count to (i + 1) / count.
        r_start = radius0 + (radius1 - radius0) * i / count
        r_end = radius0 + (radius1 - radius0) * (i + 1) / count
        coefficients[:2, 3] = r_start, r_end - r_start
        spans.append(coefficients)
    polyline = polynomial_polyline(spans, BSPLINE_TOLERANCE)
    return {"type": "curve", "points": polyline.tolist(), "basis": "linear", "open_ends": True}
