"""What a pixel-filter plugin is: the shape of a filter's module (`PixelFilterPlugin`), which mypy checks every
module of spectrace.pixel_filters.PIXEL_FILTERS against, and the radius range the filters share."""

from collections.abc import Callable
from typing import Any, Protocol

import numpy as np

from spectrace.core.parameters import Range
from spectrace.core.registry import TabledPlugin

RADIUS_LIMIT = 16.0  # pixels: a wider filter blurs more than any use asks and wastes samples far from the pixel
# pixels: about the spacing of 32-bit film positions at the largest film side (2^14 px, a 24-bit significand:
# 2^-10 ≈ 0.001 px). A narrower radius or σ cannot move a sample off the pixel's centre there, and the numbers that
# normalise the filter (1/∫f, -1/2σ²) leave 32-bit range long before σ reaches 0 (σ = 1e-30 px gave NaN weights,
# every sample dropped; σ = 1e-300 px divided by zero).
WIDTH_LIMIT = 0.001
RADIUS = Range(WIDTH_LIMIT, RADIUS_LIMIT)


class PixelFilterPlugin(TabledPlugin, Protocol):
    """What a pixel filter's module holds; each function takes the `PixelFilter` (its `support` the radius in
    pixels, its own keys as fields), and its Mitsuba 3 and pbrt-v4 mappings: MITSUBA_PLUGINS (the rfilters it
    imports) with `from_mitsuba` and `to_mitsuba` (the export; Mitsuba's radii are fixed, each filter's
    default_radius), PBRT_FILTERS with `from_pbrt`. Beside these, where it applies: `check`, the rules spanning
    several keys."""

    @property
    def TABULATED(self) -> bool:  # noqa: N802
        """Whether the kernel draws it from RenderParams.filter_cdf (else in closed form, the table unused)."""
        ...

    def default_radius(self, pixel_filter: Any) -> float:
        """The radius in pixels when none is given."""
        ...

    def evaluate(self, pixel_filter: Any, x: np.ndarray) -> np.ndarray:
        """f(x) of one axis at offsets |x| (pixels, float64, >= 0)."""
        ...

    def integral(self, pixel_filter: Any) -> float:
        """∫f over [−radius, radius], in closed form."""
        ...

    def device_shape(self, pixel_filter: Any) -> tuple[float, float]:
        """RenderParams.filter_shape.zw, what kernels/pixel_filter.cl reads of this filter beside radius and 1/∫f."""
        ...

    @property
    def MITSUBA_PLUGINS(self) -> tuple[str, ...]: ...  # noqa: N802

    def from_mitsuba(self, importer: Any, rfilter: Any, properties: Any) -> dict:
        """The `film.filter` table of a Mitsuba rfilter of MITSUBA_PLUGINS (`importer` reads its properties)."""
        ...

    def to_mitsuba(self, pixel_filter: Any) -> dict:
        """Mitsuba's rfilter of the same f (the export checks the radius is Mitsuba's fixed one)."""
        ...

    @property
    def PBRT_FILTERS(self) -> tuple[str, ...]: ...  # noqa: N802

    def from_pbrt(self, context: Any, entity: Any, radius: Callable[[float], float]) -> dict:
        """The `film.filter` table of a pbrt-v4 PixelFilter of PBRT_FILTERS (`entity`, None for pbrt's default);
        `radius(default)` reads its xradius (pbrt's radius parameters are every filter's)."""
        ...
