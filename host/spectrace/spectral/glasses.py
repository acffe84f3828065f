"""Indices of refraction of dielectrics: constant, Sellmeier or Cauchy dispersion, and optical glasses by name
(Sellmeier coefficients from `spectra/glasses/sellmeier.csv`).

The file's header cites the source (refractiveindex.info database, SCHOTT catalogue 2017) and units: the index is
n²(λ) = 1 + Σ B_i λ² / (λ² − C_i) with λ in µm and C_i in µm², relative to air. kernels/ior.cl evaluates the same
three models on the device.
"""

from __future__ import annotations

import csv
from dataclasses import dataclass
from functools import cache
from typing import Literal

import numpy as np

from spectrace.errors import SpectraceError
from spectrace.resources import spectra_dir

GLASSES_FILE = "glasses/sellmeier.csv"

# Names people use for a catalogue glass: "BK7" is sold today as SCHOTT's lead-free N-BK7.
GLASS_ALIASES = {"BK7": "N-BK7"}


@dataclass(frozen=True)
class Glass:
    name: str
    sellmeier_b: tuple[float, float, float]
    sellmeier_c_um2: tuple[float, float, float]
    valid_um: tuple[float, float]  # the wavelength range the catalogue fitted the formula on
    nd_catalog: float  # n at the helium d line, 587.5618 nm, as the catalogue quotes it
    abbe_catalog: float

    def ior(self, wavelength_nm) -> np.ndarray:
        return sellmeier_ior(self.sellmeier_b, self.sellmeier_c_um2, wavelength_nm)

    def index_of_refraction(self) -> IndexOfRefraction:
        return IndexOfRefraction("sellmeier", (*self.sellmeier_b, *self.sellmeier_c_um2), name=self.name)


@dataclass(frozen=True)
class IndexOfRefraction:
    """A dielectric's index relative to the medium outside it (air): `constant` (n), `sellmeier` (B1, B2, B3, C1,
    C2, C3; λ in µm, C in µm²) or `cauchy` (a, b: n = a + b/λ², λ in µm, b in µm²)."""

    model: Literal["constant", "sellmeier", "cauchy"]
    coefficients: tuple[float, ...]
    name: str | None = None  # the glass it came from, if any

    @property
    def dispersive(self) -> bool:
        return self.model != "constant"

    def at(self, wavelength_nm) -> np.ndarray:
        if self.model == "sellmeier":
            return sellmeier_ior(self.coefficients[:3], self.coefficients[3:], wavelength_nm)
        if self.model == "cauchy":
            return cauchy_ior(self.coefficients[0], self.coefficients[1], wavelength_nm)
        return np.full(np.shape(wavelength_nm), float(self.coefficients[0]))

    @staticmethod
    def constant(n: float) -> IndexOfRefraction:
        return IndexOfRefraction("constant", (float(n),))


def sellmeier_ior(b, c_um2, wavelength_nm) -> np.ndarray:
    """n(λ) of the three-term Sellmeier formula; λ in nm, converted to the formula's µm. NaN where n² < 0."""
    lam2 = (np.asarray(wavelength_nm, np.float64) * 1e-3) ** 2
    with np.errstate(divide="ignore", invalid="ignore"):
        n2 = 1.0 + sum(bi * lam2 / (lam2 - ci) for bi, ci in zip(b, c_um2))
        return np.sqrt(n2)


def cauchy_ior(a: float, b_um2: float, wavelength_nm) -> np.ndarray:
    """n(λ) = a + b / λ² with λ in µm (b in µm²)."""
    lam_um = np.asarray(wavelength_nm, np.float64) * 1e-3
    return a + b_um2 / lam_um**2


@cache
def _glass_table() -> dict[str, Glass]:
    path = spectra_dir() / GLASSES_FILE
    lines = [line for line in path.read_text(encoding="utf-8").splitlines() if not line.lstrip().startswith("#")]
    glasses = {}
    for row in csv.DictReader(lines):
        glasses[row["glass"]] = Glass(
            name=row["glass"],
            sellmeier_b=(float(row["B1"]), float(row["B2"]), float(row["B3"])),
            sellmeier_c_um2=(float(row["C1_um2"]), float(row["C2_um2"]), float(row["C3_um2"])),
            valid_um=(float(row["valid_min_um"]), float(row["valid_max_um"])),
            nd_catalog=float(row["nd_catalog"]),
            abbe_catalog=float(row["Vd_catalog"]),
        )
    return glasses


def glass_names() -> list[str]:
    """Every name `glass` accepts: the catalogue's, then the aliases."""
    return list(_glass_table()) + list(GLASS_ALIASES)


def glass(name: str, where: str | None = None) -> Glass:
    table = _glass_table()
    key = GLASS_ALIASES.get(name, name)
    if key not in table:
        raise SpectraceError(f"unknown glass '{name}' (glasses: {', '.join(glass_names())})", where=where)
    return table[key]


# The index a dielectric may have at any visible wavelength, interior over exterior. Below 1 the interior is the
# rarer medium (an air bubble in water): light from outside may then be totally reflected, which the Fresnel term
# and Snell's law already give for either side of the surface. At 1 a smooth interface passes light straight
# through; a rough one degenerates near 1 (ROUGH_IOR_GAP).
IOR_RANGE = (0.25, 4.0)
# A rough interface needs |n − 1| at least this large: its refraction half vector n_o ωo + n_i ωi vanishes as the
# indices meet.
ROUGH_IOR_GAP = 1e-4
_CHECK_WAVELENGTHS_NM = np.arange(360.0, 831.0, 1.0)
_COEFFICIENT_COUNTS = {"sellmeier": 6, "cauchy": 2}


def index_of_refraction(value, where: str | None = None) -> IndexOfRefraction:
    """An IndexOfRefraction from a number, a glass name ("BK7", "SF11", ...), {"sellmeier": [B1, B2, B3, C1, C2,
    C3]} or {"cauchy": [a, b]} (λ in µm); it must lie within IOR_RANGE over 360–830 nm."""
    if isinstance(value, IndexOfRefraction):
        ior = value
    elif isinstance(value, str):
        ior = glass(value, where=where).index_of_refraction()
    elif isinstance(value, (int, float, np.floating)) and not isinstance(value, bool):
        ior = IndexOfRefraction.constant(float(value))
    elif isinstance(value, dict) and len(value) == 1 and next(iter(value)) in _COEFFICIENT_COUNTS:
        model, coefficients = next(iter(value.items()))
        count = _COEFFICIENT_COUNTS[model]
        try:
            numbers = tuple(float(c) for c in coefficients)
        except (TypeError, ValueError):
            numbers = ()
        if len(numbers) != count or not all(np.isfinite(numbers)):
            raise SpectraceError(f"{model} needs {count} finite numbers, got {coefficients!r}", where=where)
        ior = IndexOfRefraction(model, numbers)
    else:
        raise SpectraceError(
            f"ior must be a number, a glass name ({', '.join(glass_names())}), "
            f"{{ sellmeier = [B1, B2, B3, C1, C2, C3] }} or {{ cauchy = [a, b] }}; got {value!r}",
            where=where,
        )
    n = ior.at(_CHECK_WAVELENGTHS_NM)
    low, high = IOR_RANGE
    bad = ~(np.isfinite(n) & (n >= low) & (n <= high))
    if np.any(bad):
        first = int(np.argmax(bad))
        raise SpectraceError(
            f"the index of refraction must lie in [{low}, {high:g}] over 360–830 nm; it is "
            f"{n[first]:.6g} at {_CHECK_WAVELENGTHS_NM[first]:g} nm",
            where=where,
        )
    return ior
