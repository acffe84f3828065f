"""Optical glasses by name: Sellmeier dispersion coefficients from `spectra/glasses/sellmeier.csv`.

The file's header cites the source (refractiveindex.info database, SCHOTT catalogue 2017) and units: the index is
n²(λ) = 1 + Σ B_i λ² / (λ² − C_i) with λ in µm and C_i in µm², relative to air.
"""

from __future__ import annotations

import csv
from dataclasses import dataclass
from functools import cache

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


def sellmeier_ior(b, c_um2, wavelength_nm) -> np.ndarray:
    """n(λ) of the three-term Sellmeier formula; λ in nm, converted to the formula's µm."""
    lam2 = (np.asarray(wavelength_nm, np.float64) * 1e-3) ** 2
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
