"""Measured complex indices of refraction η(λ) + i k(λ) of metals, shipped in spectra/metals/ (sources in
spectra/metals/README.md), for conductor materials."""

from spectrace.errors import SpectraceError
from spectrace.spectral.spectrum import Spectrum
from spectrace.spectral.spectrum_io import library_spectrum

# The four metals most scenes use; each name below is also a file spectra/metals/<name>.csv.
COMMON_METALS = ("Au", "Ag", "Cu", "Al")
# Every conductor `material` name Mitsuba 3 knows (its data/ior/<name>.eta.spd files), keyed by Mitsuba's own
# spelling; all are file-safe, so the key is the file name.
MITSUBA_MEASURED = (
    "a-C", "Ag", "Al", "AlAs", "AlAs_palik", "AlSb", "AlSb_palik", "Au", "Be", "Be_palik", "Cr", "CsI",
    "CsI_palik", "Cu", "Cu2O", "Cu2O_palik", "CuO", "CuO_palik", "Cu_palik", "d-C", "d-C_palik", "Hg", "HgTe",
    "HgTe_palik", "Hg_palik", "Ir", "Ir_palik", "K", "K_palik", "Li", "Li_palik", "MgO", "MgO_palik", "Mo",
    "Mo_palik", "Na_palik", "Nb", "Nb_palik", "Ni_palik", "Rh", "Rh_palik", "Se", "Se-e", "Se-e_palik",
    "Se_palik", "SiC", "SiC_palik", "SnTe", "SnTe_palik", "Ta", "Ta_palik", "Te", "Te-e", "Te-e_palik",
    "Te_palik", "ThF4", "ThF4_palik", "TiC", "TiC_palik", "TiN", "TiN_palik", "TiO2", "TiO2-e", "TiO2-e_palik",
    "TiO2_palik", "V_palik", "VC", "VC_palik", "VN", "VN_palik", "W",
)  # fmt: skip
# Mitsuba's "none": η = 0, k = 1, whose Fresnel reflectance is 1 at every angle and wavelength.
PERFECT_MIRROR = "none"
METALS = (*COMMON_METALS, *(m for m in MITSUBA_MEASURED if m not in COMMON_METALS), PERFECT_MIRROR)


def metal_ior(metal: str, where: str | None = None) -> tuple[Spectrum, Spectrum]:
    """(η, k) of `metal` (one of METALS: Mitsuba 3's conductor names) on the renderer's grid."""
    if metal not in METALS:
        raise SpectraceError(f"unknown metal '{metal}' (known: {', '.join(METALS)})", where=where)
    if metal == PERFECT_MIRROR:
        return Spectrum.constant(0.0, name="none:eta"), Spectrum.constant(1.0, name="none:k")
    return library_spectrum(f"metals/{metal}:eta"), library_spectrum(f"metals/{metal}:k")


def metal_names_doc() -> str:
    """The `metal` names as the docs' tables write a key's type."""
    return ", ".join(f'`"{m}"`' for m in METALS[:-1]) + f' or `"{METALS[-1]}"`'
