"""`tent`: f(x) = max(0, 1 − |x|/radius) (kernels/pixel_filter.cl, PIXEL_FILTER_TENT), drawn in closed form."""

from collections.abc import Callable

import numpy as np

from spectrace.core.parameters import Parameter
from spectrace.pixel_filters.base import RADIUS

NAME = "tent"
PARAMETERS = (
    Parameter("radius", "float", "pixels", None, RADIUS, default_doc="1", doc="where f = 1 − |x|/radius reaches 0"),
)
TABULATED = False
MITSUBA_PLUGINS = ("tent",)
PBRT_FILTERS = ("triangle",)


def default_radius(pixel_filter) -> float:
    return 1.0


def evaluate(pixel_filter, x: np.ndarray) -> np.ndarray:
    return np.maximum(0.0, 1.0 - x / pixel_filter.support)


def integral(pixel_filter) -> float:
    return pixel_filter.support


def device_shape(pixel_filter) -> tuple[float, float]:
    return 0.0, 0.0


def from_mitsuba(importer, rfilter, properties) -> dict:
    return {"type": "tent"}  # radius 1 in Mitsuba, fixed


def to_mitsuba(pixel_filter) -> dict:
    return {"type": "tent"}


def from_pbrt(context, entity, radius: Callable[[float], float]) -> dict:
    """pbrt-v4's TriangleFilter, of default radius 2."""
    return {"type": "tent", "radius": radius(2.0)}
