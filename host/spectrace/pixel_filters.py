"""The pixel's reconstruction filter (kernels/pixel_filter.cl): box, tent, Gaussian and Mitchell–Netravali, each
separable, f(x, y) = f(x) f(y), applied by filter importance sampling so the film stays a per-pixel sum.

`FILTERS` is the one table of them: each type's parameters (name, unit, default, range, meaning), from which the
scene schema's `film.filter`, the Python API (`PixelFilter`) and docs/scene-format.md's table come. Offsets and
radii are in pixels. Box is today's and our scenes' default; Mitsuba 3's default (and hence the Mitsuba importer's
when a file names none) is its Gaussian of σ = 0.5 px, cut off at 4σ.
"""

from dataclasses import dataclass
from math import erf, exp, pi, sqrt
from typing import Literal

import numpy as np

from spectrace.core.contract import PIXEL_FILTER_BINS, PIXEL_FILTERS
from spectrace.core.parameters import Parameter, Range
from spectrace.errors import SpectraceError
from spectrace.number_text import number_problem

FilterType = Literal["box", "tent", "gaussian", "mitchell"]
RADIUS_LIMIT = 16.0  # pixels: a wider filter blurs more than any use asks and wastes samples far from the pixel
# pixels: about the spacing of 32-bit film positions at the largest film side (2^14 px, a 24-bit significand:
# 2^-10 ≈ 0.001 px). A narrower radius or σ cannot move a sample off the pixel's centre there, and the numbers that
# normalise the filter (1/∫f, -1/2σ²) leave 32-bit range long before σ reaches 0 (σ = 1e-30 px gave NaN weights,
# every sample dropped; σ = 1e-300 px divided by zero).
WIDTH_LIMIT = 0.001
_RADIUS = Range(WIDTH_LIMIT, RADIUS_LIMIT)
# A Gaussian's radius below σ/16 leaves f a peak of 1 - exp(-1/512) ≈ 2^-9 above its cut-off: less than that and its
# 32-bit evaluation, exp(−x²/2σ²) − exp(−r²/2σ²), is all rounding (radius 1e-4 px under σ = 4 px weighted every
# sample 0, a black image).
GAUSSIAN_RADIUS_PER_STDDEV = 1.0 / 16.0
FILTERS: dict[str, tuple[Parameter, ...]] = {
    "box": (),
    "tent": (
        Parameter(
            "radius", "float", "pixels", None, _RADIUS, default_doc="1", doc="where f = 1 − |x|/radius reaches 0"
        ),
    ),
    "gaussian": (
        Parameter("stddev", "float", "pixels", 0.5, Range(WIDTH_LIMIT, 4.0), doc="σ of exp(−x²/2σ²)"),
        Parameter(
            "radius",
            "float",
            "pixels",
            None,
            _RADIUS,
            default_doc="4 stddev",
            doc="cut-off, at least stddev/16; f = exp(−x²/2σ²) − exp(−radius²/2σ²) inside it (Mitsuba 3's and "
            "pbrt-v4's form)",
        ),
    ),
    "mitchell": (
        Parameter("radius", "float", "pixels", None, _RADIUS, default_doc="2", doc="the cubic's support"),
        Parameter("b", "float", "", 1.0 / 3.0, Range(0.0, 1.0), default_doc="1/3", doc="Mitchell–Netravali B"),
        Parameter("c", "float", "", 1.0 / 3.0, Range(0.0, 1.0), default_doc="1/3", doc="Mitchell–Netravali C"),
    ),
}
assert tuple(FILTERS) == PIXEL_FILTERS


@dataclass(frozen=True)
class PixelFilter:
    """A pixel filter; `radius` None is the type's default (box ½, tent 1, gaussian 4·stddev, mitchell 2)."""

    type: FilterType = "box"
    radius: float | None = None
    stddev: float = 0.5
    b: float = 1.0 / 3.0
    c: float = 1.0 / 3.0

    def __post_init__(self) -> None:
        if self.type not in FILTERS:
            raise SpectraceError(f"unknown pixel filter {self.type!r}; one of {', '.join(FILTERS)}", where="filter")
        for parameter in FILTERS[self.type]:
            value = getattr(self, parameter.name)
            if value is not None:
                parameter.check(value, where=f"filter.{parameter.name}")
        if self.type == "gaussian" and not self.support >= GAUSSIAN_RADIUS_PER_STDDEV * self.stddev:
            raise SpectraceError(
                f"a Gaussian's radius must be at least stddev/16 ({self.stddev / 16:g} px), got {self.support:g}: "
                "a narrower window leaves nothing of the curve above its cut-off in 32-bit floats",
                where="filter.radius",
            )

    @property
    def support(self) -> float:
        """The radius in pixels beyond which f = 0."""
        if self.radius is not None:
            return float(self.radius)
        return {"box": 0.5, "tent": 1.0, "gaussian": 4.0 * self.stddev, "mitchell": 2.0}[self.type]

    def evaluate(self, x: np.ndarray) -> np.ndarray:
        """f(x) of one axis at offsets x (pixels), float64."""
        x = np.abs(np.asarray(x, np.float64))
        r = self.support
        if self.type == "box":
            return (x <= r).astype(np.float64)
        if self.type == "tent":
            return np.maximum(0.0, 1.0 - x / r)
        if self.type == "gaussian":
            alpha = -1.0 / (2.0 * self.stddev**2)
            return np.where(x <= r, np.maximum(0.0, np.exp(alpha * x * x) - exp(alpha * r * r)), 0.0)
        return mitchell_1d(2.0 * x / r, self.b, self.c)

    def integral(self) -> float:
        """∫f over [−radius, radius], in closed form."""
        r = self.support
        if self.type == "box":
            return 2.0 * r
        if self.type == "tent":
            return r
        if self.type == "gaussian":
            s = self.stddev
            return s * sqrt(2.0 * pi) * erf(r / (s * sqrt(2.0))) - 2.0 * r * exp(-(r * r) / (2.0 * s * s))
        return r / 2.0  # the cubic integrates to 1 over [−2, 2] for every B, C (Mitchell & Netravali 1988)

    def device_cdf(self) -> np.ndarray:
        """The CDF of |f| over [0, radius] at the ends of PIXEL_FILTER_BINS equal bins (float32, last exactly 1),
        integrated by 256 midpoints a bin; all zero for box and tent, which are sampled in closed form."""
        if self.type in ("box", "tent"):
            return np.zeros(PIXEL_FILTER_BINS, np.float32)
        steps = 256
        x = (np.arange(PIXEL_FILTER_BINS * steps) + 0.5) * (self.support / (PIXEL_FILTER_BINS * steps))
        mass = np.abs(self.evaluate(x)).reshape(PIXEL_FILTER_BINS, steps).sum(axis=1)
        cdf = np.cumsum(mass) / mass.sum()
        cdf[-1] = 1.0
        return cdf.astype(np.float32)

    def device_shape(self) -> tuple[float, float, float, float]:
        """RenderParams.filter_shape: radius, 1/∫f, then gaussian -1/(2σ²), exp(-r²/(2σ²)); mitchell B, C."""
        r = self.support
        if self.type == "gaussian":
            alpha = -1.0 / (2.0 * self.stddev**2)
            return r, 1.0 / self.integral(), alpha, exp(alpha * r * r)
        if self.type == "mitchell":
            return r, 1.0 / self.integral(), self.b, self.c
        return r, 1.0 / self.integral(), 0.0, 0.0


BOX_FILTER = PixelFilter()
MITSUBA_DEFAULT_FILTER = PixelFilter("gaussian", stddev=0.5)


def mitchell_1d(x: np.ndarray, b: float, c: float) -> np.ndarray:
    """Mitchell & Netravali's cubic k(x) at x = |offset| in filter units, zero from 2 on."""
    x = np.abs(np.asarray(x, np.float64))
    inner = ((12 - 9 * b - 6 * c) * x**3 + (-18 + 12 * b + 6 * c) * x**2 + (6 - 2 * b)) / 6.0
    outer = ((-b - 6 * c) * x**3 + (6 * b + 30 * c) * x**2 + (-12 * b - 48 * c) * x + (8 * b + 24 * c)) / 6.0
    return np.where(x < 1.0, inner, np.where(x < 2.0, outer, 0.0))


def parse_filter_option(text: str, where: str = "--filter") -> PixelFilter:
    """A pixel filter from the command line's form, `TYPE` or `TYPE:KEY=VALUE,KEY=VALUE` (`gaussian:stddev=0.5,
    radius=2`), the keys those of FILTERS; anything else raises a SpectraceError at `where`."""
    name, _, rest = text.strip().partition(":")
    name = name.strip()
    if name not in FILTERS:
        raise SpectraceError(f"unknown pixel filter {name!r}; one of {', '.join(FILTERS)}", where=where)
    keys = [parameter.name for parameter in FILTERS[name]]
    values: dict[str, float] = {}
    for item in (part.strip() for part in rest.split(",")) if rest.strip() else ():
        key, equals, value = (piece.strip() for piece in item.partition("="))
        if key not in keys:
            allowed = f"its keys are {', '.join(keys)}" if keys else "it has no keys"
            raise SpectraceError(f"{name} filter has no key {key!r} ({allowed})", where=where)
        if not equals or key in values:
            raise SpectraceError(f"give each key once as {key}=NUMBER, got {item!r}", where=where)
        if problem := number_problem(value):
            raise SpectraceError(f"{key} {problem}", where=where)
        values[key] = float(value)
    try:
        return PixelFilter(name, **values)  # type: ignore[arg-type]
    except SpectraceError as error:
        raise SpectraceError(error.message, where=where) from None


def from_spec(spec) -> PixelFilter:
    """A `film.filter` value from the schema: a type name, or a table with `type` and that type's keys."""
    if spec is None:
        return BOX_FILTER
    if isinstance(spec, str):
        return PixelFilter(spec)  # type: ignore[arg-type]
    return PixelFilter(**{k: v for k, v in spec.model_dump().items() if v is not None})
