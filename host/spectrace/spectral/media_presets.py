"""Measured media for subsurface scattering: Jensen et al. 2001's table (spectra/media/jensen2001.csv) and
Narasimhan et al. 2006's (spectra/media/narasimhan2006.csv), the named media pbrt-v4 knows.

Both give coefficients in 1/mm at the red, green and blue of a colour camera. Jensen et al. give the reduced
scattering coefficient σs' = σs(1 − g): such a preset keeps σs' whatever phase function it is given,
σs = σs' / (1 − g), so g = 0 (the default) uses σs = σs' in an isotropic medium; by the similarity relation
(Wyman, Patterson & Wilson 1989) media of equal σs' look alike once light has scattered many times. Narasimhan et
al. give σs itself (they measure g apart), which such a preset keeps for any g. Each RGB triple becomes a smooth
spectrum whose linear sRGB is that triple (`coefficient_spectrum`).
"""

import csv
from dataclasses import dataclass
from functools import cache

import numpy as np

from spectrace.errors import SpectraceError
from spectrace.resources import spectra_dir
from spectrace.spectral.spectrum import Spectrum
from spectrace.spectral.uplift import uplift_reflectance

PRESETS_FILE = "media/jensen2001.csv"
# The second table: σs not reduced (its column sigma_s, where the first has sigma_s_prime).
UNREDUCED_PRESETS_FILE = "media/narasimhan2006.csv"


@dataclass(frozen=True)
class MediumPreset:
    name: str
    sigma_s_prime_per_mm: tuple[float, float, float]  # reduced scattering (σs itself where not `reduced`), R, G, B
    sigma_a_per_mm: tuple[float, float, float]
    reduced: bool = True


@cache
def medium_presets() -> dict[str, MediumPreset]:
    presets = {}
    for file, scattering in ((PRESETS_FILE, "sigma_s_prime"), (UNREDUCED_PRESETS_FILE, "sigma_s")):
        text = (spectra_dir() / file).read_text(encoding="utf-8")
        lines = [line for line in text.splitlines() if line and not line.startswith("#")]
        for row in csv.DictReader(lines):
            values = [float(row[f"{q}_{c}"]) for q in (scattering, "sigma_a") for c in "rgb"]
            presets[row["name"]] = MediumPreset(
                row["name"],
                (values[0], values[1], values[2]),
                (values[3], values[4], values[5]),
                reduced=scattering == "sigma_s_prime",
            )
    return presets


def coefficient_spectrum(rgb, name: str = "", where: str | None = None) -> Spectrum:
    """A smooth spectrum ≥ 0 with no upper bound whose linear sRGB under D65 is `rgb`: the bounded reflectance
    uplift (Jakob & Hanika 2019) of rgb / (2 max), times 2 max, as pbrt-v4's RGBUnboundedSpectrum does; halving
    keeps the fit away from the gamut's edge, where it would turn into a box."""
    values = np.asarray(rgb, np.float64)
    if values.shape != (3,) or not np.all(np.isfinite(values)) or np.any(values < 0):
        raise SpectraceError(f"expected 3 finite coefficients >= 0, got {list(np.ravel(rgb))}", where=where)
    peak = float(values.max())
    if peak == 0.0:
        return Spectrum.zeros(name=name)
    return uplift_reflectance(values / (2.0 * peak), where=where)[0].scaled(2.0 * peak, name=name)


def preset_coefficients(name: str, scale: float, g: float = 0.0, where: str | None = None) -> tuple[Spectrum, Spectrum]:
    """(σa, σs) of a preset in 1/scene unit for the Henyey–Greenstein asymmetry g: the table's 1/mm values times
    `scale`, the millimetres in one scene unit (1000 for a scene in metres), with σs = σs' / (1 − g) for a table of
    reduced coefficients."""
    presets = medium_presets()
    if name not in presets:
        raise SpectraceError(f"unknown medium preset '{name}' (presets: {', '.join(presets)})", where=where)
    preset = presets[name]
    sigma_a = coefficient_spectrum(preset.sigma_a_per_mm, name=f"{name} sigma_a", where=where)
    sigma_s = coefficient_spectrum(preset.sigma_s_prime_per_mm, name=f"{name} sigma_s", where=where)
    return sigma_a.scaled(scale), sigma_s.scaled(scale / (1.0 - g) if preset.reduced else scale)
