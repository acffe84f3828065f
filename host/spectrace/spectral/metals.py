"""Measured complex indices of refraction η(λ) + i k(λ) of metals, shipped in spectra/metals/ (sources in
spectra/metals/README.md), for conductor materials."""

from spectrace.errors import SpectraceError
from spectrace.spectral.spectrum import Spectrum
from spectrace.spectral.spectrum_io import library_spectrum

METALS = ("Au", "Ag", "Cu", "Al")


def metal_ior(metal: str, where: str | None = None) -> tuple[Spectrum, Spectrum]:
    """(η, k) of `metal` ("Au", "Ag", "Cu" or "Al") on the renderer's grid."""
    if metal not in METALS:
        raise SpectraceError(f"unknown metal '{metal}' (known: {', '.join(METALS)})", where=where)
    return library_spectrum(f"metals/{metal}:eta"), library_spectrum(f"metals/{metal}:k")
