"""Compact texel storage: how each value of a texture is held in the texel buffer (Texture.storage, read by
kernels/texture.cl), chosen per texture where it is exact or within a measured bound, float32 otherwise.

- 8- or 16-bit unsigned normalised integers (k standing for k / 255, k / 65535) for data textures (scalars such as
  roughness, opacity and heights; normal maps) whose values are all such codes, as a raw 8- or 16-bit file gives:
  exact at level 0. A pyramid's coarser levels (averages) are rounded to the nearest code, within half a code step,
  as the file's own quantisation.
- Half floats for the rest that tolerate them, and for any texture whose values are all halves (an OpenEXR stored
  in half: exact). Other data textures stay float: a float height map, since a bump map differentiates it. Sigmoid
  coefficients in their dimensionless form (t = (λ − centre) / half span; in powers of λ in nm, half coefficients
  are off by up to ΔE2000 5.4), when they all fit in half's range: colour difference to the float texel at most
  ΔE2000 0.32 over the RGB cube, 0.09 in photographs (docs/textures.md, Memory). Emission RGB and spectral bands
  whose largest value lies in [2^-4, 65504]: each value within a relative 2^-11, or (below half's normal range,
  2^10 times darker than the brightest or more) within 2^-25 absolute; ΔE2000 at most 0.06 for emission images.

The choice depends only on the values, so a texture is stored alike in every scene and render.
"""

import numpy as np

from spectrace.core.contract import (
    SIGMOID_CENTRE_NM,
    SIGMOID_HALF_SPAN_NM,
    STORAGE_FLOAT,
    STORAGE_HALF,
    STORAGE_UNORM8,
    STORAGE_UNORM16,
    TEXEL_SCALAR,
    TEXEL_SIGMOID,
    TEXEL_VECTOR,
)

HALF_MAX = 65504.0
# The smallest largest value an emission or spectral texture stored in half may have: below it, too many of its
# values would lie under half's normal range (2^-14), where half keeps fewer significant bits.
HALF_LEAST_PEAK = 2.0**-4
# Beyond this the kernel takes a sigmoid's argument for ±infinity (kernels/rgb_spectrum.cl): the saturated black and
# white texels' coefficients (0, 0, ±1e6) are stored as (0, 0, ±HALF_MAX), which stays beyond it.
SIGMOID_SATURATED = 1.0e4
BYTES = {STORAGE_FLOAT: 4, STORAGE_HALF: 2, STORAGE_UNORM8: 1, STORAGE_UNORM16: 2}
_UNORM = {STORAGE_UNORM8: (255, np.uint8), STORAGE_UNORM16: (65535, np.uint16)}


def _codes_exact(values: np.ndarray, levels: int) -> bool:
    """Whether every value is k / levels for an integer k in [0, levels], as a float32 holds it."""
    values = np.asarray(values, np.float32)
    if values.size == 0 or values.min() < 0.0 or values.max() > 1.0:
        return False
    codes = np.rint(values.astype(np.float64) * levels)
    return bool(np.array_equal((codes / levels).astype(np.float32), values))


def _half_exact(values: np.ndarray) -> bool:
    values = np.asarray(values, np.float32)
    return bool(np.all(np.abs(values) <= HALF_MAX)) and np.array_equal(values.astype(np.float16), values)


def data_storage(values: np.ndarray) -> int:
    """The storage of a data texture (TEXEL_SCALAR, TEXEL_VECTOR) with these level-0 values: an exact one."""
    if _codes_exact(values, 255):
        return STORAGE_UNORM8
    if _codes_exact(values, 65535):
        return STORAGE_UNORM16
    return STORAGE_HALF if _half_exact(values) else STORAGE_FLOAT


def predicted_storage(texel_format: int, values: np.ndarray) -> int:
    """The storage a texture of these level-0 values (linear values, not yet converted) gets: exact for data
    textures, emission and bands; for sigmoid coefficients half, which `storage` may still turn to float once the
    coefficients are known (at most twice the bytes)."""
    if texel_format in (TEXEL_SCALAR, TEXEL_VECTOR):
        return data_storage(values)
    if texel_format == TEXEL_SIGMOID:
        return STORAGE_HALF
    peak = float(np.max(np.abs(values))) if np.size(values) else 0.0
    if HALF_LEAST_PEAK <= peak <= HALF_MAX or peak == 0.0 or _half_exact(values):
        return STORAGE_HALF
    return STORAGE_FLOAT


def dimensionless(coefficients: np.ndarray) -> np.ndarray:
    """Sigmoid coefficients (..., 3) of λ in nm -> those of t = (λ − centre) / half span: the same polynomial."""
    c = np.asarray(coefficients, np.float64)
    m, h = SIGMOID_CENTRE_NM, SIGMOID_HALF_SPAN_NM
    c0, c1, c2 = c[..., 0], c[..., 1], c[..., 2]
    return np.stack([c0 * h * h, (2.0 * c0 * m + c1) * h, (c0 * m + c1) * m + c2], axis=-1)


def _saturated(coefficients: np.ndarray) -> np.ndarray:
    c = coefficients
    return (c[..., 0] == 0.0) & (c[..., 1] == 0.0) & (np.abs(c[..., 2]) >= SIGMOID_SATURATED)


def storage(texel_format: int, levels: list[np.ndarray], values: np.ndarray) -> int:
    """The storage of a texture's device levels (as device_texels gives them: sigmoid coefficients in nm, ...),
    `values` its level-0 linear values."""
    storage = predicted_storage(texel_format, values)
    if texel_format == TEXEL_SIGMOID:
        for level in levels:
            c = dimensionless(level)
            if float(np.max(np.abs(np.where(_saturated(level)[..., None], 0.0, c)), initial=0.0)) > HALF_MAX:
                return STORAGE_FLOAT
    return storage


def encode(texel_format: int, storage: int, levels: list[np.ndarray]) -> np.ndarray:
    """The stored values of every level, one after the other, as bytes (little-endian)."""
    parts = []
    for level in levels:
        level = np.asarray(level, np.float64)
        if storage in _UNORM:
            top, dtype = _UNORM[storage]
            parts.append(np.clip(np.rint(level * top), 0, top).astype(f"<u{np.dtype(dtype).itemsize}").ravel())
        elif storage == STORAGE_HALF:
            if texel_format == TEXEL_SIGMOID:
                saturated = _saturated(level)
                sign = np.sign(level[..., 2])
                level = dimensionless(level)
                level[saturated] = 0.0
                level[..., 2] = np.where(saturated, sign * HALF_MAX, level[..., 2])
            parts.append(level.astype("<f2").ravel())
        else:
            parts.append(level.astype("<f4").ravel())
    return np.concatenate(parts).view(np.uint8)
