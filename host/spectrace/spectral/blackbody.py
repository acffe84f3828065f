"""Planck's law for the spectral radiance of a black body."""

from dataclasses import dataclass

import numpy as np

from spectrace.spectral.grid import GRID_NM
from spectrace.spectral.spectrum import Extension, Spectrum

# CODATA 2018 exact values (SI).
PLANCK_CONSTANT = 6.62607015e-34  # J s
SPEED_OF_LIGHT = 299792458.0  # m/s
BOLTZMANN_CONSTANT = 1.380649e-23  # J/K
WIEN_DISPLACEMENT = 2.897771955e-3  # m K


def planck_radiance(wavelength_nm: np.ndarray, temperature_k: float) -> np.ndarray:
    """Spectral radiance of a black body in W/(m² sr nm)."""
    lam = np.asarray(wavelength_nm, float) * 1e-9
    exponent = PLANCK_CONSTANT * SPEED_OF_LIGHT / (lam * BOLTZMANN_CONSTANT * temperature_k)
    per_metre = 2.0 * PLANCK_CONSTANT * SPEED_OF_LIGHT**2 / lam**5 / np.expm1(exponent)
    return per_metre * 1e-9


def blackbody(temperature_k: float) -> Spectrum:
    """A black body's spectral shape, normalised so that its peak (Wien's λ_max = b/T, even when it lies outside
    360–830 nm) is 1, as pbrt-v4 does: absolute values (~10⁷ W/(m² sr nm) at 5500 K) are rarely what a scene
    wants; give the scale separately."""
    peak = planck_radiance(np.array([WIEN_DISPLACEMENT / temperature_k * 1e9]), temperature_k)[0]
    extension = Extension(0.0, np.inf, NormalisedPlanckCurve(temperature_k, peak))
    return Spectrum(
        planck_radiance(GRID_NM, temperature_k) / peak, name=f"blackbody {temperature_k:g} K", extension=extension
    )


@dataclass(frozen=True)
class NormalisedPlanckCurve:
    """nm -> Planck's radiance at `temperature_k` divided by `peak` (a plain dataclass, not a closure, so that
    scenes pickle)."""

    temperature_k: float
    peak: float

    def __call__(self, nm: np.ndarray) -> np.ndarray:
        return planck_radiance(nm, self.temperature_k) / self.peak
