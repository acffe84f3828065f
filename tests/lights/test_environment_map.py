"""Environment maps: irradiance from a latitude-longitude map equals an independent quadrature over its texels.

The meter's estimate combines light sampling (the map's piecewise-constant pdf) and cosine sampling with MIS; a pdf
inconsistent with the sampling routine, or a wrong direction mapping, biases it away from the quadrature."""

import numpy as np
import pytest

from spectrace.engine.meters import IrradianceMeter, measure
from spectrace.io.exr import write_exr
from spectrace.scene import load_scene
from spectrace.scene.model import Camera, EnvironmentMap, Scene
from spectrace.spectral.grid import GRID_NM
from spectrace.spectral.uplift import uplift_illuminant

CAMERA = Camera(origin=(0.0, 0.0, -1.0), target=(0.0, 0.0, 0.0))


def _basis_at(wavelength_nm: float) -> np.ndarray:
    return np.array([np.interp(wavelength_nm, GRID_NM, uplift_illuminant(p).values) for p in np.eye(3)])


def _direction(u, v):
    """The documented convention: θ = v π from +y, φ = 2π u − π, φ = 0 looking along −z."""
    theta, phi = np.broadcast_arrays(v * np.pi, u * 2 * np.pi - np.pi)
    return np.stack([np.sin(theta) * np.sin(phi), np.cos(theta), -np.sin(theta) * np.cos(phi)], axis=-1)


def _quadrature_irradiance(rgb, scale, normal, wavelength_nm):
    return quadrature_irradiance(scale * rgb @ _basis_at(wavelength_nm), normal)


def quadrature_irradiance(radiance, normal, sub=24):
    """∫ L cos⁺ dω over the sphere of a map of (height, width) texel radiances, each texel split into sub × sub
    cells with their exact solid angles."""
    height, width = radiance.shape[:2]
    total = 0.0
    for row in range(height):
        v_edges = (row + np.arange(sub + 1) / sub) / height
        cell_solid = (np.cos(v_edges[:-1] * np.pi) - np.cos(v_edges[1:] * np.pi)) * (2 * np.pi / (width * sub))
        v_centres = (v_edges[:-1] + v_edges[1:]) / 2
        for column in range(width):
            u_centres = (column + (np.arange(sub) + 0.5) / sub) / width
            d = _direction(u_centres[None, :], v_centres[:, None])
            cos = np.clip(d @ np.asarray(normal, float), 0.0, None)
            total += radiance[row, column] * np.sum(cos * cell_solid[:, None])
    return total


def test_uniform_map_gives_pi_times_radiance(device):
    k = 0.7
    rgb = np.full((8, 16, 3), k, np.float32)
    scene = Scene(camera=CAMERA, width=1, height=1, shapes=[], lights=[EnvironmentMap(rgb, 1.0)])
    reading = measure(
        scene,
        IrradianceMeter((0.0, 0.0, 0.0), (0.2, 0.9, -0.3)),
        wavelengths_nm=[450.0, 600.0],
        streams=64,
        samples_per_item=32,
        device=device,
    )
    expected = np.pi * k * np.array([_basis_at(lam).sum() for lam in (450.0, 600.0)])
    assert np.all(np.abs(reading.spectral - expected) < 4 * reading.spectral_standard_error + 1e-4 * expected)
    assert np.all(reading.spectral_standard_error < 0.01 * expected)


@pytest.mark.parametrize("normal", [(0.0, 1.0, 0.0), (0.6, -0.2, -0.77), (-0.3, 0.1, 0.95)])
def test_structured_map_matches_quadrature(device, tmp_path, normal):
    rng = np.random.default_rng(4)
    rgb = rng.uniform(0.0, 0.3, (8, 16, 3)).astype(np.float32)
    rgb[1, 3] = (40.0, 30.0, 10.0)  # a small, bright "sun" the sampler must find
    rgb[5, 12] = (0.0, 5.0, 8.0)
    path = tmp_path / "sky.exr"
    write_exr(path, rgb, None, {})
    (tmp_path / "scene.toml").write_text(
        "[camera]\norigin = [0, 0, -1]\ntarget = [0, 0, 0]\nfov = 40\n[film]\nwidth = 1\nheight = 1\n"
        '[materials]\n[[lights]]\ntype = "envmap"\nfile = "sky.exr"\nscale = 0.5\n'
    )
    scene = load_scene(tmp_path / "scene.toml")
    normal = tuple(np.asarray(normal) / np.linalg.norm(normal))
    reading = measure(
        scene,
        IrradianceMeter((0.0, 0.0, 0.0), normal),
        wavelengths_nm=[550.0],
        streams=64,
        samples_per_item=64,
        device=device,
    )
    expected = _quadrature_irradiance(rgb, 0.5, normal, 550.0)
    value, standard_error = reading.spectral[0], reading.spectral_standard_error[0]
    assert standard_error < 0.02 * expected
    assert abs(value - expected) < 4 * standard_error + 1e-3 * expected, (value, expected, standard_error)
