"""Measured re-radiation (Donaldson) matrices of fluorescent surfaces, read from CSV and reduced to the
`fluorescent` material's parametric form.

Donaldson (1954, "Spectrophotometry of fluorescent pigments", British Journal of Applied Physics 5(6)) described a
fluorescent surface by a matrix over excitation and emission wavelengths; Hullin et al. (2010, "Fluorescent
immersion range scanning", ACM Transactions on Graphics 29(4)) measure and render such bispectral reflectance
matrices. The file holds only the matrix's fluorescent part, the photons moved to another wavelength (the
diagonal's elastic reflectance is the material's `base`):

    # any comment lines
    wavelength_nm,<λ_out 1>,<λ_out 2>,...        the header: the emission wavelengths, nm, ascending
    <λ_in 1>,M11,M12,...                         one row per excitation wavelength, nm, ascending
    ...

M[λ_in, λ_out] is photons re-emitted per nm of λ_out per photon arriving at λ_in (1/nm): rows are excitation,
columns emission. Some publications print the transpose (emission down the rows); transpose such a table first.
The spectra made from it are resampled onto the grid as a spectrum CSV is, its end values held beyond its range.

The material's device form holds one emission spectrum e(λ_out) for every λ_in, the separable (rank-one) matrix
a(λ_in)·Q·e(λ_out): the matrix's excitation spectrum a·Q is each row's photon total, ∫ M dλ_out, and e the
leading right singular vector. A matrix further than SEPARABILITY_TOLERANCE from its rank-one approximation (the
Frobenius norm of the remainder relative to the matrix's) is refused rather than rendered wrong.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from spectrace.errors import SpectraceError
from spectrace.spectral.spectrum import Spectrum
from spectrace.spectral.spectrum_io import (
    WAVELENGTH_COLUMN,
    _check_ascending,
    _parse_number,
    _read_csv_table,
    _spectrum_from_samples,
)

SEPARABILITY_TOLERANCE = 0.02


@dataclass(frozen=True)
class SeparableMatrix:
    """A Donaldson matrix as the fluorescent material takes it."""

    excitation: Spectrum  # a(λ_in)·Q: photons re-emitted (at any λ_out) per photon arriving at λ_in
    emission: Spectrum  # e(λ_out), the re-emitted photons' spectrum (shape only)
    separability_error: float  # ‖M − rank-one M‖ / ‖M‖


def read_matrix(path: str | Path) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(λ_in, λ_out, M) of a Donaldson matrix CSV; errors name the file, and the line for a bad row."""
    path = Path(path)
    table = _read_csv_table(path)
    where = f"{path}:{table.rows[0][0] - 1}" if table.rows else str(path)
    wavelengths_out: list[float] = []
    for text in table.columns:
        wavelength_nm = _parse_number(text, "emission wavelength in the header", where)
        _check_ascending(wavelengths_out[-1] if wavelengths_out else None, wavelength_nm, where)
        wavelengths_out.append(wavelength_nm)
    if len(wavelengths_out) < 2 or len(table.rows) < 2:
        raise SpectraceError(
            f"a re-radiation matrix needs at least 2 emission columns and 2 excitation rows, got "
            f"{len(wavelengths_out)} and {len(table.rows)}",
            where=str(path),
        )
    wavelengths_in: list[float] = []
    rows: list[list[float]] = []
    for line_number, fields in table.rows:
        line = f"{path}:{line_number}"
        if len(fields) != 1 + len(wavelengths_out):
            raise SpectraceError(
                f"expected {1 + len(wavelengths_out)} comma-separated fields, got {len(fields)}", where=line
            )
        wavelength_nm = _parse_number(fields[0], f"excitation wavelength ({WAVELENGTH_COLUMN})", line)
        _check_ascending(wavelengths_in[-1] if wavelengths_in else None, wavelength_nm, line)
        wavelengths_in.append(wavelength_nm)
        row = [_parse_number(text, "matrix value", line) for text in fields[1:]]
        if min(row) < 0.0:
            raise SpectraceError(f"matrix value {min(row):g} is negative: photons per nm are not", where=line)
        rows.append(row)
    return np.array(wavelengths_in), np.array(wavelengths_out), np.array(rows)


def separable_matrix(path: str | Path, name: str | None = None) -> SeparableMatrix:
    """The excitation a·Q and emission e of the Donaldson matrix CSV at `path` (see the module's text), or a
    SpectraceError naming the file: a row re-emitting more photons than arrive, a matrix of zeros, or one that is
    not separable."""
    path = Path(path)
    label = name or path.stem
    wavelengths_in, wavelengths_out, matrix = read_matrix(path)
    photons = np.trapezoid(matrix, wavelengths_out, axis=1)
    worst = int(np.argmax(photons))
    if photons[worst] > 1.0 + 1e-6:
        raise SpectraceError(
            f"the row at {wavelengths_in[worst]:g} nm re-emits {photons[worst]:.4g} photons per photon arriving "
            "(∫ M dλ_out must not exceed 1)",
            where=str(path),
        )
    if not np.any(matrix > 0.0):
        raise SpectraceError("the matrix is zero everywhere: nothing is re-emitted", where=str(path))
    _, singular, right = np.linalg.svd(matrix, full_matrices=False)
    error = float(np.sqrt(np.sum(singular[1:] ** 2) / np.sum(singular**2)))
    if error > SEPARABILITY_TOLERANCE:
        raise SpectraceError(
            f"the matrix is not separable (its rank-one remainder is {100 * error:.3g} % of it, more than "
            f"{100 * SEPARABILITY_TOLERANCE:g} %): its emission spectrum changes with the excitation wavelength, "
            "which the fluorescent material cannot hold",
            where=str(path),
        )
    emission = right[0] * np.sign(right[0][np.argmax(np.abs(right[0]))])
    where = str(path)
    return SeparableMatrix(
        excitation=_spectrum_from_samples(
            list(wavelengths_in), list(photons), name=f"{label} excitation", source=f"{path} rows", where=where
        ),
        emission=_spectrum_from_samples(
            list(wavelengths_out),
            list(np.clip(emission, 0.0, None)),
            name=f"{label} emission",
            source=f"{path} columns",
            where=where,
        ),
        separability_error=error,
    )
