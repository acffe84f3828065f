"""Fluorescent substances: an excitation spectrum, an emission spectrum and a quantum yield.

A fluorophore absorbs a photon at λ_in with a relative efficiency excitation(λ_in) and re-emits, with probability
`quantum_yield`, one photon whose wavelength is distributed as the emission spectrum (a quantum spectrum: photons
per nm). Photons are conserved, not energy: a photon moved from λ_in to λ_out > λ_in keeps λ_in/λ_out of its energy
(the Stokes loss).

The shipped ones are `spectra/fluorescent/<name>.csv` (sources and parametrisations in `spectra/fluorescent/README.md`),
each with columns `excitation` and `emission` and a `# quantum_yield: <number>` comment line; their columns are also
library spectra (`fluorescent/fluorescein:emission`). A user file in the same format is loaded by its path.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cache
from pathlib import Path

import numpy as np

from spectrace.errors import SpectraceError
from spectrace.io.input_files import is_regular_file
from spectrace.resources import spectra_dir
from spectrace.spectral.grid import GRID_NM, integrate_on_grid
from spectrace.spectral.spectrum import Spectrum
from spectrace.spectral.spectrum_io import COMMENT_PREFIX, load_spectrum_csv

FLUORESCENT_FOLDER = "fluorescent"
COLUMNS = ("excitation", "emission")
YIELD_KEY = "quantum_yield"


@dataclass(frozen=True)
class Fluorophore:
    name: str
    excitation: Spectrum  # relative, peak 1
    emission: Spectrum  # relative photons per nm, peak 1
    quantum_yield: float  # emitted photons per absorbed photon, in [0, 1]
    source: str = ""

    def emission_pdf(self) -> np.ndarray:
        """The emission spectrum on the grid as a probability density of the emitted photon's wavelength, 1/nm
        (integral 1 over the grid; the photons a band emits outside the grid are not counted)."""
        values = self.emission.values
        return values / float(integrate_on_grid(values))

    def mean_emission_nm(self) -> float:
        return float(integrate_on_grid(GRID_NM * self.emission_pdf()))


def _shipped_files() -> dict[str, Path]:
    return {path.stem: path for path in sorted((spectra_dir() / FLUORESCENT_FOLDER).glob("*.csv"))}


def fluorophore_names() -> list[str]:
    """The shipped fluorophores' names, for `load_fluorophore`."""
    return list(_shipped_files())


def _quantum_yield(path: Path) -> float:
    where = f"{path}: # {YIELD_KEY}"
    for line in path.read_text(encoding="utf-8-sig").splitlines():
        stripped = line.strip()
        if stripped and not stripped.startswith(COMMENT_PREFIX):
            break
        key, separator, text = stripped.lstrip(COMMENT_PREFIX).partition(":")
        if separator and key.strip().casefold() == YIELD_KEY:
            try:
                value = float(text.split()[0]) if text.split() else math.nan
            except ValueError:
                value = math.nan
            if not 0.0 <= value <= 1.0:
                raise SpectraceError(
                    f"the quantum yield must be a number in [0, 1] (photons out per photon in), got '{text.strip()}'",
                    where=where,
                )
            return value
    raise SpectraceError(
        f"a fluorophore file needs a '# {YIELD_KEY}: <number>' comment line before its header", where=str(path)
    )


def load_fluorophore_csv(path: str | Path, name: str | None = None) -> Fluorophore:
    """A fluorophore from a CSV with columns excitation and emission and a `# quantum_yield:` line. Errors name the
    file (and line or key)."""
    path = Path(path)
    label = name or path.stem
    excitation, emission = (load_spectrum_csv(path, column=column, name=f"{label}:{column}") for column in COLUMNS)
    quantum_yield = _quantum_yield(path)
    for column, spectrum in zip(COLUMNS, (excitation, emission)):
        if spectrum.min() < 0:
            raise SpectraceError(f"column '{column}' has negative values", where=str(path))
        if not spectrum.max() > 0:
            raise SpectraceError(f"column '{column}' is zero on 360-830 nm", where=str(path))
    return Fluorophore(label, excitation, emission, quantum_yield, source=str(path))


def load_fluorophore(spec: str, where: str | None = None) -> Fluorophore:
    """A shipped fluorophore by name (case-insensitive, see `fluorophore_names`) or a fluorophore CSV by path."""
    spec = spec.strip()
    if spec.lower().endswith(".csv") or "/" in spec or "\\" in spec or is_regular_file(spec):
        return load_fluorophore_csv(Path(spec))
    names = {name.casefold(): name for name in fluorophore_names()}
    name = names.get(spec.casefold())
    if name is None:
        raise SpectraceError(
            f"unknown fluorophore '{spec}' (available: {', '.join(fluorophore_names())}; or a CSV file)", where=where
        )
    return _load_shipped(name)


@cache
def _load_shipped(name: str) -> Fluorophore:
    return load_fluorophore_csv(_shipped_files()[name])
