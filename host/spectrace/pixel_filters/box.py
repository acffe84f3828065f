"""`box`: uniform over the pixel (kernels/pixel_filter.cl, PIXEL_FILTER_BOX), f = 1 within the radius; the
default, drawn as the samples were before filters existed."""

from collections.abc import Callable

import numpy as np

NAME = "box"
PARAMETERS = ()
TABULATED = False
MITSUBA_PLUGINS = ("box",)
PBRT_FILTERS = ("box",)


def default_radius(pixel_filter) -> float:
    return 0.5


def evaluate(pixel_filter, x: np.ndarray) -> np.ndarray:
    return (x <= pixel_filter.support).astype(np.float64)


def integral(pixel_filter) -> float:
    return 2.0 * pixel_filter.support


def device_shape(pixel_filter) -> tuple[float, float]:
    return 0.0, 0.0


def from_mitsuba(importer, rfilter, properties) -> dict:
    return {"type": "box"}


def to_mitsuba(pixel_filter) -> dict:
    return {"type": "box"}


def from_pbrt(context, entity, radius: Callable[[float], float]) -> dict:
    """pbrt-v4's BoxFilter of radius 0.5 (its default) is this one; a wider box is not imported."""
    if radius(0.5) != 0.5:
        context.warn(entity.location, "a box filter's radius other than 0.5 is not imported")
    return {"type": "box"}
