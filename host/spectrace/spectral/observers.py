"""Standard observers for the display experiment, and photometric XYZ (683 lm/W scale) on the project grid.

Two XYZ scales coexist in spectrace; this module owns the second one:
- film XYZ (`spectrace.spectral.spectrum_to_xyz`): integral L cmf dlambda / integral ybar dlambda, CIE 1931 only,
  so a constant radiance 1 has Y = 1 (the renderer's convention);
- photometric XYZ (`photometric_xyz` here): K_m * integral L cmf dlambda with K_m = 683 lm/W, so that for a
  radiance in W/(sr m^2 nm) the CIE 1931 Y is the luminance in cd/m^2 (CIE 15:2004, section 7.1).
  For the 1964 10 degree and the 2012 2 degree observers the same factor is used; their Y is then not a
  luminance by definition, but CIELAB only uses ratios to the reference white, so the scale cancels.

The colour matching functions are read from colour-science (`colour.MSDS_CMFS`) at load time, not copied:
CIE 1931 2 degree and CIE 1964 10 degree at 1 nm over 360..830 nm (CVRL "Older CIE Standards"), and the
CIE 2012 2 degree "physiologically relevant" XYZ functions (CVRL, adopted by CIE 170-2:2015; colour-science
files them as "CIE 2015 2 Degree Standard Observer") at 1 nm over 390..830 nm. A table is zero where it has no
data (360..389 nm for the 2012 observer): the standard defines the functions only on its own range.
"""

from __future__ import annotations

from enum import StrEnum
from functools import cache

import colour
import numpy as np

from spectrace.spectral import GRID_NM, Spectrum
from spectrace.spectral.grid import TRAPEZOID_WEIGHTS_NM

LUMINOUS_EFFICACY_LM_PER_W = 683.0  # K_m, maximum luminous efficacy for photopic vision (CIE 15:2004; SI candela)


class Observer(StrEnum):
    """The observers whose colour differences the display commands report (value = short key in JSON)."""

    CIE_1931_2 = "cie1931_2"
    CIE_1964_10 = "cie1964_10"
    CIE_2012_2 = "cie2012_2"

    @property
    def label(self) -> str:
        return _LABELS[self]

    @property
    def colour_science_name(self) -> str:
        return _COLOUR_SCIENCE_NAMES[self]


_LABELS = {
    Observer.CIE_1931_2: "CIE 1931 2°",
    Observer.CIE_1964_10: "CIE 1964 10°",
    Observer.CIE_2012_2: "CIE 2012 2°",
}
_COLOUR_SCIENCE_NAMES = {
    Observer.CIE_1931_2: "CIE 1931 2 Degree Standard Observer",
    Observer.CIE_1964_10: "CIE 1964 10 Degree Standard Observer",
    Observer.CIE_2012_2: "CIE 2015 2 Degree Standard Observer",
}

ALL_OBSERVERS: tuple[Observer, ...] = tuple(Observer)


@cache
def observer_cmfs(observer: Observer) -> np.ndarray:
    """(471, 3) read-only: xbar, ybar, zbar of `observer` on the grid, zero outside its table."""
    cmfs = colour.MSDS_CMFS[observer.colour_science_name]
    wavelengths_nm = np.asarray(cmfs.wavelengths, dtype=np.float64)
    values = np.asarray(cmfs.values, dtype=np.float64)
    on_grid = np.stack(
        [np.interp(GRID_NM, wavelengths_nm, values[:, axis], left=0.0, right=0.0) for axis in range(3)], axis=-1
    )
    on_grid.setflags(write=False)
    return on_grid


@cache
def _photometric_weights(observer: Observer) -> np.ndarray:
    weights = LUMINOUS_EFFICACY_LM_PER_W * observer_cmfs(observer) * TRAPEZOID_WEIGHTS_NM[:, None]
    weights.setflags(write=False)
    return weights


def photometric_xyz(radiance: Spectrum | np.ndarray, observer: Observer = Observer.CIE_1931_2) -> np.ndarray:
    """683 lm/W * integral L(lambda) cmf(lambda) dlambda (trapezoid rule on the grid).

    `radiance`: a Spectrum or grid samples on the last axis, in W/(sr m^2 nm); the CIE 1931 Y is then the
    luminance in cd/m^2. For a radiance on a relative scale the result is on the same relative scale.
    """
    values = radiance.values if isinstance(radiance, Spectrum) else np.asarray(radiance, dtype=np.float64)
    return values @ _photometric_weights(observer)


def luminance_cd_m2(radiance: Spectrum | np.ndarray) -> float | np.ndarray:
    """Luminance 683 lm/W * integral L ybar dlambda (CIE 1931) of a radiance in W/(sr m^2 nm), in cd/m^2."""
    return photometric_xyz(radiance, Observer.CIE_1931_2)[..., 1]
