"""The one wavelength grid every spectrum lives on: 360..830 nm in 1 nm steps (471 samples).

The kernels look a spectrum up by linear interpolation between grid samples, so the integral of a
spectrum (or of a product of spectra) is the trapezoid rule on this grid; `trapezoid_weights_nm`
gives that rule as per-sample weights so integrals become dot products.
"""

import numpy as np

GRID_MIN_NM = 360.0
GRID_MAX_NM = 830.0
GRID_STEP_NM = 1.0
GRID_NM = np.arange(360, 831, dtype=np.float64)
GRID_SIZE = GRID_NM.size  # 471

assert round((GRID_MAX_NM - GRID_MIN_NM) / GRID_STEP_NM) + 1 == GRID_SIZE


def _trapezoid_weights() -> np.ndarray:
    weights = np.full(GRID_SIZE, GRID_STEP_NM)
    weights[[0, -1]] = 0.5 * GRID_STEP_NM
    weights.setflags(write=False)
    return weights


TRAPEZOID_WEIGHTS_NM = _trapezoid_weights()


def integrate_on_grid(values: np.ndarray) -> np.ndarray:
    """Trapezoid integral over the grid (units: those of `values` times nm); works on the last axis."""
    return np.asarray(values, dtype=np.float64) @ TRAPEZOID_WEIGHTS_NM


def resample_to_grid(wavelengths_nm: np.ndarray, values: np.ndarray) -> np.ndarray:
    """Linear interpolation of (ascending) samples onto the grid; outside the samples the end values are held."""
    # np.interp holds the first/last value beyond the sampled range, which is the extrapolation we want.
    return np.interp(GRID_NM, np.asarray(wavelengths_nm, np.float64), np.asarray(values, np.float64))
