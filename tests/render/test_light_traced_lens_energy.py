"""Energy through a glass sphere (a ball lens) from a distant light, light-traced, against an independent integral.

A distant light of irradiance E shines straight down (−z) on a smooth glass sphere (index n, radius r, centre
height z_c) over a diffuse screen z = 0 of albedo ρ. The camera is a point between the sphere and the screen looking
straight down, so the screen it sees is the square |x| ≤ X, |y| ≤ Y (X, Y from its field of view) and each pixel
covers the same area of it: the flux on that square is Φ = (π/ρ) Σ L_pixel · a_pixel, from the image alone.

The expected flux, with `max_depth = 4` (light → sphere → sphere → screen → camera: at most two refractions or one
reflection before the screen):
- the sunlit screen outside the sphere's shadow, E (4XY − πr²);
- over the sphere's aperture, each impact point (b, φ) of the disk of radius r: E · T(θ_i) · T'(θ_t) if the ray
  refracted in and out lands in the square, plus E · R(θ_i) if the ray reflected off the outside does, with the
  unpolarised Fresnel equations (the mean of the s and p reflectances at each interface; T' from inside the glass),
  the ray geometry traced here with numpy vectors (Snell's law in vector form), integrated by the midpoint rule.
The rays through the sphere's rim are deviated up to 2(θ_i − θ_t) ≈ 96° and miss the square, so the indicator
matters, and the focused light crosses the shadow: the test checks where the light goes as well as how much.
"""

from pathlib import Path

import numpy as np

import spectrace
from replica_agreement import spectrace_replicas
from scene_text import camera_film
from spectrace.engine.renderer import Renderer
from stats_toolkit import assert_within_standard_errors, mean_and_standard_error

IRRADIANCE, IOR, RADIUS, CENTRE_HEIGHT, ALBEDO = 2.0, 1.5, 0.05, 0.1, 0.5
CAMERA_HEIGHT, HALF_TAN = 0.04, 1.5  # the camera sees the square of half-width CAMERA_HEIGHT · HALF_TAN


def _scene(tmp_path: Path) -> Path:
    fov = np.degrees(2 * np.arctan(HALF_TAN))
    path = tmp_path / "ball_lens.toml"
    path.write_text(
        camera_film(
            origin=f"[0, 0, {CAMERA_HEIGHT}]",
            target="[0, 0, 0]",
            fov=fov,
            width="32",
            height="32",
            camera="up = [0, 1, 0]",
        )
        + f"""
[integrator]
type = "light"
max_depth = 4
rr_depth = 40

[sampler]
spp = 8
seed = 11

[materials.screen]
type = "diffuse"
reflectance = {{ value = {ALBEDO} }}

[materials.glass]
type = "dielectric"
ior = {IOR}

[[shapes]]
type = "rectangle"
material = "screen"
transform = [{{ scale = 0.065 }}]

[[shapes]]
type = "sphere"
material = "glass"
center = [0, 0, {CENTRE_HEIGHT}]
radius = {RADIUS}

[[lights]]
type = "distant"
direction = [0, 0, -1]
irradiance = {{ value = {IRRADIANCE} }}
""",
        encoding="utf-8",
    )
    return path


def _fresnel_reflectance(cos_i: np.ndarray, n_i: float, n_t: float) -> np.ndarray:
    sin_t = n_i / n_t * np.sqrt(np.maximum(0.0, 1 - cos_i**2))
    cos_t = np.sqrt(np.maximum(0.0, 1 - sin_t**2))
    r_s = ((n_i * cos_i - n_t * cos_t) / (n_i * cos_i + n_t * cos_t)) ** 2
    r_p = ((n_i * cos_t - n_t * cos_i) / (n_i * cos_t + n_t * cos_i)) ** 2
    return np.where(sin_t >= 1, 1.0, 0.5 * (r_s + r_p))


def _refract(d: np.ndarray, normal: np.ndarray, eta: float) -> np.ndarray:
    """Unit d through the interface whose unit normal faces against d, eta = n_from / n_to (no total reflection)."""
    cos_i = -np.sum(d * normal, axis=-1, keepdims=True)
    cos_t = np.sqrt(1 - eta**2 * (1 - cos_i**2))
    return eta * d + (eta * cos_i - cos_t) * normal


def _lands_in_view(origin: np.ndarray, direction: np.ndarray, half: tuple[float, float]) -> np.ndarray:
    down = direction[..., 2] < 0
    t = np.where(down, -origin[..., 2] / np.where(down, direction[..., 2], -1.0), 0.0)
    hit = origin + t[..., None] * direction
    return down & (np.abs(hit[..., 0]) <= half[0]) & (np.abs(hit[..., 1]) <= half[1])


def expected_flux(half: tuple[float, float], rings: int = 1500, spokes: int = 360) -> tuple[float, float]:
    """(Φ on the square, the part of it that came through or off the sphere)."""
    b = (np.arange(rings) + 0.5) / rings * RADIUS
    phi = (np.arange(spokes) + 0.5) / spokes * 2 * np.pi
    bb, pp = np.meshgrid(b, phi, indexing="ij")
    area = bb * (RADIUS / rings) * (2 * np.pi / spokes)
    centre = np.array([0.0, 0.0, CENTRE_HEIGHT])
    entry = np.stack([bb * np.cos(pp), bb * np.sin(pp), CENTRE_HEIGHT + np.sqrt(RADIUS**2 - bb**2)], axis=-1)
    normal_in = (entry - centre) / RADIUS
    d = np.broadcast_to(np.array([0.0, 0.0, -1.0]), entry.shape)
    cos_i = -np.sum(d * normal_in, axis=-1)
    reflectance_in = _fresnel_reflectance(cos_i, 1.0, IOR)
    reflected = d + 2 * cos_i[..., None] * normal_in
    inside = _refract(d, normal_in, 1 / IOR)
    # The chord from the entry point: the other root of |entry + t·inside − centre| = r.
    chord = -2 * np.sum(inside * (entry - centre), axis=-1)
    exit_point = entry + chord[..., None] * inside
    normal_out = (exit_point - centre) / RADIUS
    cos_inside = np.sum(inside * normal_out, axis=-1)
    transmittance_out = 1 - _fresnel_reflectance(cos_inside, IOR, 1.0)
    leaving = _refract(inside, -normal_out, IOR)
    through = (1 - reflectance_in) * transmittance_out * _lands_in_view(exit_point, leaving, half)
    off = reflectance_in * _lands_in_view(entry, reflected, half)
    sphere_part = IRRADIANCE * float(np.sum((through + off) * area))
    direct = IRRADIANCE * (4 * half[0] * half[1] - np.pi * RADIUS**2)
    return direct + sphere_part, sphere_part


def test_flux_through_a_ball_lens_from_a_distant_light(device, tmp_path):
    scene = spectrace.load_scene(_scene(tmp_path))
    _, _, right, up = scene.camera.basis(scene.width / scene.height)
    assert np.allclose(right[1:], 0) and np.allclose(up[[0, 2]], 0)
    half = (CAMERA_HEIGHT * abs(right[0]), CAMERA_HEIGHT * abs(up[1]))
    assert half[0] > RADIUS and half[1] > RADIUS  # the whole shadow is in view
    pixel_area = 4 * half[0] * half[1] / (scene.width * scene.height)
    images = spectrace_replicas(Renderer(scene, device), 8, 8)[..., 1]  # Y = radiance for a constant spectrum
    flux = np.pi / ALBEDO * images.sum(axis=(1, 2)) * pixel_area
    mean, standard_error = mean_and_standard_error(flux)
    expected, sphere_part = expected_flux(half)
    # The sphere's share is a large part of the flux, and the noise small beside it: a lost Fresnel factor or a
    # misplaced caustic moves the sum by many standard errors.
    assert sphere_part > 0.3 * expected
    assert standard_error < 0.01 * expected
    assert_within_standard_errors(mean, expected, standard_error)
