"""`Spectrum`: a spectral quantity sampled on the common wavelength grid (see `grid.py`), and how it continues
beyond that grid (`Extension`) for a film whose wavelengths reach further (`film.wavelengths`)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from numbers import Real
from typing import overload

import numpy as np

from spectrace.errors import SpectraceError
from spectrace.spectral.grid import GRID_MAX_NM, GRID_MIN_NM, GRID_NM, GRID_SIZE


@dataclass(frozen=True)
class Extension:
    """What a spectrum is beyond the common grid: its values on [lo_nm, hi_nm] (the range its data or formula
    defines), from `evaluate` (nm -> values). `rgb_uplift`: the spectrum is an RGB uplift, whose continuation
    outside the visible is a convention, used only when the scene asks for it (`film.extend_rgb`).

    `evaluate` must pickle with plain `pickle` (a module-level function or a small dataclass such as those below,
    never a lambda or a closure): scenes travel to other processes, a cluster's workers among them."""

    lo_nm: float
    hi_nm: float
    evaluate: Callable[[np.ndarray], np.ndarray]
    rgb_uplift: bool = False

    def __post_init__(self) -> None:
        # A lambda or closure pickles only through cloudpickle: plain pickle (the command line's measure of what a
        # cluster's workers receive, process pools) would fail on the whole scene, far from here.
        name = getattr(self.evaluate, "__qualname__", "")
        if "<lambda>" in name or "<locals>" in name:
            raise TypeError(f"an Extension's evaluate must pickle: a module-level function or dataclass, not {name}")

    def scaled(self, factor: float) -> Extension:
        return Extension(self.lo_nm, self.hi_nm, ScaledCurve(factor, self.evaluate), self.rgb_uplift)

    def times(self, other: Extension) -> Extension:
        return Extension(
            max(self.lo_nm, other.lo_nm),
            min(self.hi_nm, other.hi_nm),
            ProductCurve(self.evaluate, other.evaluate),
            self.rgb_uplift or other.rgb_uplift,
        )


@dataclass(frozen=True)
class ConstantCurve:
    """nm -> `level` everywhere."""

    level: float

    def __call__(self, nm: np.ndarray) -> np.ndarray:
        return np.full(np.shape(nm), self.level)


@dataclass(frozen=True)
class ScaledCurve:
    """nm -> factor * curve(nm)."""

    factor: float
    curve: Callable[[np.ndarray], np.ndarray]

    def __call__(self, nm: np.ndarray) -> np.ndarray:
        return self.factor * self.curve(nm)


@dataclass(frozen=True)
class ProductCurve:
    """nm -> first(nm) * second(nm)."""

    first: Callable[[np.ndarray], np.ndarray]
    second: Callable[[np.ndarray], np.ndarray]

    def __call__(self, nm: np.ndarray) -> np.ndarray:
        return self.first(nm) * self.second(nm)


@dataclass(frozen=True, eq=False)  # arrays have no single truth value: curves compare by identity
class SampledCurve:
    """nm -> linear interpolation of the samples (wavelengths ascending, nm), held constant beyond them."""

    wavelengths_nm: np.ndarray
    values: np.ndarray

    def __call__(self, nm: np.ndarray) -> np.ndarray:
        return np.interp(nm, self.wavelengths_nm, self.values)


def sampled_extension(wavelengths_nm: np.ndarray, values: np.ndarray) -> Extension:
    """The extension of measured samples: linear interpolation, over the samples' own range only."""
    wavelengths = np.array(wavelengths_nm, np.float64)
    data = np.array(values, np.float64)
    return Extension(float(wavelengths[0]), float(wavelengths[-1]), SampledCurve(wavelengths, data))


def _range_text(lo: float, hi: float) -> str:
    return f"{lo:g}-{hi:g} nm"


class Spectrum:
    """471 float64 samples on the 360..830 nm, 1 nm grid; read-only once built.

    `name` is a short label (``"cornell_box/reflectance:white"``), `source` says where the values came
    from (a file and line, a scene key) so that later errors can point back at it. Units are those of
    whatever was loaded: reflectance (dimensionless), relative radiance, an index of refraction, ...
    """

    __slots__ = ("_values", "extension", "name", "source")

    def __init__(self, values: np.ndarray, name: str = "", source: str = "", extension: Extension | None = None):
        array = np.array(values, dtype=np.float64)  # always a private copy
        if array.shape != (GRID_SIZE,):
            raise ValueError(f"a Spectrum needs {GRID_SIZE} samples on the grid, got shape {array.shape}")
        if not np.all(np.isfinite(array)):
            raise SpectraceError(f"spectrum '{name}' has NaN or infinite values", where=source or None)
        array.setflags(write=False)
        self._values = array
        self.name = name
        self.source = source
        self.extension = extension  # None: defined on the common grid only

    @classmethod
    def constant(cls, value: float, name: str = "", source: str = "", rgb_uplift: bool = False) -> Spectrum:
        level = float(value)
        extension = Extension(-np.inf, np.inf, ConstantCurve(level), rgb_uplift)
        return cls(np.full(GRID_SIZE, level), name=name or f"constant {value:g}", source=source, extension=extension)

    @classmethod
    def zeros(cls, name: str = "zero", source: str = "") -> Spectrum:
        return cls.constant(0.0, name=name, source=source)

    @property
    def values(self) -> np.ndarray:
        """The samples at `GRID_NM` (read-only float64 array)."""
        return self._values

    @property
    def wavelengths_nm(self) -> np.ndarray:
        return GRID_NM

    @overload
    def evaluate(self, wavelengths_nm: float) -> float: ...

    @overload
    def evaluate(self, wavelengths_nm: np.ndarray) -> np.ndarray: ...

    def evaluate(self, wavelengths_nm: np.ndarray | float) -> np.ndarray | float:
        """Linear interpolation between grid samples, as the kernels do; held constant outside the grid."""
        return np.interp(wavelengths_nm, GRID_NM, self._values)

    def max(self) -> float:
        return float(self._values.max())

    def min(self) -> float:
        return float(self._values.min())

    def mean(self) -> float:
        """Mean of the grid samples (equal weight per nm)."""
        return float(self._values.mean())

    def scaled(self, factor: float, name: str | None = None) -> Spectrum:
        extension = self.extension.scaled(float(factor)) if self.extension is not None else None
        return Spectrum(
            self._values * float(factor),
            name=self.name if name is None else name,
            source=self.source,
            extension=extension,
        )

    def __mul__(self, other: float | Real | Spectrum) -> Spectrum:
        if isinstance(other, Spectrum):
            extension = (
                self.extension.times(other.extension)
                if self.extension is not None and other.extension is not None
                else None
            )
            return Spectrum(
                self._values * other._values, name=f"{self.name}*{other.name}", source=self.source, extension=extension
            )
        if isinstance(other, Real) and not isinstance(other, bool):
            return self.scaled(float(other))
        return NotImplemented

    __rmul__ = __mul__

    def __truediv__(self, divisor: float | Real) -> Spectrum:
        if isinstance(divisor, Real) and not isinstance(divisor, bool):
            return self.scaled(1.0 / float(divisor))
        return NotImplemented

    def on_wavelengths(self, wavelengths_nm: np.ndarray, extend_rgb: bool = False) -> np.ndarray:
        """Values at `wavelengths_nm` (ascending, nm): the grid samples (lerped) within the common grid, the extension
        beyond it. One-line errors when the spectrum does not reach that far, or is an RGB uplift and `extend_rgb`
        is not set: a film that sees further than a spectrum is defined must not see a silent zero or a guess."""
        wavelengths = np.asarray(wavelengths_nm, np.float64)
        inside = (wavelengths >= GRID_MIN_NM) & (wavelengths <= GRID_MAX_NM)
        result = np.empty(wavelengths.shape)
        result[inside] = np.interp(wavelengths[inside], GRID_NM, self._values)
        outside = wavelengths[~inside]
        if outside.size == 0:
            return result
        wanted = _range_text(wavelengths[0], wavelengths[-1])
        label = f"spectrum '{self.name or 'unnamed'}'"
        extension = self.extension
        if extension is not None and extension.rgb_uplift and not extend_rgb:
            raise SpectraceError(
                f"{label} is an RGB uplift, defined for the visible ({_range_text(GRID_MIN_NM, GRID_MAX_NM)}) only; "
                f"the film's wavelengths {wanted} need measured data, or film.extend_rgb = true to continue it"
            )
        data_lo, data_hi = (extension.lo_nm, extension.hi_nm) if extension is not None else (GRID_MIN_NM, GRID_MAX_NM)
        if outside.min() < min(data_lo, GRID_MIN_NM) or outside.max() > max(data_hi, GRID_MAX_NM):
            missing = [_range_text(a, b) for a, b in ((wavelengths[0], data_lo), (data_hi, wavelengths[-1])) if b > a]
            defined = _range_text(extension.lo_nm, extension.hi_nm) if extension else "the common grid"
            raise SpectraceError(
                f"{label} is defined over {defined}; the film's wavelengths {wanted} also need {' and '.join(missing)}",
                where=self.source or None,
            )
        assert extension is not None
        values = np.asarray(extension.evaluate(outside), np.float64)
        if not np.all(np.isfinite(values)):
            raise SpectraceError(
                f"{label} has NaN or infinite values beyond the common grid", where=self.source or None
            )
        result[~inside] = values
        return result

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Spectrum):
            return NotImplemented
        return bool(np.array_equal(self._values, other._values))

    def __hash__(self) -> int:
        return hash(self._values.tobytes())

    def __len__(self) -> int:
        return GRID_SIZE

    def _repr_png_(self) -> bytes:
        """A notebook shows a spectrum as its curve against wavelength (spectrace.plots.plot_spectra draws several,
        in their colours, into a figure or file)."""
        import io

        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.figure import Figure

        figure = Figure(figsize=(5.0, 2.6))
        FigureCanvasAgg(figure)
        axes = figure.subplots()
        axes.plot(GRID_NM, self._values, color="0.2", linewidth=1.4)
        axes.set_xlim(GRID_NM[0], GRID_NM[-1])
        axes.set_xlabel("wavelength (nm)")
        axes.set_title(self.name or "spectrum", fontsize=9)
        axes.grid(alpha=0.3)
        buffer = io.BytesIO()
        figure.savefig(buffer, format="png", dpi=80, bbox_inches="tight")
        return buffer.getvalue()

    def __repr__(self) -> str:
        return f"Spectrum({self.name!r}, min={self.min():.4g}, mean={self.mean():.4g}, max={self.max():.4g}" + (
            f", source={self.source!r})" if self.source else ")"
        )
