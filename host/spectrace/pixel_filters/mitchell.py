"""`mitchell`: Mitchell & Netravali 1988, f(x) = k(2|x|/radius) with their cubic k on [0, 2] of parameters B, C
(kernels/pixel_filter.cl, PIXEL_FILTER_MITCHELL), drawn from the table of |f| and weighted by f/p, negative on its
lobes."""

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
