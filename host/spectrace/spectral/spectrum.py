"""`Spectrum`: a spectral quantity sampled on the common wavelength grid (see `grid.py`)."""

from __future__ import annotations

from numbers import Real
from typing import overload

import numpy as np

from spectrace.errors import SpectraceError
from spectrace.spectral.grid import GRID_NM, GRID_SIZE


class Spectrum:
    """471 float64 samples on the 360..830 nm, 1 nm grid; read-only once built.

    `name` is a short label (``"cornell_box/reflectance:white"``), `source` says where the values came
    from (a file and line, a scene key) so that later errors can point back at it. Units are those of
    whatever was loaded: reflectance (dimensionless), relative radiance, an index of refraction, ...
    """

    __slots__ = ("_values", "name", "source")

    def __init__(self, values: np.ndarray, name: str = "", source: str = ""):
        array = np.array(values, dtype=np.float64)  # always a private copy
        if array.shape != (GRID_SIZE,):
            raise ValueError(f"a Spectrum needs {GRID_SIZE} samples on the grid, got shape {array.shape}")
        if not np.all(np.isfinite(array)):
            raise SpectraceError(f"spectrum '{name}' has NaN or infinite values", where=source or None)
        array.setflags(write=False)
        self._values = array
        self.name = name
        self.source = source

    @classmethod
    def constant(cls, value: float, name: str = "", source: str = "") -> Spectrum:
        return cls(np.full(GRID_SIZE, float(value)), name=name or f"constant {value:g}", source=source)

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
        return Spectrum(self._values * float(factor), name=self.name if name is None else name, source=self.source)

    def __mul__(self, other: float | Real | Spectrum) -> Spectrum:
        if isinstance(other, Spectrum):
            return Spectrum(self._values * other._values, name=f"{self.name}*{other.name}", source=self.source)
        if isinstance(other, Real) and not isinstance(other, bool):
            return self.scaled(float(other))
        return NotImplemented

    __rmul__ = __mul__

    def __truediv__(self, divisor: float | Real) -> Spectrum:
        if isinstance(divisor, Real) and not isinstance(divisor, bool):
            return self.scaled(1.0 / float(divisor))
        return NotImplemented

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Spectrum):
            return NotImplemented
        return bool(np.array_equal(self._values, other._values))

    def __hash__(self) -> int:
        return hash(self._values.tobytes())

    def __len__(self) -> int:
        return GRID_SIZE

    def __repr__(self) -> str:
        return f"Spectrum({self.name!r}, min={self.min():.4g}, mean={self.mean():.4g}, max={self.max():.4g}" + (
            f", source={self.source!r})" if self.source else ")"
        )
