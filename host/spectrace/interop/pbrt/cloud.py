"""pbrt-v4's `cloud` medium (Pharr, Jakob & Humphreys, 4th ed., 11.4.2: a procedural density from Perlin noise over
the box p0–p1 of the medium's space, 0 outside it) tabulated as a density grid.

The density at a point p of medium space: pp = frequency · p; with wispiness w > 0, pp is moved twice by the noise's
gradient, pp += 0.05 w 2⁻ⁱ ∇noise(10 · 1.99ⁱ pp) for i = 0, 1; then d = Σ_{i<5} 2⁻⁽ⁱ⁺¹⁾ noise(1.99ⁱ pp), and
ρ = clamp(clamp((1 − p_y) · 4.5 · density · d, 0, 1) + 2 max(0, ½ − p_y), 0, 1). Unitless, in [0, 1]: σa and σs
are multiplied by it, and pbrt-v4's majorant is σt itself.

spectrace has no procedural medium on the device, so the import samples ρ at the voxel centres of a grid over the
box (trilinear between them, as every density grid). Its resolution along an axis is SAMPLES_PER_CELL samples per
lattice cell of the finest noise the density reads (frequency · 10 · 1.99 with wispiness, frequency · 1.99⁴
without) over the box's extent along that axis, at most MAX_CLOUD_VOXELS voxels in all (scaled down evenly, with a
warning, when more would be needed)."""

from __future__ import annotations

import math

import numpy as np

from spectrace.textures.perlin import noise, noise_gradient

# Samples per lattice cell of the finest noise: Perlin noise is 0 at every lattice point and swings between them,
# so a cell is about its shortest period. A sine sampled 4 times a period is interpolated linearly within
# 1 − cos(π/4) ≈ 29 % of its amplitude, but the finest octave weighs 1/32 of the sum (measured along rays: 0.5–1.6 %
# of the full density, tests/interop/test_pbrt_cloud.py).
SAMPLES_PER_CELL = 4
# The most voxels a tabulated cloud gets (8 MB of float32, some tens of seconds of numpy): pbrt-v4's own clouds
# scene (frequency 5, wispiness 1 over the unit box) would want 398 an axis and gets 128, 1.3 samples a cell of its
# finest warp and 26 a cell of its coarsest octave, which carries half of the noise's weight.
MAX_CLOUD_VOXELS = 128**3
# Points evaluated at once (bounds the temporary arrays to some tens of MB).
_CHUNK = 1 << 18

OCTAVES = 5
WARP_STEPS = 2
LACUNARITY = 1.99


def cloud_density(p: np.ndarray, density: float = 1.0, wispiness: float = 1.0, frequency: float = 5.0) -> np.ndarray:
    """pbrt-v4's CloudMedium density at points p (..., 3) of the medium's space."""
    p = np.asarray(p, np.float64)
    pp = frequency * p
    if wispiness > 0:
        omega, scale = 0.05 * wispiness, 10.0
        for _ in range(WARP_STEPS):
            pp = pp + omega * noise_gradient(scale * pp)
            omega *= 0.5
            scale *= LACUNARITY
    d = np.zeros(p.shape[:-1])
    omega, scale = 0.5, 1.0
    for _ in range(OCTAVES):
        d += omega * noise(scale * pp)
        omega *= 0.5
        scale *= LACUNARITY
    height = p[..., 1]
    d = np.clip((1.0 - height) * 4.5 * density * d, 0.0, 1.0)
    d += 2.0 * np.maximum(0.0, 0.5 - height)
    return np.clip(d, 0.0, 1.0)


def finest_frequency(wispiness: float, frequency: float) -> float:
    """Lattice cells per unit of medium space of the finest noise the density reads."""
    warp = 10.0 * LACUNARITY ** (WARP_STEPS - 1) if wispiness > 0 else 0.0
    return abs(frequency) * max(LACUNARITY ** (OCTAVES - 1), warp)


def cloud_resolution(
    p0, p1, wispiness: float, frequency: float, max_voxels: int | None = None
) -> tuple[list[int], bool]:
    """([nx, ny, nz], whether the voxel cap lowered it): SAMPLES_PER_CELL samples per finest lattice cell along
    each axis of the box, each at least 2; when the product passes max_voxels (default MAX_CLOUD_VOXELS) all three
    shrink by one factor."""
    max_voxels = MAX_CLOUD_VOXELS if max_voxels is None else max_voxels
    extent = np.abs(np.asarray(p1, np.float64) - np.asarray(p0, np.float64))
    wanted = [max(2, math.ceil(SAMPLES_PER_CELL * finest_frequency(wispiness, frequency) * e)) for e in extent]
    if math.prod(wanted) <= max_voxels:
        return wanted, False
    factor = (max_voxels / math.prod(wanted)) ** (1.0 / 3.0)
    resolution = [max(2, math.floor(n * factor)) for n in wanted]
    while math.prod(resolution) > max_voxels:
        largest = resolution.index(max(resolution))
        resolution[largest] -= 1
    return resolution, True


def voxel_centres(p0, p1, resolution: list[int]) -> np.ndarray:
    """The voxel centres (nz, ny, nx, 3) of a grid of `resolution` over the box p0–p1 (x fastest)."""
    low, high = np.asarray(p0, np.float64), np.asarray(p1, np.float64)
    axes = [low[a] + (np.arange(n) + 0.5) / n * (high[a] - low[a]) for a, n in enumerate(resolution)]
    z, y, x = np.meshgrid(axes[2], axes[1], axes[0], indexing="ij")
    return np.stack([x, y, z], axis=-1)


def tabulate_cloud(p0, p1, resolution: list[int], density: float, wispiness: float, frequency: float) -> np.ndarray:
    """The density at the voxel centres, float32 (nz, ny, nx)."""
    centres = voxel_centres(p0, p1, resolution).reshape(-1, 3)
    values = np.empty(len(centres), np.float32)
    for start in range(0, len(centres), _CHUNK):
        chunk = centres[start : start + _CHUNK]
        values[start : start + len(chunk)] = cloud_density(chunk, density, wispiness, frequency)
    nx, ny, nz = resolution
    return values.reshape(nz, ny, nx)
