"""pbrt-v4's image infinite lights as spectrace environment maps.

pbrt-v4 stores an environment as a square image in Clarberg's equal-area octahedral mapping ("Fast Equal-Area
Mapping of the (Hemi)Sphere using SIMD", JGT 2008; pbrt-v4 section 3.8.3), +z of the light's frame at the square's
centre; spectrace's `envmap` is a latitude-longitude image with +y up (kernels/light_environment_map.cl). The importer
resamples the square into a latitude-longitude image in spectrace's world, with the light's transform (and the
importer's handedness mirror) applied, so the environment needs no transform of its own.
"""

from __future__ import annotations

import math

import numpy as np

from spectrace.spectral.colorimetry import LINEAR_SRGB_TO_XYZ


def sphere_to_square(directions: np.ndarray) -> np.ndarray:
    """(n, 2) points of [0, 1]² for (n, 3) unit directions: the equal-area octahedral map, with the exact arctangent
    where pbrt-v4 evaluates a minimax polynomial of it (they differ by under 1e-5)."""
    x, y, z = (np.abs(directions[:, i]) for i in range(3))
    r = np.sqrt(np.maximum(1.0 - z, 0.0))
    a, b = np.maximum(x, y), np.minimum(x, y)
    ratio = np.divide(b, a, out=np.zeros_like(a), where=a > 0)
    phi = np.arctan(ratio) * (2.0 / math.pi)
    phi = np.where(x < y, 1.0 - phi, phi)
    v = phi * r
    u = r - v
    south = directions[:, 2] < 0
    u, v = np.where(south, 1.0 - v, u), np.where(south, 1.0 - u, v)
    u = np.copysign(u, directions[:, 0])
    v = np.copysign(v, directions[:, 1])
    return np.stack([(u + 1.0) / 2.0, (v + 1.0) / 2.0], axis=1)


def square_to_sphere(points: np.ndarray) -> np.ndarray:
    """The inverse of `sphere_to_square`: (n, 3) unit directions for (n, 2) points of [0, 1]²."""
    u, v = 2.0 * points[:, 0] - 1.0, 2.0 * points[:, 1] - 1.0
    signed_distance = 1.0 - (np.abs(u) + np.abs(v))
    r = 1.0 - np.abs(signed_distance)
    phi = np.where(r == 0, 1.0, (np.abs(v) - np.abs(u)) / np.where(r == 0, 1.0, r) + 1.0) * (math.pi / 4.0)
    z = np.copysign(1.0 - r * r, signed_distance)
    ring = r * np.sqrt(np.maximum(2.0 - r * r, 0.0))
    return np.stack([np.copysign(np.cos(phi), u) * ring, np.copysign(np.sin(phi), v) * ring, z], axis=1)


def latitude_longitude_directions(height: int, width: int) -> np.ndarray:
    """(height, width, 3) directions of spectrace's envmap texel centres: θ = acos(y) down the rows, φ = atan2(x, −z)
    across the columns from −π (kernels/light_environment_map.cl)."""
    theta = (np.arange(height) + 0.5) / height * math.pi
    phi = (np.arange(width) + 0.5) / width * 2.0 * math.pi - math.pi
    sin_theta = np.sin(theta)[:, None]
    return np.stack(
        [
            sin_theta * np.sin(phi)[None, :],
            np.repeat(np.cos(theta)[:, None], width, 1),
            -sin_theta * np.cos(phi)[None, :],
        ],
        axis=-1,
    )


def bilinear(image: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Texels of an (h, w, c) image at (n, 2) points of [0, 1]² (x across, y down the rows), edges clamped."""
    height, width = image.shape[:2]
    x = np.clip(points[:, 0] * width - 0.5, 0.0, width - 1.0)
    y = np.clip(points[:, 1] * height - 0.5, 0.0, height - 1.0)
    x0, y0 = np.floor(x).astype(np.int64), np.floor(y).astype(np.int64)
    x1, y1 = np.minimum(x0 + 1, width - 1), np.minimum(y0 + 1, height - 1)
    fx, fy = (x - x0)[:, None], (y - y0)[:, None]
    top = image[y0, x0] * (1 - fx) + image[y0, x1] * fx
    bottom = image[y1, x0] * (1 - fx) + image[y1, x1] * fx
    return top * (1 - fy) + bottom * fy


def to_latitude_longitude(square: np.ndarray, spectrace_from_light: np.ndarray, height: int) -> np.ndarray:
    """The (height, 2 height, 3) latitude-longitude image of a square equal-area map whose light frame is turned into
    spectrace's world by the 3x3 `spectrace_from_light`."""
    directions = latitude_longitude_directions(height, 2 * height).reshape(-1, 3)
    in_light = directions @ np.linalg.inv(spectrace_from_light).T
    in_light /= np.linalg.norm(in_light, axis=1, keepdims=True)
    return bilinear(square, sphere_to_square(in_light)).reshape(height, 2 * height, -1).astype(np.float32)


def upper_illuminance(square: np.ndarray) -> float:
    """pbrt-v4's illuminance of a square map's +z hemisphere (its `illuminance` parameter's reference): the luminance
    of each texel whose centre lies above the horizon, times cos θ, times 2π / texels, as pbrt-v4 computes it (a
    texel's solid angle is 4π / texels, so this is half the physical illuminance; pbrt's images follow it)."""
    height, width = square.shape[:2]
    y, x = np.meshgrid((np.arange(height) + 0.5) / height, (np.arange(width) + 0.5) / width, indexing="ij")
    directions = square_to_sphere(np.stack([x.ravel(), y.ravel()], axis=1))
    luminance = square.reshape(-1, 3) @ LINEAR_SRGB_TO_XYZ[1]
    cosine = np.maximum(directions[:, 2], 0.0)
    return float((luminance * cosine).sum() * 2.0 * math.pi / (height * width))
