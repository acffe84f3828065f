"""CIE illuminants on the grid, from colour-science's `SDS_ILLUMINANTS` (read at load time, not copied).

Tabulated illuminants (D65 and the other D series, F, LED, ... at 5 nm, most over 300..780 nm) are
interpolated linearly to 1 nm, as CIE 15:2004 recommends for the D illuminants, and their last value
is held beyond the table (780..830 nm for D65, where ybar is below 1.5e-5 of its peak). Illuminant A,
defined by a Planck formula, is computed at every grid wavelength instead.
Values keep CIE's relative scale (100 at 560 nm); `d65_normalised` rescales D65 to film Y = 1.
"""

from functools import cache

import numpy as np

from spectrace.errors import SpectraceError
from spectrace.spectral.colorimetry import normalised_to_unit_y
from spectrace.spectral.grid import GRID_MAX_NM, GRID_MIN_NM, GRID_NM, GRID_STEP_NM, resample_to_grid
from spectrace.spectral.spectrum import Extension, Spectrum, sampled_extension

CIE_ILLUMINANT_PREFIX = "cie:"


def cie_illuminant_names() -> list[str]:
    """Names `cie_illuminant` accepts (colour-science's keys: "A", "D65", "FL2", "LED-B1", ...)."""
    import colour  # here, not at module import: it takes about a second

    return sorted(colour.SDS_ILLUMINANTS.keys())


@cache
def _cie_illuminant_values(canonical_name: str) -> np.ndarray:
    import colour

    if canonical_name == "A":
        shape = colour.SpectralShape(GRID_MIN_NM, GRID_MAX_NM, GRID_STEP_NM)
        values = np.asarray(colour.sd_CIE_standard_illuminant_A(shape).values, dtype=np.float64)
    else:
        sd = colour.SDS_ILLUMINANTS[canonical_name]
        values = resample_to_grid(sd.wavelengths, sd.values)
    assert values.shape == GRID_NM.shape
    values.setflags(write=False)
    return values


def cie_illuminant(name: str, where: str | None = None) -> Spectrum:
    """A CIE illuminant by name ("D65", "A", "FL2", case-insensitive), relative spectral power (100 at 560 nm)."""
    import colour

    by_folded_name = {key.casefold(): key for key in colour.SDS_ILLUMINANTS}
    canonical_name = by_folded_name.get(name.strip().casefold())
    if canonical_name is None:
        raise SpectraceError(
            f"unknown CIE illuminant '{name}' (available: {', '.join(cie_illuminant_names())})", where=where
        )
    return Spectrum(
        _cie_illuminant_values(canonical_name),
        name=f"{CIE_ILLUMINANT_PREFIX}{canonical_name}",
        source="colour-science SDS_ILLUMINANTS",
        extension=_cie_illuminant_extension(canonical_name),
    )


# CIE 15:2004 eq. (3.1): illuminant A's relative spectral power, with c2 = 1.435e7 nm K and T = 2848 K.
_ILLUMINANT_A_C2_NM_K = 1.435e7
_ILLUMINANT_A_K = 2848.0


def _illuminant_a(wavelengths_nm: np.ndarray) -> np.ndarray:
    lam = np.asarray(wavelengths_nm, np.float64)
    return (
        100.0
        * (560.0 / lam) ** 5
        * np.expm1(_ILLUMINANT_A_C2_NM_K / (_ILLUMINANT_A_K * 560.0))
        / np.expm1(_ILLUMINANT_A_C2_NM_K / (_ILLUMINANT_A_K * lam))
    )


def _cie_illuminant_extension(canonical_name: str) -> Extension:
    """Illuminant A is a formula, defined at every wavelength; the others are their tables' range."""
    if canonical_name == "A":
        return Extension(0.0, np.inf, _illuminant_a)
    import colour

    sd = colour.SDS_ILLUMINANTS[canonical_name]
    return sampled_extension(np.asarray(sd.wavelengths), np.asarray(sd.values))


@cache
def d65_normalised() -> Spectrum:
    """CIE D65 scaled so that its film Y is 1: the emission the sRGB white (1, 1, 1) stands for."""
    return normalised_to_unit_y(cie_illuminant("D65"), name="cie:D65 (film Y = 1)")
