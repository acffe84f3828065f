"""The light tracer's and BDPT's connections to the thin-lens and orthographic cameras, against the floor's radiance.

A spot light of intensity I at height h over a diffuse floor of albedo ρ, pointing down with a cone of 80° (wider
than the view; its intensity constant within), gives the floor the radiance ρ/π · I h / r³ (r the distance to the
light). A camera looking straight down sees it; each pixel's value is that
radiance averaged over what the pixel sees, computed here with numpy from the cameras' definitions:
- orthographic: parallel rays from the pixel's square of the view rectangle (view_width across);
- thin lens: rays from points uniform on the aperture disk through the point of the plane of focus that the
  pinhole's ray through the film position reaches (pbrt-v4's and Mitsuba 3's thin lens); focused nearer than the
  floor, so each pixel averages the radiance over a blurred footprint and the strongly peaked centre spreads out
  (blocks differ from the pinhole's by up to 49 %).
Block means of independent replicas within 5 standard errors.
"""

from pathlib import Path

import numpy as np
import pytest

import spectrace
from replica_agreement import spectrace_replicas
from spectrace.engine.renderer import Renderer
from spectrace.errors import SpectraceError
from stats_toolkit import assert_within_standard_errors, mean_and_standard_error

INTENSITY, LIGHT_HEIGHT, ALBEDO, CAMERA_HEIGHT, SIZE, BLOCK = 2.0, 0.6, 0.5, 3.0, 32, 8
APERTURE, FOCUS, VIEW_WIDTH = 0.5, 1.0, 3.0


def _scene(tmp_path: Path, camera: str) -> Path:
    path = tmp_path / "floor.toml"
    path.write_text(
        f"""
[camera]
origin = [0.2, -0.1, {CAMERA_HEIGHT}]
target = [0.2, -0.1, 0]
up = [0, 1, 0]
{camera}

[film]
width = {SIZE}
height = {SIZE}

[integrator]
type = "light"
max_depth = 2

[sampler]
spp = 8
seed = 3

[materials.floor]
type = "diffuse"
reflectance = {{ value = {ALBEDO} }}

[[shapes]]
type = "rectangle"
material = "floor"
transform = [{{ scale = 6 }}]

[[lights]]
type = "spot"
position = [0, 0, {LIGHT_HEIGHT}]
target = [0, 0, 0]
cutoff_angle = 80
falloff_start = 80
intensity = {{ value = {INTENSITY} }}
""",
        encoding="utf-8",
    )
    return path


def _radiance(origins: np.ndarray, directions: np.ndarray) -> np.ndarray:
    t = -origins[..., 2] / directions[..., 2]
    p = origins + t[..., None] * directions
    r2 = p[..., 0] ** 2 + p[..., 1] ** 2 + LIGHT_HEIGHT**2
    return ALBEDO / np.pi * INTENSITY * LIGHT_HEIGHT / r2**1.5


def _film_grid(supersample: int) -> tuple[np.ndarray, np.ndarray]:
    """(ndc_x, ndc_y) of a supersample × supersample grid in each pixel, shaped (SIZE·s, SIZE·s)."""
    offsets = (np.arange(supersample) + 0.5) / supersample
    px = (np.arange(SIZE)[:, None] + offsets[None, :]).ravel()
    ndc_x = 2 * px / SIZE - 1
    ndc_y = 1 - 2 * px / SIZE
    return np.meshgrid(ndc_x, ndc_y, indexing="xy")


def _blocks(per_sample: np.ndarray, supersample: int) -> np.ndarray:
    n = SIZE // BLOCK
    return per_sample.reshape(n, BLOCK * supersample, n, BLOCK * supersample).mean(axis=(1, 3))


def _expected_orthographic(scene) -> np.ndarray:
    origin, forward, right, up = scene.camera.basis(1.0)
    nx, ny = _film_grid(8)
    origins = origin + nx[..., None] * right + ny[..., None] * up
    return _blocks(_radiance(origins, np.broadcast_to(forward, origins.shape)), 8)


def _expected_thin_lens(scene, supersample: int = 4, lens_rings: int = 12, lens_spokes: int = 24) -> np.ndarray:
    origin, forward, right, up = scene.camera.basis(1.0)
    nx, ny = _film_grid(supersample)
    focus_points = origin + FOCUS * (forward + nx[..., None] * right + ny[..., None] * up)
    total = np.zeros(nx.shape)
    rho = np.sqrt((np.arange(lens_rings) + 0.5) / lens_rings) * APERTURE  # equal-area rings
    phi = (np.arange(lens_spokes) + 0.5) / lens_spokes * 2 * np.pi
    for r in rho:
        for a in phi:
            lens = origin + r * (np.cos(a) * right / np.linalg.norm(right) + np.sin(a) * up / np.linalg.norm(up))
            total += _radiance(np.broadcast_to(lens, focus_points.shape), focus_points - lens)
    return _blocks(total / (lens_rings * lens_spokes), supersample)


@pytest.mark.parametrize("integrator", ["light", "bdpt"])
@pytest.mark.parametrize("camera", ["orthographic", "thinlens"])
def test_floor_seen_through_other_cameras(device, tmp_path, camera, integrator):
    """The light tracer's connections alone; BDPT's weighed against next-event estimation from the camera's
    vertices (MIS over both)."""
    if camera == "orthographic":
        scene = spectrace.load_scene(_scene(tmp_path, f'type = "orthographic"\nview_width = {VIEW_WIDTH}'))
        expected = _expected_orthographic(scene)
    else:
        keys = f'type = "thinlens"\nfov = 50\naperture_radius = {APERTURE}\nfocus_distance = {FOCUS}'
        scene = spectrace.load_scene(_scene(tmp_path, keys))
        expected = _expected_thin_lens(scene)
    scene = scene.with_overrides(integrator=integrator)
    images = spectrace_replicas(Renderer(scene, device), 8, 16)[..., 1]
    n = SIZE // BLOCK
    blocks = images.reshape(len(images), n, BLOCK, n, BLOCK).mean(axis=(2, 4))
    mean, standard_error = mean_and_standard_error(blocks)
    assert np.all(standard_error < 0.05 * expected)
    assert_within_standard_errors(mean, expected, standard_error)


def test_equirectangular_camera_refused_in_one_line(device, tmp_path):
    scene = spectrace.load_scene(_scene(tmp_path, 'type = "equirectangular"'))
    with pytest.raises(SpectraceError, match="equirectangular") as error:
        Renderer(scene, device)
    assert "\n" not in str(error.value)
