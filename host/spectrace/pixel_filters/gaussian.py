"""`gaussian`: Mitsuba 3's windowed Gaussian, f(x) = max(0, exp(−x²/2σ²) − exp(−r²/2σ²)) (kernels/pixel_filter.cl,
PIXEL_FILTER_GAUSSIAN; pbrt-v4's GaussianFilter has the same form), drawn from the table of |f|. Mitsuba 3's
default filter is this one with σ = 0.5 px, r = 4σ."""

from collections.abc import Callable
from math import erf, exp, pi, sqrt

import numpy as np

from spectrace.core.parameters import Parameter, Range
from spectrace.errors import SpectraceError
from spectrace.pixel_filters.base import RADIUS, WIDTH_LIMIT

NAME = "gaussian"
PARAMETERS = (
    Parameter("stddev", "float", "pixels", 0.5, Range(WIDTH_LIMIT, 4.0), doc="σ of exp(−x²/2σ²)"),
    Parameter(
        "radius",
        "float",
        "pixels",
        None,
        RADIUS,
        default_doc="4 stddev",
        doc="cut-off, at least stddev/16; f = exp(−x²/2σ²) − exp(−radius²/2σ²) inside it (Mitsuba 3's and "
        "pbrt-v4's form)",
    ),
)
TABULATED = True
MITSUBA_PLUGINS = ("gaussian",)
PBRT_FILTERS = ("gaussian",)
# A radius below σ/16 leaves f a peak of 1 - exp(-1/512) ≈ 2^-9 above its cut-off: less than that and its 32-bit
# evaluation, exp(−x²/2σ²) − exp(−r²/2σ²), is all rounding (radius 1e-4 px under σ = 4 px weighted every sample 0,
# a black image).
RADIUS_PER_STDDEV = 1.0 / 16.0


def check(pixel_filter) -> None:
    if not pixel_filter.support >= RADIUS_PER_STDDEV * pixel_filter.stddev:
        raise SpectraceError(
            f"a Gaussian's radius must be at least stddev/16 ({pixel_filter.stddev / 16:g} px), got "
            f"{pixel_filter.support:g}: a narrower window leaves nothing of the curve above its cut-off in 32-bit "
            "floats",
            where="filter.radius",
        )


def default_radius(pixel_filter) -> float:
    return 4.0 * pixel_filter.stddev


def evaluate(pixel_filter, x: np.ndarray) -> np.ndarray:
    r = pixel_filter.support
    alpha = -1.0 / (2.0 * pixel_filter.stddev**2)
    return np.where(x <= r, np.maximum(0.0, np.exp(alpha * x * x) - exp(alpha * r * r)), 0.0)


def integral(pixel_filter) -> float:
    r, s = pixel_filter.support, pixel_filter.stddev
    return s * sqrt(2.0 * pi) * erf(r / (s * sqrt(2.0))) - 2.0 * r * exp(-(r * r) / (2.0 * s * s))


def device_shape(pixel_filter) -> tuple[float, float]:
    """-1/(2σ²) and the cut-off exp(-r²/(2σ²))."""
    r = pixel_filter.support
    alpha = -1.0 / (2.0 * pixel_filter.stddev**2)
    return alpha, exp(alpha * r * r)


def from_mitsuba(importer, rfilter, properties) -> dict:
    stddev = importer.number(properties["stddev"]) if "stddev" in properties else 0.5
    try:  # the filter's own range; Mitsuba's radius is fixed at 4σ, this filter's default
        PARAMETERS[0].check(stddev, where="filter.stddev")
    except SpectraceError as exc:
        raise importer.fail(rfilter, exc.message, "type") from None
    return {"type": "gaussian", "stddev": stddev}


def to_mitsuba(pixel_filter) -> dict:
    return {"type": "gaussian", "stddev": float(pixel_filter.stddev)}


def from_pbrt(context, entity, radius: Callable[[float], float]) -> dict:
    """pbrt-v4's GaussianFilter, σ = 0.5 and radius 1.5 by default (also pbrt's default filter: `entity` None)."""
    window = radius(1.5)
    sigma = context.one(entity, "sigma", 0.5) if entity is not None else 0.5
    return {"type": "gaussian", "stddev": sigma, "radius": window}
