"""Perlin noise on the host (numpy), the same function as kernels/noise.cl's `perlin_noise`: Perlin 2002, "Improving
Noise" (the quintic fade 6t⁵ − 15t⁴ + 10t³, gradients from the twelve cube-edge directions by a 4-bit hash), as
pbrt-v4 defines it (Pharr, Jakob & Humphreys, 4th ed., 10.6.1 "Perlin Noise": lattice coordinates wrapped to 256,
hashed through Perlin's permutation), and its finite-difference gradient (pbrt-v4's DNoise). Unitless: points in
lattice units, values in about [−1, 1], 0 at every lattice point. Evaluated in float64 (the device in float32).

For what needs the noise where there is no device, such as tabulating a procedural medium on import."""

from __future__ import annotations

import numpy as np

# Ken Perlin's permutation of 0..255 (kernels/noise.cl's NOISE_PERMUTATION).
PERMUTATION = np.array(
    [151, 160, 137, 91, 90, 15, 131, 13, 201, 95, 96, 53, 194, 233, 7, 225, 140, 36, 103, 30, 69, 142, 8, 99, 37,
     240, 21, 10, 23, 190, 6, 148, 247, 120, 234, 75, 0, 26, 197, 62, 94, 252, 219, 203, 117, 35, 11, 32, 57, 177,
     33, 88, 237, 149, 56, 87, 174, 20, 125, 136, 171, 168, 68, 175, 74, 165, 71, 134, 139, 48, 27, 166, 77, 146,
     158, 231, 83, 111, 229, 122, 60, 211, 133, 230, 220, 105, 92, 41, 55, 46, 245, 40, 244, 102, 143, 54, 65, 25,
     63, 161, 1, 216, 80, 73, 209, 76, 132, 187, 208, 89, 18, 169, 200, 196, 135, 130, 116, 188, 159, 86, 164, 100,
     109, 198, 173, 186, 3, 64, 52, 217, 226, 250, 124, 123, 5, 202, 38, 147, 118, 126, 255, 82, 85, 212, 207, 206,
     59, 227, 47, 16, 58, 17, 182, 189, 28, 42, 223, 183, 170, 213, 119, 248, 152, 2, 44, 154, 163, 70, 221, 153,
     101, 155, 167, 43, 172, 9, 129, 22, 39, 253, 19, 98, 108, 110, 79, 113, 224, 232, 178, 185, 112, 104, 218, 246,
     97, 228, 251, 34, 242, 193, 238, 210, 144, 12, 191, 179, 162, 241, 81, 51, 145, 235, 249, 14, 239, 107, 49,
     192, 214, 31, 181, 199, 106, 157, 184, 84, 204, 176, 115, 121, 50, 45, 127, 4, 150, 254, 138, 236, 205, 93,
     222, 114, 67, 29, 24, 72, 243, 141, 128, 195, 78, 66, 215, 61, 156, 180],
    np.int64,
)  # fmt: skip
# Each 4-bit code's gradient (the hash's low four bits): u is the offset's x for codes below 8 and 12, 13, else its
# y; v is its y below 4 and 12, 13, else its z; bit 0 negates u, bit 1 v. The gradient is then the vector of those
# signed picks: Perlin's twelve edge directions, and four of them again.
_CODES = np.arange(16)
GRADIENTS = np.zeros((16, 3))
GRADIENTS[_CODES, np.where((_CODES < 8) | (_CODES == 12) | (_CODES == 13), 0, 1)] += np.where(_CODES & 1, -1.0, 1.0)
GRADIENTS[_CODES, np.where((_CODES < 4) | (_CODES == 12) | (_CODES == 13), 1, 2)] += np.where(_CODES & 2, -1.0, 1.0)
# pbrt-v4's DNoise: forward differences over this step (lattice units).
GRADIENT_STEP = 0.01


def noise(p: np.ndarray) -> np.ndarray:
    """Perlin noise at points p (..., 3) in lattice units."""
    # pbrt-v4 takes coordinates modulo 2³⁰ first, so that far points still have a lattice cell.
    p = np.fmod(np.asarray(p, np.float64), float(1 << 30))
    cell = np.floor(p)
    d = p - cell
    index = cell.astype(np.int64)
    fade = d * d * d * (d * (d * 6.0 - 15.0) + 10.0)
    corners = []
    for corner in np.ndindex(2, 2, 2):
        offset = np.asarray(corner)
        x, y, z = np.moveaxis((index + offset) & 255, -1, 0)
        code = PERMUTATION[(PERMUTATION[(PERMUTATION[x] + y) & 255] + z) & 255] & 15
        gradient = GRADIENTS[code]
        corners.append(
            gradient[..., 0] * (d[..., 0] - offset[0])
            + gradient[..., 1] * (d[..., 1] - offset[1])
            + gradient[..., 2] * (d[..., 2] - offset[2])
        )
    fx, fy, fz = np.moveaxis(fade, -1, 0)
    # The kernel's order of blends: along x, then y, then z.
    x00 = corners[0] + fx * (corners[4] - corners[0])
    x10 = corners[2] + fx * (corners[6] - corners[2])
    x01 = corners[1] + fx * (corners[5] - corners[1])
    x11 = corners[3] + fx * (corners[7] - corners[3])
    y0 = x00 + fy * (x10 - x00)
    y1 = x01 + fy * (x11 - x01)
    return y0 + fz * (y1 - y0)


def noise_gradient(p: np.ndarray) -> np.ndarray:
    """pbrt-v4's DNoise at points p (..., 3): (noise(p + h eᵢ) − noise(p)) / h for each axis, h = GRADIENT_STEP."""
    p = np.asarray(p, np.float64)
    centre = noise(p)
    steps = np.eye(3) * GRADIENT_STEP
    return np.stack([(noise(p + step) - centre) / GRADIENT_STEP for step in steps], axis=-1)
