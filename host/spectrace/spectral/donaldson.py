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

The material takes a matrix in one of two forms. A separable (rank-one) matrix a(λ_in)·Q·e(λ_out) becomes the
parametric dye: its excitation spectrum a·Q is each row's photon total, ∫ M dλ_out, and e the leading right singular
vector, and it renders exactly as that dye. A matrix further than SEPARABILITY_TOLERANCE from its rank-one
approximation (the Frobenius norm of the remainder relative to the matrix's), whose emission changes with the
excitation wavelength, is kept as the table it is (`TabulatedMatrix`): the device holds it on the film's 1 nm grid,
bilinear between the file's samples and 0 outside them, with the marginals and CDFs its sampling needs
(kernels/fluorescence_matrix.cl). Its material's excitation and emission spectra are then its row totals and
its column totals (the emission under an excitation of one photon per nm at every λ_in), which describe it but do
not render it.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from spectrace.core.equality import fields_equal, identity_hash
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


@dataclass(frozen=True, eq=False)
class TabulatedMatrix:
    """A non-separable Donaldson matrix as the file gives it: M[λ_in, λ_out] (1/nm)."""

    wavelengths_in: np.ndarray  # nm, ascending
    wavelengths_out: np.ndarray  # nm, ascending
    values: np.ndarray  # (len(wavelengths_in), len(wavelengths_out))
    source: str  # the file

    __eq__ = fields_equal
    __hash__ = identity_hash

    def on_grid(self, grid_nm: np.ndarray) -> tuple[int, int, np.ndarray]:
        """(i0, j0, D): the matrix bilinear at the points of `grid_nm` within its wavelengths, D's rows starting at
        grid point i0, its columns at j0; D is empty where fewer than 2 points of the grid fall within it."""
        grid_nm = np.asarray(grid_nm, np.float64)
        rows = (grid_nm >= self.wavelengths_in[0]) & (grid_nm <= self.wavelengths_in[-1])
        columns = (grid_nm >= self.wavelengths_out[0]) & (grid_nm <= self.wavelengths_out[-1])
        if rows.sum() < 2 or columns.sum() < 2:
            return 0, 0, np.zeros((0, 0))
        along_in = np.stack([np.interp(grid_nm[rows], self.wavelengths_in, column) for column in self.values.T], axis=1)
        table = np.stack([np.interp(grid_nm[columns], self.wavelengths_out, row) for row in along_in])
        return int(np.argmax(rows)), int(np.argmax(columns)), table


@dataclass(frozen=True)
class DonaldsonMatrix:
    """A Donaldson matrix as the fluorescent material takes it."""

    excitation: Spectrum  # a(λ_in)·Q: photons re-emitted (at any λ_out) per photon arriving at λ_in
    emission: Spectrum  # e(λ_out), the re-emitted photons' spectrum (shape only; a tabulated matrix's column totals)
    separability_error: float  # ‖M − rank-one M‖ / ‖M‖
    tabulated: TabulatedMatrix | None  # the matrix itself where it is not separable; None where it is


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


def donaldson_matrix(path: str | Path, name: str | None = None) -> DonaldsonMatrix:
    """The Donaldson matrix CSV at `path` in the material's form (see the module's text), or a SpectraceError naming
    the file: a row re-emitting more photons than arrive, or a matrix of zeros."""
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
    tabulated = None
    if error > SEPARABILITY_TOLERANCE:
        tabulated = TabulatedMatrix(wavelengths_in, wavelengths_out, matrix, str(path))
        emission = np.trapezoid(matrix, wavelengths_in, axis=0)
    else:
        emission = right[0] * np.sign(right[0][np.argmax(np.abs(right[0]))])
    where = str(path)
    return DonaldsonMatrix(
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
        tabulated=tabulated,
    )


def device_block(matrix: TabulatedMatrix, grid_nm: np.ndarray) -> np.ndarray | None:
    """The block kernels/fluorescence_matrix.cl reads (its layout is stated there) for `matrix` on the spectra
    table's 1 nm grid `grid_nm`, or None where the matrix holds fewer than 2 of the grid's points each way (nothing
    is re-emitted within the film's wavelengths)."""
    i0, j0, table = matrix.on_grid(grid_nm)
    if table.size == 0 or not np.any(table > 0.0):
        return None
    row_cells = 0.5 * (table[:, 1:] + table[:, :-1])  # the 1 nm cells' masses, trapezoid rule
    column_cells = 0.5 * (table[1:, :] + table[:-1, :]).T
    row_totals, column_totals = row_cells.sum(axis=1), column_cells.sum(axis=1)
    header = np.array([i0, table.shape[0], j0, table.shape[1]], np.float64)
    return np.concatenate(
        [header, table.ravel(), row_totals, column_totals, _cdfs(row_cells).ravel(), _cdfs(column_cells).ravel()]
    )


def _cdfs(cells: np.ndarray) -> np.ndarray:
    """Each line's CDF over its cells (one value more than cells, 0 to 1); a line of zeros stays zeros."""
    cdf = np.concatenate([np.zeros((cells.shape[0], 1)), np.cumsum(cells, axis=1)], axis=1)
    totals = cdf[:, -1:]
    normalised = np.divide(cdf, totals, out=np.zeros_like(cdf), where=totals > 0.0)
    normalised[totals[:, 0] > 0.0, -1] = 1.0
    return normalised
