"""A Mitsuba <transform> (translate, rotate, scale, matrix, lookat steps, applied in file order) as spectrace's
transform steps and as the 4 x 4 matrix they make (Mitsuba 3's src/core/parser.cpp and its Transform4f)."""

from __future__ import annotations

import math

import numpy as np

from spectrace.errors import SpectraceError
from spectrace.geometry.transforms import transform_matrix
from spectrace.interop.mitsuba.context import ImportContext
from spectrace.interop.mitsuba.plugins import KNOWN_TAGS
from spectrace.interop.mitsuba.tree import Element


def transform_steps(ctx: ImportContext, element: Element) -> list[dict]:
    """A <transform> as spectrace transform steps, first step first (Mitsuba applies them in file order)."""
    steps: list[dict] = []
    for step in element.children:
        if step.tag == "translate":
            steps.append({"translate": ctx.vector(step)})
        elif step.tag == "scale":
            if step.get("value") is not None:
                values = ctx.numbers(step, "value")
                if len(values) not in (1, 3):
                    raise ctx.fail(step, f"scale needs 1 or 3 numbers, got {len(values)}", "value")
                factors = values * 3 if len(values) == 1 else values
                steps.append({"scale": values[0] if len(values) == 1 else values})
            else:
                factors = ctx.vector(step, default=1.0)
                steps.append({"scale": factors})
            if 0.0 in factors:
                raise ctx.fail(step, "scale factors must be non-zero (a zero scale flattens the shape)")
        elif step.tag == "rotate":
            angle = ctx.parse_number(ctx.attribute(step, "angle", "0"), step, "angle")
            axis = ctx.vector(step)
            if not any(axis):
                raise ctx.fail(step, "the rotation axis (x, y, z) must not be zero")
            if abs(float(np.linalg.norm(axis)) - 1.0) <= 1e-7:
                steps.append({"rotate": {"axis": axis, "angle": angle}})
            else:
                # Mitsuba does not normalise the axis: its Rodrigues matrix with a longer axis also stretches.
                steps.append({"matrix": _unnormalised_rotation(axis, angle).tolist()})
                ctx.notes.append(
                    f"{ctx.at(step)}: rotate axis {tuple(axis)} is not a unit vector; Mitsuba does not "
                    "normalise it (the step also scales), and neither does the import"
                )
        elif step.tag == "matrix":
            values = ctx.numbers(step, "value")
            if len(values) == 9:
                values = values[0:3] + [0.0] + values[3:6] + [0.0] + values[6:9] + [0.0, 0.0, 0.0, 0.0, 1.0]
            if len(values) != 16:
                raise ctx.fail(step, f"a matrix needs 16 (or 9) numbers, got {len(values)}", "value")
            steps.append({"matrix": [values[i : i + 4] for i in range(0, 16, 4)]})
        elif step.tag == "lookat":
            steps.append({"matrix": look_at(ctx, step).tolist()})
        elif step.tag in KNOWN_TAGS:
            ctx.unsupported_plugin(step, " transform step")
        # an unknown tag (a misspelt step) is reported by report_unknown_tags
    return steps


def look_at(ctx: ImportContext, element: Element) -> np.ndarray:
    """Mitsuba's look_at: columns left = up × dir, up' = dir × left, dir, and the origin."""
    vectors = {}
    for key, default in (("origin", None), ("target", None), ("up", "0, 1, 0")):
        vectors[key] = np.array(ctx.numbers(element, key, default))
        if len(vectors[key]) != 3:
            raise ctx.fail(element, f"{key} needs 3 numbers, got {len(vectors[key])}", key)
    origin, target, up = vectors["origin"], vectors["target"], vectors["up"]
    direction = target - origin
    left = np.cross(up, direction)
    if not (np.linalg.norm(direction) > 0 and np.linalg.norm(left) > 0):
        raise ctx.fail(element, "lookat needs target != origin and up not parallel to the view")
    direction /= np.linalg.norm(direction)
    left /= np.linalg.norm(left)
    matrix = np.eye(4)
    matrix[:3, 0], matrix[:3, 1], matrix[:3, 2], matrix[:3, 3] = left, np.cross(direction, left), direction, origin
    return matrix


def to_world(ctx: ImportContext, properties: dict[str, Element], key: str = "to_world") -> np.ndarray:
    element = properties.get(key)
    if element is None:
        return np.eye(4)
    element = ctx.resolve(element)
    steps = transform_steps(ctx, element)
    try:
        with np.errstate(over="ignore", invalid="ignore"):  # an overflow is reported just below
            matrix = transform_matrix(steps, where="")
    except SpectraceError as error:
        raise ctx.fail(element, error.message) from None
    if not np.isfinite(matrix).all():
        raise ctx.fail(element, "the transform overflows (its product is not finite)")
    return matrix


def _unnormalised_rotation(axis: list[float], degrees: float) -> np.ndarray:
    """Mitsuba's rotate step as it builds it, axis a as given: cos θ I + sin θ [a]× + (1 − cos θ) a aᵀ (a rotation only
    for a unit axis)."""
    a = np.asarray(axis, np.float64)
    cos, sin = math.cos(math.radians(degrees)), math.sin(math.radians(degrees))
    cross = np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])
    matrix = np.eye(4)
    matrix[:3, :3] = cos * np.eye(3) + sin * cross + (1.0 - cos) * np.outer(a, a)
    return matrix
