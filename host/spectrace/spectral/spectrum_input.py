"""A spectrum given as input, for a role: what the Python API accepts as a spectrum (`SpectrumLike`), and the one
path by which the API and the scene loader turn an RGB triple or a spectrum into a reflectance or an emission, with
the same checks and the same errors."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from numbers import Real
from typing import TYPE_CHECKING, Union, cast

import numpy as np

from spectrace.errors import SpectraceError
from spectrace.spectral.grid import GRID_NM
from spectrace.spectral.spectrum import Spectrum

if TYPE_CHECKING:
    import colour

# What `spectrum` accepts: a Spectrum; a colour-science SpectralDistribution; a constant; a library name
# ("cie:D65", "cornell_box/light"); (wavelengths_nm, values) arrays; an (N, 2) array or [[λ, v], ...] pairs;
# a {wavelength_nm: value} mapping; or 471 values on the renderer's 360..830 nm, 1 nm grid.
SpectrumLike = Union[Spectrum, "colour.SpectralDistribution", float, str, Sequence, np.ndarray, Mapping]  # noqa: UP007 (a quoted member)


def spectrum(source: SpectrumLike, scale: float = 1.0, name: str | None = None) -> Spectrum:
    """A `Spectrum` on the renderer's grid from any of the forms in `SpectrumLike`, times `scale`.

    Tabulated data are joined linearly and their end values held outside their range, as in scene files.
    """
    result = _spectrum_unscaled(source, name)
    if not isinstance(scale, Real) or not math.isfinite(scale) or scale < 0:
        raise SpectraceError(f"scale must be a finite number >= 0, got {scale!r}", where=name)
    return result if scale == 1.0 else result.scaled(float(scale))


def _spectrum_unscaled(source: SpectrumLike, name: str | None) -> Spectrum:
    from spectrace.spectral.spectrum_io import library_spectrum, parse_inline_spectrum, spectrum_from_colour

    label = name or "spectrum"
    if isinstance(source, Spectrum):
        return source if name is None else source.scaled(1.0, name=name)
    if type(source).__name__ == "SpectralDistribution":
        return spectrum_from_colour(cast("colour.SpectralDistribution", source), name=name)
    if isinstance(source, Real) and not isinstance(source, bool):
        return Spectrum.constant(float(source), name=name or "")
    if isinstance(source, str):
        return library_spectrum(source) if name is None else library_spectrum(source).scaled(1.0, name=name)
    if isinstance(source, Mapping):
        return parse_inline_spectrum({str(k): v for k, v in source.items()}, where=label, name=name)
    if isinstance(source, tuple) and len(source) == 2 and all(np.ndim(part) == 1 for part in source):
        wavelengths, values = (np.asarray(part, np.float64) for part in source)
        if wavelengths.shape != values.shape:
            raise SpectraceError(
                f"wavelengths ({wavelengths.size}) and values ({values.size}) differ in length", where=label
            )
        return parse_inline_spectrum(np.stack([wavelengths, values], axis=1).tolist(), where=label, name=name)
    array = np.asarray(source, np.float64) if isinstance(source, (Sequence, np.ndarray)) else None
    if array is not None and array.shape == GRID_NM.shape:
        return Spectrum(array, name=name or "", source="array on the 360..830 nm grid")
    if array is not None and array.ndim == 2 and array.shape[1] == 2:
        return parse_inline_spectrum(array.tolist(), where=label, name=name)
    raise SpectraceError(
        f"cannot make a spectrum from {type(source).__name__}: give a Spectrum, a colour.SpectralDistribution, a "
        "number, a library name, (wavelengths_nm, values), [[wavelength_nm, value], ...], a {wavelength_nm: value} "
        f"mapping or {GRID_NM.size} values on the 360..830 nm grid",
        where=label,
    )


def rgb_reflectance(rgb: Sequence[float] | np.ndarray) -> Spectrum:
    """A smooth reflectance in [0, 1] whose colour under D65 is the linear sRGB triple (Jakob & Hanika 2019), as
    `{ rgb = [...] }` for a material in a scene file."""
    from spectrace.spectral.uplift import uplift_reflectance

    return uplift_reflectance(rgb)[0]


def rgb_emission(rgb: Sequence[float] | np.ndarray, scale: float = 1.0) -> Spectrum:
    """A D65-based emission spectrum whose linear sRGB is `rgb` x `scale` ((1, 1, 1) = D65 with film Y = 1), in
    W/(m² sr nm), as `{ rgb = [...] }` for a radiance in a scene file."""
    from spectrace.spectral.uplift import uplift_illuminant

    return uplift_illuminant(rgb, scale=scale)


def from_rgb(rgb: Sequence[float], emission: bool, where: str | None) -> Spectrum:
    """The spectrum of a linear sRGB triple: an emission (D65-based, any magnitude) or a reflectance (in [0, 1])."""
    values = np.asarray(rgb, float)
    if np.any(values < 0):
        raise SpectraceError(f"rgb components must be >= 0, got {list(rgb)}", where=where)
    if emission:
        return rgb_emission(values)
    if np.any(values > 1):
        raise SpectraceError(f"a reflectance rgb must lie in [0, 1], got {list(rgb)}", where=where)
    return rgb_reflectance(values)


def within_bounds(result: Spectrum, emission: bool, where: str | None) -> Spectrum:
    """`result`, refused where it is negative or, for a reflectance, above 1 (it would create energy)."""
    values = result.values
    if np.any(values < 0):
        raise SpectraceError("spectrum has negative values", where=where)
    if not emission and np.any(values > 1.0 + 1e-6):
        raise SpectraceError(f"reflectance exceeds 1 (max {values.max():.4g}): it would create energy", where=where)
    return result


def optical_constant(result: Spectrum, positive: bool, where: str | None) -> Spectrum:
    """η (positive: > 0) or k (≥ 0) of a complex index of refraction: no upper bound."""
    within_bounds(result, True, where)
    if positive and not result.values.min() > 0:
        raise SpectraceError(f"must be > 0 at every wavelength (min {result.values.min():.4g})", where=where)
    return result


def is_rgb(source: object) -> bool:
    """A linear sRGB triple as the Python API takes it: three numbers in a tuple or list."""
    return isinstance(source, (tuple, list)) and len(source) == 3 and all(isinstance(c, Real) for c in source)


def role_spectrum(source: SpectrumLike, emission: bool, where: str) -> Spectrum:
    """The Python API's reflectance (emission=False) or emission from a triple (`from_rgb`) or any SpectrumLike,
    checked as the scene loader checks its own."""
    if is_rgb(source):
        return from_rgb(cast("Sequence[float]", source), emission, where)
    return within_bounds(spectrum(source), emission, where)


def reflectance(source: SpectrumLike, where: str) -> Spectrum:
    return role_spectrum(source, False, where)


def emission(source: SpectrumLike, where: str) -> Spectrum:
    return role_spectrum(source, True, where)
