"""Piecewise-constant 2-D distributions over the unit square, the tables kernels/distribution_2d.cl samples: a
marginal CDF over rows, then each row's conditional CDF (Pharr, Jakob & Humphreys, "Physically Based Rendering",
4th ed., sec. A.5.6). The environment map draws directions with one, and so do the projector and the goniometric
light for their light paths."""

import numpy as np

NO_DISTRIBUTION = -1  # a Light row's `triangle` for a projector or goniometric light that draws uniformly


def piecewise_constant_2d(weights: np.ndarray) -> np.ndarray:
    """The (height + 1) + height·(width + 1) floats of the density ∝ `weights` (height, width), ≥ 0 with a positive
    sum: a cell's probability is its weight over the sum; a row of zeros gets an even conditional CDF (never drawn)."""
    height, width = weights.shape
    row_mass = weights.sum(axis=1)
    row_cdf = np.zeros((height, width + 1))
    row_cdf[:, 1:] = np.cumsum(weights, axis=1)
    row_cdf = np.divide(
        row_cdf, row_cdf[:, -1:], out=np.tile(np.linspace(0, 1, width + 1), (height, 1)), where=row_cdf[:, -1:] > 0
    )
    marginal = np.concatenate([[0.0], np.cumsum(row_mass)]) / row_mass.sum()
    marginal[-1] = 1.0
    row_cdf[:, -1] = 1.0
    return np.concatenate([marginal, row_cdf.ravel()]).astype(np.float32)


def add_distribution(weights: np.ndarray, out) -> int:
    """Puts the tables of `weights` in the texel buffer of LightRows `out` (four floats a texel, once: see
    LightRows.add_chunk); the first texel's index, which a Light row's `triangle` holds; NO_DISTRIBUTION when the
    weights are all zero."""
    weights = np.asarray(weights, np.float64)
    if not weights.sum() > 0:
        return NO_DISTRIBUTION
    floats = piecewise_constant_2d(weights)
    chunk = np.zeros((len(floats) + 3) // 4 * 4, np.float32)
    chunk[: len(floats)] = floats
    return out.add_chunk(chunk.reshape(-1, 4))
