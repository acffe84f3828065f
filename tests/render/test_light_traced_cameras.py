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
- equirectangular: the whole sphere of directions, each pixel's mean over its (u, v) square, the floor made smaller
  so that all of it lies inside the cone.
Block means of independent replicas within 5 standard errors.
"""

from pathlib import Path

import numpy as np
import pytest

import spectrace
from replica_agreement import spectrace_replicas
from scene_text import camera_film
from spectrace.engine.renderer import Renderer
from spectrace.errors import SpectraceError
from stats_toolkit import assert_power, assert_within_standard_errors, mean_and_standard_error

INTENSITY, LIGHT_HEIGHT, ALBEDO, CAMERA_HEIGHT, SIZE, BLOCK = 2.0, 0.6, 0.5, 3.0, 32, 8
APERTURE, FOCUS, VIEW_WIDTH = 0.5, 1.0, 3.0


def _scene(tmp_path: Path, camera: str) -> Path:
    path = tmp_path / "floor.toml"
    path.write_text(
        camera_film(
            origin=f"[0.2, -0.1, {CAMERA_HEIGHT}]",
            target="[0.2, -0.1, 0]",
            fov=None,
            width=SIZE,
            height=SIZE,
            camera=f"up = [0, 1, 0]\n{camera}",
        )
        + f"""
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
    images = spectrace_replicas(Renderer(scene, device), 8, 24 if integrator == "light" else 16)[..., 1]
    n = SIZE // BLOCK
    # Quarters of the image (2 x 2 blocks), each to 5 %: the light tracer's single blocks are too noisy for that.
    blocks = images.reshape(len(images), n // 2, 2 * BLOCK, n // 2, 2 * BLOCK).mean(axis=(2, 4))
    expected = expected.reshape(n // 2, 2, n // 2, 2).mean(axis=(1, 3))
    mean, standard_error = mean_and_standard_error(blocks)
    assert_within_standard_errors(mean, expected, standard_error, power=0.05)


def _expected_equirectangular(scene, supersample: int = 24) -> np.ndarray:
    """Each pixel's mean over film positions uniform in it of the radiance along θ = π v, φ = 2π u − π (camera.cl's
    equirectangular camera: θ from up, φ around it from forward toward right), 0 where the ray misses the floor
    ([-FLOOR, FLOOR]², all of it inside the spot's cone), in blocks of BLOCK/2 pixels."""
    origin, forward, right, up = scene.camera.basis(2.0)
    width, height = 2 * SIZE, SIZE
    offsets = (np.arange(supersample) + 0.5) / supersample
    u = ((np.arange(width)[:, None] + offsets[None, :]).ravel()) / width
    v = ((np.arange(height)[:, None] + offsets[None, :]).ravel()) / height
    uu, vv = np.meshgrid(u, v, indexing="xy")
    theta, phi = np.pi * vv, 2 * np.pi * uu - np.pi
    directions = (
        (np.sin(theta) * np.sin(phi))[..., None] * right
        + np.cos(theta)[..., None] * up
        + (np.sin(theta) * np.cos(phi))[..., None] * forward
    )
    downward = directions[..., 2] < -1e-9
    t = np.where(downward, -origin[2] / np.where(downward, directions[..., 2], -1.0), 0.0)
    hit = origin + t[..., None] * directions
    on_floor = downward & (np.abs(hit[..., 0]) <= FLOOR) & (np.abs(hit[..., 1]) <= FLOOR)
    origins = np.broadcast_to(origin, directions.shape)
    radiance = np.where(on_floor, _radiance(origins, np.where(on_floor[..., None], directions, forward)), 0.0)
    block = BLOCK // 2
    return radiance.reshape(height // block, block * supersample, width // block, block * supersample).mean(axis=(1, 3))


FLOOR = 2.0  # the equirectangular test's floor half-width: its corners (r < 2.9) lie inside the 80° cone (r < 3.4)


def test_floor_seen_through_the_equirectangular_camera(device, tmp_path):
    """The whole sphere of directions on a 2:1 film: the floor below, nothing elsewhere; the light tracer's
    connections (importance 1/(2π² sin θ d²)) against the radiance averaged over each pixel's directions."""
    text = _scene(tmp_path, 'type = "equirectangular"').read_text()
    text = text.replace(f"width = {SIZE}", f"width = {2 * SIZE}").replace("scale = 6", f"scale = {FLOOR}")
    path = tmp_path / "equirectangular.toml"
    path.write_text(text, encoding="utf-8")
    scene = spectrace.load_scene(path)
    assert scene.camera.type == "equirectangular" and scene.width == 2 * SIZE
    expected = _expected_equirectangular(scene)
    images = spectrace_replicas(Renderer(scene, device), 8, 16)[..., 1]
    block = BLOCK // 2
    blocks = images.reshape(len(images), SIZE // block, block, 2 * SIZE // block, block).mean(axis=(2, 4))
    mean, standard_error = mean_and_standard_error(blocks)
    lit = expected > 0.05 * expected.max()
    assert lit.sum() >= 8 and (~lit).sum() >= 8
    assert_power(expected[lit], standard_error[lit], what="lit blocks")
    assert_within_standard_errors(mean, expected, standard_error)


def test_equirectangular_camera_with_a_wider_filter_refused_in_one_line(device, tmp_path):
    text = _scene(tmp_path, 'type = "equirectangular"').read_text()
    path = tmp_path / "filtered.toml"
    path.write_text(text.replace(f"height = {SIZE}", f'height = {SIZE}\nfilter = "gaussian"'), encoding="utf-8")
    scene = spectrace.load_scene(path)
    with pytest.raises(SpectraceError, match="equirectangular camera with the box filter only") as error:
        Renderer(scene, device)
    assert "\n" not in str(error.value)
