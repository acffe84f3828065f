"""`box`: uniform over the pixel (kernels/pixel_filter.cl, PIXEL_FILTER_BOX), f = 1 within the radius; the
default, drawn as the samples were before filters existed."""

import numpy as np

NAME = "box"
PARAMETERS = ()
TABULATED = False


def default_radius(pixel_filter) -> float:
    return 0.5


def evaluate(pixel_filter, x: np.ndarray) -> np.ndarray:
    return (x <= pixel_filter.support).astype(np.float64)


def integral(pixel_filter) -> float:
    return 2.0 * pixel_filter.support


def device_shape(pixel_filter) -> tuple[float, float]:
    return 0.0, 0.0
