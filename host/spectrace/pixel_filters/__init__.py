"""The pixel's reconstruction filter (kernels/pixel_filter.cl): box, tent, Gaussian and Mitchell–Netravali, each
separable, f(x, y) = f(x) f(y), applied by filter importance sampling so the film stays a per-pixel sum.

One module per filter, each with its parameter table (name, unit, default, range, meaning), from which the scene
schema's `film.filter`, the command line's `--filter` and docs/scene-format.md's table come, and its f, ∫f and
device row (`base.PixelFilterPlugin`). `PIXEL_FILTERS` lists them; a filter's position there is its device code
(RenderParams.pixel_filter, PIXEL_FILTER_<NAME> in the kernels: `generated_sources`). Offsets and radii are in
pixels. Box is our scenes' default; Mitsuba 3's default (and hence the Mitsuba importer's when a file names none) is
its Gaussian of σ = 0.5 px, cut off at 4σ.
"""

from dataclasses import dataclass

import numpy as np

from spectrace.core.contract import PIXEL_FILTER_BINS, GeneratedSources
from spectrace.core.registry import Registry
from spectrace.errors import SpectraceError
from spectrace.number_text import number_problem
from spectrace.pixel_filters import box, gaussian, mitchell, tent
from spectrace.pixel_filters.base import PixelFilterPlugin

PIXEL_FILTERS = Registry[PixelFilterPlugin]("pixel filter", (box, tent, gaussian, mitchell))


def generated_sources() -> GeneratedSources:
    """PIXEL_FILTER_<NAME> and PIXEL_FILTER_TYPE_COUNT, which every kernel that places camera samples is built with."""
    return GeneratedSources(PIXEL_FILTERS.kernel_defines("PIXEL_FILTER"))


@dataclass(frozen=True)
class PixelFilter:
    """A pixel filter: its type (a name of PIXEL_FILTERS) and the keys of every type, each read by the types whose
    table names it; `radius` None is the type's default (box ½, tent 1, gaussian 4·stddev, mitchell 2)."""

    type: str = "box"
    radius: float | None = None
    stddev: float = 0.5
    b: float = 1.0 / 3.0
    c: float = 1.0 / 3.0

    def __post_init__(self) -> None:
        if self.type not in PIXEL_FILTERS:
            raise SpectraceError(
                f"unknown pixel filter {self.type!r}; one of {', '.join(PIXEL_FILTERS)}", where="filter"
            )
        for parameter in self.plugin.PARAMETERS:
            value = getattr(self, parameter.name)
            if value is not None:
                parameter.check(value, where=f"filter.{parameter.name}")
        if (check := getattr(self.plugin, "check", None)) is not None:
            check(self)

    @property
    def plugin(self) -> PixelFilterPlugin:
        return PIXEL_FILTERS[self.type]

    @property
    def support(self) -> float:
        """The radius in pixels beyond which f = 0."""
        if self.radius is not None:
            return float(self.radius)
        return self.plugin.default_radius(self)

    def evaluate(self, x: np.ndarray) -> np.ndarray:
        """f(x) of one axis at offsets x (pixels), float64."""
        return self.plugin.evaluate(self, np.abs(np.asarray(x, np.float64)))

    def integral(self) -> float:
        """∫f over [−radius, radius], in closed form."""
        return self.plugin.integral(self)

    def device_cdf(self) -> np.ndarray:
        """The CDF of |f| over [0, radius] at the ends of PIXEL_FILTER_BINS equal bins (float32, last exactly 1),
        integrated by 256 midpoints a bin; all zero for a filter sampled in closed form."""
        if not self.plugin.TABULATED:
            return np.zeros(PIXEL_FILTER_BINS, np.float32)
        steps = 256
        x = (np.arange(PIXEL_FILTER_BINS * steps) + 0.5) * (self.support / (PIXEL_FILTER_BINS * steps))
        mass = np.abs(self.evaluate(x)).reshape(PIXEL_FILTER_BINS, steps).sum(axis=1)
        cdf = np.cumsum(mass) / mass.sum()
        cdf[-1] = 1.0
        return cdf.astype(np.float32)

    def device_shape(self) -> tuple[float, float, float, float]:
        """RenderParams.filter_shape: radius, 1/∫f, then the filter's own two numbers (its device_shape)."""
        return self.support, 1.0 / self.integral(), *self.plugin.device_shape(self)

    @property
    def code(self) -> int:
        """RenderParams.pixel_filter."""
        return PIXEL_FILTERS.codes[self.type]


BOX_FILTER = PixelFilter()
MITSUBA_DEFAULT_FILTER = PixelFilter("gaussian", stddev=0.5)


def parse_filter_option(text: str, where: str = "--filter") -> PixelFilter:
    """A pixel filter from the command line's form, `TYPE` or `TYPE:KEY=VALUE,KEY=VALUE` (`gaussian:stddev=0.5,
    radius=2`), the keys those of the type's table; anything else raises a SpectraceError at `where`."""
    name, _, rest = text.strip().partition(":")
    name = name.strip()
    if name not in PIXEL_FILTERS:
        raise SpectraceError(f"unknown pixel filter {name!r}; one of {', '.join(PIXEL_FILTERS)}", where=where)
    keys = [parameter.name for parameter in PIXEL_FILTERS[name].PARAMETERS]
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
        return PixelFilter(name, **values)
    except SpectraceError as error:
        raise SpectraceError(error.message, where=where) from None


def from_spec(spec) -> PixelFilter:
    """A `film.filter` value from the schema: a type name, or a table with `type` and that type's keys."""
    if spec is None:
        return BOX_FILTER
    if isinstance(spec, str):
        return PixelFilter(spec)
    return PixelFilter(**{k: v for k, v in spec.model_dump().items() if v is not None})
