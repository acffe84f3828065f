"""CIE illuminants on the grid: D65 from the table shipped in spectra/, A from its formula, the others from
colour-science's `SDS_ILLUMINANTS` (read when first asked for, not copied).

D65 is the white every RGB reflectance and emission is uplifted against, so a render or an import that has RGB
colours needs it, and A is the bundled scenes' lamp: the D65 table (colour-science's, written out unchanged) and
the A formula (grouped as colour-science's) keep colour-science, and the second or more it takes to import, out of
those processes with the same bits.

Tabulated illuminants (D65 and the other D series, F, LED, ... at 5 nm, most over 300..780 nm) are
interpolated linearly to 1 nm, as CIE 15:2004 recommends for the D illuminants, and their last value
is held beyond the table (780..830 nm for D65, where ybar is below 1.5e-5 of its peak). Illuminant A,
defined by a Planck formula, is computed at every grid wavelength instead.
Values keep CIE's relative scale (100 at 560 nm); `d65_normalised` rescales D65 to film Y = 1.
"""

from functools import cache

import numpy as np

from spectrace.errors import SpectraceError
from spectrace.resources import spectra_dir
from spectrace.spectral.colorimetry import normalised_to_unit_y
from spectrace.spectral.grid import GRID_NM, resample_to_grid
from spectrace.spectral.spectrum import Extension, Spectrum, sampled_extension

CIE_ILLUMINANT_PREFIX = "cie:"

# Illuminants read from a table under spectra/ (wavelength_nm, relative power) rather than from colour-science.
SHIPPED_ILLUMINANT_TABLES = {"D65": "illuminants/cie_d65.csv"}


@cache
def shipped_illuminant_table(canonical_name: str) -> tuple[np.ndarray, np.ndarray]:
    """The wavelengths (nm) and relative powers of a table in SHIPPED_ILLUMINANT_TABLES, as written (read-only)."""
    path = spectra_dir() / SHIPPED_ILLUMINANT_TABLES[canonical_name]
    lines = [
        line for line in path.read_text(encoding="utf-8").splitlines() if line.strip() and not line.startswith("#")
    ]
    table = np.array([[float(field) for field in line.split(",")] for line in lines[1:]], dtype=np.float64)
    if table.ndim != 2 or table.shape[1] != 2 or not np.all(np.diff(table[:, 0]) > 0):
        raise RuntimeError(f"{SHIPPED_ILLUMINANT_TABLES[canonical_name]} is not a table of ascending wavelengths")
    wavelengths, values = np.ascontiguousarray(table[:, 0]), np.ascontiguousarray(table[:, 1])
    wavelengths.setflags(write=False)
    values.setflags(write=False)
    return wavelengths, values


def _sampled_table(canonical_name: str) -> tuple[np.ndarray, np.ndarray]:
    if canonical_name in SHIPPED_ILLUMINANT_TABLES:
        return shipped_illuminant_table(canonical_name)
    import colour  # here, not at module import: it takes about a second

    sd = colour.SDS_ILLUMINANTS[canonical_name]
    return np.asarray(sd.wavelengths), np.asarray(sd.values)


def cie_illuminant_names() -> list[str]:
    """Names `cie_illuminant` accepts (colour-science's keys: "A", "D65", "FL2", "LED-B1", ...)."""
    import colour  # here, not at module import: it takes about a second

    return sorted(colour.SDS_ILLUMINANTS.keys())


@cache
def _cie_illuminant_values(canonical_name: str) -> np.ndarray:
    if canonical_name == "A":
        values = _illuminant_a(GRID_NM)
    else:
        values = resample_to_grid(*_sampled_table(canonical_name))
    assert values.shape == GRID_NM.shape
    values.setflags(write=False)
    return values


def cie_illuminant(name: str, where: str | None = None) -> Spectrum:
    """A CIE illuminant by name ("D65", "A", "FL2", case-insensitive), relative spectral power (100 at 560 nm)."""
    canonical_name = _canonical_name(name)
    if canonical_name is None:
        raise SpectraceError(
            f"unknown CIE illuminant '{name}' (available: {', '.join(cie_illuminant_names())})", where=where
        )
    return Spectrum(
        _cie_illuminant_values(canonical_name),
        name=f"{CIE_ILLUMINANT_PREFIX}{canonical_name}",
        source=_SOURCES.get(canonical_name, "colour-science SDS_ILLUMINANTS"),
        extension=_cie_illuminant_extension(canonical_name),
    )


_SOURCES = {"D65": "CIE 15:2004 Table T.1 (spectra/illuminants/cie_d65.csv)", "A": "CIE 15:2004 eq. (3.1)"}


def _canonical_name(name: str) -> str | None:
    folded = name.strip().casefold()
    shipped = {key.casefold(): key for key in (*SHIPPED_ILLUMINANT_TABLES, "A")}
    if folded in shipped:
        return shipped[folded]
    import colour  # here, not at module import: it takes about a second

    return {key.casefold(): key for key in colour.SDS_ILLUMINANTS}.get(folded)


# CIE 15:2004 eq. (3.1): illuminant A's relative spectral power, with c2 = 1.435e7 nm K and T = 2848 K.
_ILLUMINANT_A_C2_NM_K = 1.435e7
_ILLUMINANT_A_K = 2848.0


def _illuminant_a(wavelengths_nm: np.ndarray) -> np.ndarray:
    lam = np.asarray(wavelengths_nm, np.float64)
    # Grouped as colour-science's sd_CIE_standard_illuminant_A groups it, so that the values on the grid are its
    # bits (tests/cli/test_startup.py compares them) without importing it.
    return (
        100.0
        * (560.0 / lam) ** 5
        * (
            np.expm1(_ILLUMINANT_A_C2_NM_K / (_ILLUMINANT_A_K * 560.0))
            / np.expm1(_ILLUMINANT_A_C2_NM_K / (_ILLUMINANT_A_K * lam))
        )
    )


def _cie_illuminant_extension(canonical_name: str) -> Extension:
    """Illuminant A is a formula, defined at every wavelength; the others are their tables' range."""
    if canonical_name == "A":
        return Extension(0.0, np.inf, _illuminant_a)
    return sampled_extension(*_sampled_table(canonical_name))


@cache
def d65_normalised() -> Spectrum:
    """CIE D65 scaled so that its film Y is 1: the emission the sRGB white (1, 1, 1) stands for."""
    return normalised_to_unit_y(cie_illuminant("D65"), name="cie:D65 (film Y = 1)")
