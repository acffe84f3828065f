"""`mitchell`: Mitchell & Netravali 1988, f(x) = k(2|x|/radius) with their cubic k on [0, 2] of parameters B, C
(kernels/pixel_filter.cl, PIXEL_FILTER_MITCHELL), drawn from the table of |f| and weighted by f/p, negative on its
lobes."""

from collections.abc import Callable

import numpy as np

from spectrace.core.parameters import Parameter, Range
from spectrace.pixel_filters.base import RADIUS

NAME = "mitchell"
PARAMETERS = (
    Parameter("radius", "float", "pixels", None, RADIUS, default_doc="2", doc="the cubic's support"),
    Parameter("b", "float", "", 1.0 / 3.0, Range(0.0, 1.0), default_doc="1/3", doc="Mitchell–Netravali B"),
    Parameter("c", "float", "", 1.0 / 3.0, Range(0.0, 1.0), default_doc="1/3", doc="Mitchell–Netravali C"),
)
TABULATED = True
MITSUBA_PLUGINS = ("mitchell",)
PBRT_FILTERS = ("mitchell",)


def default_radius(pixel_filter) -> float:
    return 2.0


def mitchell_1d(x: np.ndarray, b: float, c: float) -> np.ndarray:
    """Mitchell & Netravali's cubic k(x) at x = |offset| in filter units, zero from 2 on."""
    x = np.abs(np.asarray(x, np.float64))
    inner = ((12 - 9 * b - 6 * c) * x**3 + (-18 + 12 * b + 6 * c) * x**2 + (6 - 2 * b)) / 6.0
    outer = ((-b - 6 * c) * x**3 + (6 * b + 30 * c) * x**2 + (-12 * b - 48 * c) * x + (8 * b + 24 * c)) / 6.0
    return np.where(x < 1.0, inner, np.where(x < 2.0, outer, 0.0))


def evaluate(pixel_filter, x: np.ndarray) -> np.ndarray:
    return mitchell_1d(2.0 * x / pixel_filter.support, pixel_filter.b, pixel_filter.c)


def integral(pixel_filter) -> float:
    return pixel_filter.support / 2.0  # the cubic integrates to 1 over [−2, 2] for every B, C


def device_shape(pixel_filter) -> tuple[float, float]:
    """B and C."""
    return pixel_filter.b, pixel_filter.c


def from_mitsuba(importer, rfilter, properties) -> dict:
    table: dict[str, object] = {"type": "mitchell", "radius": 2.0}  # Mitsuba's, fixed
    for key in ("B", "C"):
        if key in properties:
            value = importer.number(properties[key])
            if not 0.0 <= value <= 1.0:
                raise importer.fail(rfilter, f"{key} must lie in [0, 1], got {value:g}", "type")
            table[key.lower()] = value
    return table


def to_mitsuba(pixel_filter) -> dict:
    return {"type": "mitchell", "B": float(pixel_filter.b), "C": float(pixel_filter.c)}


def from_pbrt(context, entity, radius: Callable[[float], float]) -> dict:
    """pbrt-v4's MitchellFilter: radius 2 and B = C = 1/3 by default."""
    window = radius(2.0)
    b = context.one(entity, "B", 1.0 / 3.0) if entity is not None else 1.0 / 3.0
    c = context.one(entity, "C", 1.0 / 3.0) if entity is not None else 1.0 / 3.0
    return {"type": "mitchell", "radius": window, "b": b, "c": c}
