"""Spectra from files, scene values and colour-science, resampled onto the common grid.

All sources share one rule: samples are joined linearly (as the kernels interpolate) and, outside the
measured range, the end values are held. Measured reflectances often stop at 400 or 700 nm; holding
the end value is the least surprising extrapolation, whereas zero would darken the deep-red end of
every red surface and invent a cut-off the material does not have.

CSV format: `#` comment lines (source, units), then a header row `wavelength_nm,<col>[,<col>...]`,
then rows of numbers with the wavelength in nm, strictly ascending.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from functools import cache
from numbers import Real
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from spectrace.errors import SpectraceError
from spectrace.io.input_files import regular_file
from spectrace.number_text import DECIMAL, NOT_FINITE
from spectrace.resources import spectra_dir
from spectrace.spectral.grid import GRID_MAX_NM, GRID_MIN_NM, resample_to_grid
from spectrace.spectral.illuminants import CIE_ILLUMINANT_PREFIX, cie_illuminant, cie_illuminant_names
from spectrace.spectral.spectrum import Spectrum, sampled_extension

if TYPE_CHECKING:
    import colour

WAVELENGTH_COLUMN = "wavelength_nm"
COMMENT_PREFIX = "#"
LIBRARY_COLUMN_SEPARATOR = ":"


# ---------------------------------------------------------------- shared validation


def _spectrum_from_samples(
    wavelengths_nm: Sequence[float], values: Sequence[float], name: str, source: str, where: str
) -> Spectrum:
    """Checks what holds for the samples as a whole (per-sample checks name their own line or entry)."""
    if len(wavelengths_nm) < 2:
        raise SpectraceError(f"a spectrum needs at least 2 samples, got {len(wavelengths_nm)}", where=where)
    lowest, highest = wavelengths_nm[0], wavelengths_nm[-1]
    if highest < GRID_MIN_NM or lowest > GRID_MAX_NM:
        raise SpectraceError(
            f"wavelengths {lowest:g}..{highest:g} nm miss the {GRID_MIN_NM:g}..{GRID_MAX_NM:g} nm range"
            " entirely (micrometres instead of nanometres?)",
            where=where,
        )
    return Spectrum(
        resample_to_grid(np.array(wavelengths_nm), np.array(values)),
        name=name,
        source=source,
        extension=sampled_extension(np.array(wavelengths_nm), np.array(values)),
    )


def _parse_number(text: str, what: str, where: str) -> float:
    """A number of a CSV or a spectrum string, as spectrace.number_text reads numbers; nan and inf are recognised
    only to say that they are not finite."""
    text = text.strip()
    if NOT_FINITE.fullmatch(text):
        raise SpectraceError(f"{what} is {text}; spectra must be finite", where=where)
    if not DECIMAL.fullmatch(text):
        hint = ": '_' is not a digit separator here" if "_" in text and DECIMAL.fullmatch(text.replace("_", "")) else ""
        raise SpectraceError(f"'{text}' is not a number ({what}){hint}", where=where)
    number = float(text)
    if not math.isfinite(number):  # e.g. 1e999
        raise SpectraceError(f"{what} is {text}, beyond the range of a float; spectra must be finite", where=where)
    return number


def _check_ascending(previous_nm: float | None, wavelength_nm: float, where: str) -> None:
    if previous_nm is not None and not wavelength_nm > previous_nm:
        raise SpectraceError(
            f"wavelengths must be strictly ascending: {wavelength_nm:g} nm follows {previous_nm:g} nm", where=where
        )


# ---------------------------------------------------------------- CSV files


@dataclass(frozen=True)
class _CsvTable:
    path: Path
    columns: list[str]  # data columns, after wavelength_nm
    rows: list[tuple[int, list[str]]]  # (1-based line number, fields) of every data row


def _read_csv_table(path: Path) -> _CsvTable:
    regular_file(path, what="spectrum file")
    try:
        # utf-8-sig: a byte order mark (spreadsheets on Windows write one) is not part of the header.
        lines = path.read_text(encoding="utf-8-sig").splitlines()
    except UnicodeDecodeError as error:
        problem = f"not a UTF-8 text file (byte 0x{error.object[error.start]:02x} at offset {error.start})"
        raise SpectraceError(f"cannot read spectrum file: {problem}", where=str(path)) from None
    except OSError as error:
        raise SpectraceError(f"cannot read spectrum file: {error.strerror or error}", where=str(path)) from None

    header: list[str] | None = None
    rows: list[tuple[int, list[str]]] = []
    for line_number, line in enumerate(lines, start=1):
        stripped = line.strip()
        if not stripped or stripped.startswith(COMMENT_PREFIX):
            continue
        fields = [field.strip() for field in stripped.split(",")]
        if header is None:
            if fields[0] != WAVELENGTH_COLUMN or len(fields) < 2:
                raise SpectraceError(
                    f"header must be '{WAVELENGTH_COLUMN},<column>[,<column>...]', got '{stripped}'",
                    where=f"{path}:{line_number}",
                )
            repeated = next((name for i, name in enumerate(fields) if name in fields[:i]), None)
            if repeated is not None:
                # Which of the two a scene's `column` would pick is a guess; the file must say.
                raise SpectraceError(f"column '{repeated}' appears twice in the header", where=f"{path}:{line_number}")
            header = fields
        else:
            rows.append((line_number, fields))
    if header is None:
        raise SpectraceError(f"no header row '{WAVELENGTH_COLUMN},<column>...' found", where=str(path))
    return _CsvTable(path=path, columns=header[1:], rows=rows)


def _pick_column(table: _CsvTable, column: str | None, where: str) -> str:
    if column is None:
        if len(table.columns) > 1:
            raise SpectraceError(
                f"the file has several columns ({', '.join(table.columns)}); name the one to use", where=where
            )
        return table.columns[0]
    if column not in table.columns:
        raise SpectraceError(f"unknown column '{column}' (available: {', '.join(table.columns)})", where=where)
    return column


def load_spectrum_csv(path: str | Path, column: str | None = None, name: str | None = None) -> Spectrum:
    """One column of a spectrum CSV, linearly interpolated onto the grid with the end values held outside.

    `column` is required when the file has more than one data column. Errors name the file, and the
    line for a bad row.
    """
    path = Path(path)
    table = _read_csv_table(path)
    chosen = _pick_column(table, column, where=str(path))
    column_index = 1 + table.columns.index(chosen)
    width = 1 + len(table.columns)

    wavelengths_nm: list[float] = []
    values: list[float] = []
    for line_number, fields in table.rows:
        where = f"{path}:{line_number}"
        if len(fields) != width:
            raise SpectraceError(f"expected {width} comma-separated fields, got {len(fields)}", where=where)
        wavelength_nm = _parse_number(fields[0], WAVELENGTH_COLUMN, where)
        _check_ascending(wavelengths_nm[-1] if wavelengths_nm else None, wavelength_nm, where)
        wavelengths_nm.append(wavelength_nm)
        values.append(_parse_number(fields[column_index], f"value in column '{chosen}'", where))

    default_name = path.stem if len(table.columns) == 1 else f"{path.stem}{LIBRARY_COLUMN_SEPARATOR}{chosen}"
    return _spectrum_from_samples(
        wavelengths_nm, values, name=name or default_name, source=f"{path} column {chosen}", where=str(path)
    )


# ---------------------------------------------------------------- values written in a scene


def _is_number(value: object) -> bool:
    return isinstance(value, Real) and not isinstance(value, bool)


def _pairs_from_text(text: str, where: str) -> list[tuple[float, float]]:
    pairs = []
    for entry in (item.strip() for item in text.split(",")):
        if not entry:
            continue  # tolerate a trailing comma
        wavelength_text, separator, value_text = entry.partition(":")
        if not separator:
            raise SpectraceError(f"expected 'wavelength_nm:value' entries, got '{entry}'", where=where)
        pairs.append(
            (
                _parse_number(wavelength_text.strip(), f"wavelength in '{entry}'", where),
                _parse_number(value_text.strip(), f"value in '{entry}'", where),
            )
        )
    return pairs


def _pairs_from_mapping(mapping: Mapping, where: str) -> list[tuple[float, float]]:
    pairs = []
    for key, value in mapping.items():
        wavelength_nm = float(key) if _is_number(key) else _parse_number(str(key), "wavelength key", where)
        if not _is_number(value):
            raise SpectraceError(f"value for wavelength '{key}' must be a number, got {value!r}", where=where)
        pairs.append((wavelength_nm, _finite(float(value), f"value for wavelength '{key}'", where)))
    return pairs


def _pairs_from_sequence(sequence: Sequence, where: str) -> list[tuple[float, float]]:
    pairs = []
    for index, pair in enumerate(sequence):
        if isinstance(pair, (str, bytes)) or not isinstance(pair, Sequence) or len(pair) != 2:
            raise SpectraceError(f"entry {index} must be a [wavelength_nm, value] pair, got {pair!r}", where=where)
        if not all(_is_number(item) for item in pair):
            raise SpectraceError(f"entry {index} must hold two numbers, got {pair!r}", where=where)
        pairs.append(
            (
                _finite(float(pair[0]), f"wavelength of entry {index}", where),
                _finite(float(pair[1]), f"value of entry {index}", where),
            )
        )
    return pairs


def _finite(number: float, what: str, where: str) -> float:
    if not math.isfinite(number):
        raise SpectraceError(f"{what} is {number}; spectra must be finite", where=where)
    return number


def parse_inline_spectrum(
    text_or_pairs: str | Sequence[Sequence[float]] | Mapping[str, float], where: str, name: str | None = None
) -> Spectrum:
    """A spectrum written in a scene: `"400:0.343, 500:0.7, 700:0.9"`, `[[400, 0.343], [500, 0.7]]`
    or `{"400": 0.343, "500": 0.7}` (wavelengths in nm, strictly ascending). Errors name `where`."""
    if isinstance(text_or_pairs, str):
        pairs = _pairs_from_text(text_or_pairs, where)
    elif isinstance(text_or_pairs, Mapping):
        pairs = _pairs_from_mapping(text_or_pairs, where)
    elif isinstance(text_or_pairs, Sequence):
        pairs = _pairs_from_sequence(text_or_pairs, where)
    else:
        raise SpectraceError(
            "a spectrum must be a 'wavelength_nm:value, ...' string, a list of [wavelength_nm, value] pairs"
            f" or a table of wavelength_nm = value, got {type(text_or_pairs).__name__}",
            where=where,
        )
    previous_nm = None
    for wavelength_nm, _ in pairs:
        _check_ascending(previous_nm, wavelength_nm, where)
        previous_nm = wavelength_nm
    return _spectrum_from_samples(
        [pair[0] for pair in pairs], [pair[1] for pair in pairs], name=name or where, source=where, where=where
    )


# ---------------------------------------------------------------- colour-science


def spectrum_from_colour(sd: colour.SpectralDistribution, name: str | None = None) -> Spectrum:
    """A colour-science spectral distribution on our grid.

    Joined linearly between its samples (not with the distribution's own interpolator: Sprague, the
    default for evenly spaced data, can overshoot below zero near sharp features), ends held.
    """
    import colour  # here, not at module import: it takes about a second

    if not isinstance(sd, colour.SpectralDistribution):
        raise TypeError(f"expected a colour.SpectralDistribution, got {type(sd).__name__}")
    label = name or str(sd.name)
    return _spectrum_from_samples(
        list(sd.wavelengths), list(sd.values), name=label, source=f"colour-science: {sd.name}", where=label
    )


# ---------------------------------------------------------------- the shipped library


def _library_files() -> dict[str, Path]:
    """Library CSV files by name: their path under spectra/ without the '.csv' (e.g. "cornell_box/light")."""
    root = spectra_dir()
    return {path.relative_to(root).with_suffix("").as_posix(): path for path in sorted(root.rglob("*.csv"))}


def _spectrum_columns(path: Path) -> list[str] | None:
    """The data columns of a spectrum CSV, or None for a CSV that is not a spectrum (another table)."""
    for line in path.read_text(encoding="utf-8").splitlines():
        stripped = line.strip()
        if stripped and not stripped.startswith(COMMENT_PREFIX):
            fields = [field.strip() for field in stripped.split(",")]
            return fields[1:] if fields[0] == WAVELENGTH_COLUMN and len(fields) > 1 else None
    return None


def list_library_spectra() -> list[str]:
    """Every name `library_spectrum` accepts: "<file>" for one-column files, "<file>:<column>" otherwise,
    then "cie:<illuminant>" for colour-science's CIE illuminants."""
    names = []
    for file_name, path in _library_files().items():
        columns = _spectrum_columns(path)
        if columns is None:
            continue
        if len(columns) == 1:
            names.append(file_name)
        else:
            names.extend(f"{file_name}{LIBRARY_COLUMN_SEPARATOR}{column}" for column in columns)
    names.extend(f"{CIE_ILLUMINANT_PREFIX}{illuminant}" for illuminant in cie_illuminant_names())
    names.extend(f"{COLORCHECKER_PREFIX}{patch}" for patch in colorchecker_patch_names())
    return names


# The 24 patches of the X-Rite ColorChecker as measured by N. Ohta (colour-science's "ColorChecker N Ohta",
# 380-780 nm every 5 nm), read from colour-science at load time.
COLORCHECKER_PREFIX = "colorchecker:"
COLORCHECKER_DATASET = "ColorChecker N Ohta"


def colorchecker_patch_names() -> list[str]:
    import colour

    return list(colour.SDS_COLOURCHECKERS[COLORCHECKER_DATASET].keys())


def colorchecker_reflectance(patch: str, where: str | None = None) -> Spectrum:
    import colour

    patches = colour.SDS_COLOURCHECKERS[COLORCHECKER_DATASET]
    if patch not in patches:
        raise SpectraceError(f"unknown ColorChecker patch '{patch}' (patches: {', '.join(patches)})", where=where)
    return spectrum_from_colour(patches[patch], name=f"{COLORCHECKER_PREFIX}{patch}")


@cache
def _load_library_spectrum(name: str, where: str | None) -> Spectrum:
    if name.casefold().startswith(CIE_ILLUMINANT_PREFIX):
        return cie_illuminant(name[len(CIE_ILLUMINANT_PREFIX) :], where=where)
    if name.casefold().startswith(COLORCHECKER_PREFIX):
        return colorchecker_reflectance(name[len(COLORCHECKER_PREFIX) :], where=where)

    file_name, _, column = name.partition(LIBRARY_COLUMN_SEPARATOR)
    files = _library_files()
    path = files.get(file_name)
    columns = _spectrum_columns(path) if path is not None else None
    if path is None or columns is None:
        raise SpectraceError(
            f"unknown library spectrum '{name}' (files: {', '.join(files) or 'none'}; or cie:<illuminant>)",
            where=where,
        )
    if column and column not in columns:
        raise SpectraceError(
            f"library spectrum '{name}': unknown column '{column}' (available: {', '.join(columns)})", where=where
        )
    if not column and len(columns) > 1:
        raise SpectraceError(
            f"library spectrum '{name}' has several columns; write '{file_name}:<column>' with one of"
            f" {', '.join(columns)}",
            where=where,
        )
    return load_spectrum_csv(path, column=column or None, name=name)


def library_spectrum(name: str, where: str | None = None) -> Spectrum:
    """A spectrum shipped with spectrace, by name: "cornell_box/reflectance:white" (file under spectra/
    without '.csv', then ':' and the column; the column may be left out for one-column files), or a CIE
    illuminant from colour-science, "cie:D65", "cie:A". `where` (a scene key) is named in errors."""
    return _load_library_spectrum(name.strip(), where)
