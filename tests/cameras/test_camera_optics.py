"""The cameras against geometric optics: the thin lens images a point at its focus distance to one pixel and a point
off focus to the circle of confusion the thin-lens formula gives, and records radiance whatever its aperture (so the
flux it collects grows with the aperture's area); the orthographic camera images a plane at its world size whatever
its distance; the equirectangular camera sees a constant environment as a uniform image and puts each direction at
the pixel of its latitude and longitude."""

import math

import numpy as np
import pytest

import spectrace
from spectrace.engine.renderer import Renderer
from spectrace.scene.model import Scene
from stats_toolkit import assert_within_standard_errors

FOV = 20.0
SIZE = 65  # odd: the view axis passes through the centre of pixel (32, 32)


def _render(device, camera, shapes, width=SIZE, height=SIZE, spp=64, seed=0, lights=()) -> np.ndarray:
    scene = Scene(
        camera=camera,
        width=width,
        height=height,
        shapes=shapes,
        lights=list(lights),
        max_depth=1,
        spp=spp,
        seed=seed,
    )
    renderer = Renderer(scene, device)
    renderer.render(spp=spp)
    return renderer.image().xyz[..., 1].astype(np.float64)


def _glowing_sphere(centre, radius) -> spectrace.Shape:
    return spectrace.shape(
        "sphere", spectrace.diffuse(0.0), emitter=spectrace.area_emitter(1.0), center=centre, radius=radius
    )


def _lens(aperture: float, focus: float) -> spectrace.Camera:
    return spectrace.Camera(
        origin=(0.0, 0.0, 0.0),
        target=(0.0, 0.0, 1.0),
        fov_degrees=FOV,
        type="thinlens",
        aperture_radius=aperture,
        focus_distance=focus,
    )


def _pixels_per_unit_on_plane(distance: float) -> float:
    """Pixels per scene unit across a plane `distance` along the view axis."""
    return (SIZE / 2.0) / (distance * math.tan(math.radians(FOV / 2.0)))


def test_a_point_at_the_focus_distance_images_to_one_pixel(device):
    # A sphere a tenth of a pixel across, 4 units out, seen through a lens 0.2 units in radius focused on it.
    image = _render(device, _lens(0.2, 4.0), [_glowing_sphere((0.0, 0.0, 4.0), 0.002)], spp=256)
    assert image.sum() > 0.0
    assert image[32, 32] / image.sum() > 0.999


def _second_moment(image: np.ndarray) -> float:
    """Σ r² I / Σ I about the image's centre, r in pixels from pixel centres."""
    y, x = np.mgrid[0:SIZE, 0:SIZE] + 0.5 - SIZE / 2.0
    return float(np.sum((x * x + y * y) * image) / np.sum(image))


@pytest.mark.slow
def test_a_point_off_focus_spreads_to_the_circle_of_confusion(device):
    """Focused at F = 4 with aperture radius A = 0.2, a point at z = 2 spreads over a disk of radius A|z − F|/z on
    the plane of focus (Pharr et al., 4th ed., 5.2.3), here 9.2 pixels. The image of a small sphere is that disk
    convolved with the sphere's own disk (radius s) and the pixel's box, so its second moment about the centre is
    R²/2 + s²/2 + 1/6 (pixels²); R measured from 16 independent renders is within 5 standard errors of the formula,
    which resolves the radius to 5 %."""
    aperture, focus, z, rho = 0.2, 4.0, 2.0, 0.006
    expected_radius = aperture * abs(z - focus) / z * _pixels_per_unit_on_plane(focus)
    sphere_radius = math.tan(math.asin(rho / z)) * _pixels_per_unit_on_plane(1.0)
    camera = _lens(aperture, focus)
    radii = []
    for seed in range(16):
        image = _render(device, camera, [_glowing_sphere((0.0, 0.0, z), rho)], spp=96, seed=seed)
        radii.append(math.sqrt(2.0 * (_second_moment(image) - 1.0 / 6.0) - sphere_radius**2))
    mean, standard_error = np.mean(radii), np.std(radii, ddof=1) / math.sqrt(len(radii))
    assert 8.0 < expected_radius < 10.0
    assert_within_standard_errors(
        mean, expected_radius, standard_error, sigmas=5.0, what="circle of confusion radius (pixels)", power=0.05
    )


@pytest.mark.parametrize("aperture", [0.0, 0.05, 0.4])
def test_a_uniform_emitter_filling_the_view_records_its_radiance_at_every_aperture(device, aperture):
    """The film records radiance: the flux through the aperture divided by its area and the pixel's solid angle.
    A wall of radiance 1 filling the view renders Y = 1 (within 5 standard errors over the pixels) through a pinhole
    and through lenses of any radius, so the flux the lens collects, Y · π A² · Ω, grows as the aperture's area."""
    wall = spectrace.shape(
        "rectangle",
        spectrace.diffuse(0.0),
        emitter=spectrace.area_emitter(1.0),
        transform=[{"scale": 50.0}, {"rotate": {"axis": [0, 1, 0], "angle": 180}}, {"translate": [0, 0, 6]}],
    )
    image = _render(device, _lens(aperture, 3.0), [wall], width=16, height=16, spp=16)
    standard_error = image.std(ddof=1) / math.sqrt(image.size)
    assert abs(image.mean() - 1.0) <= 5.0 * standard_error + 1e-6, (image.mean(), standard_error)


@pytest.mark.parametrize("distance", [3.0, 10.0])
def test_orthographic_images_a_plane_at_its_world_size(device, distance):
    """A 1 x 0.5 emitting rectangle, moved 0.25 to the image's right, seen by an orthographic camera 2 units wide on
    a 64 x 32 film (32 pixels a unit): it covers exactly columns 24..55 (16..47 moved by 8) and rows 8..23 at any
    distance (its edges fall on pixel boundaries, so each pixel is wholly in or out)."""
    camera = spectrace.Camera(
        origin=(0.0, 0.0, 0.0), target=(0.0, 0.0, 1.0), type="orthographic", view_width=2.0
    )  # image right = forward × up = world −x
    rectangle = spectrace.shape(
        "rectangle",
        spectrace.diffuse(0.0),
        emitter=spectrace.area_emitter(1.0, two_sided=True),
        transform=[{"scale": [0.5, 0.25, 1.0]}, {"translate": [-0.25, 0.0, distance]}],
    )
    image = _render(device, camera, [rectangle], width=64, height=32, spp=16)
    lit = image > 0.5
    expected = np.zeros_like(lit)
    expected[8:24, 24:56] = True
    np.testing.assert_array_equal(lit, expected)
    assert np.all(image[~expected] == 0.0)


def _equirect() -> spectrace.Camera:
    return spectrace.Camera(origin=(0.0, 0.0, 0.0), target=(0.0, 0.0, -1.0), type="equirectangular")


def test_equirectangular_sees_a_constant_environment_as_a_uniform_image(device):
    image = _render(device, _equirect(), [], width=32, height=16, spp=16, lights=[spectrace.constant_environment(1.0)])
    standard_error = image.std(ddof=1) / math.sqrt(image.size)
    assert abs(image.mean() - 1.0) <= 5.0 * standard_error + 1e-6
    assert image.min() > 0.9 and image.max() < 1.1


@pytest.mark.parametrize(
    "direction",
    [(1.0, 0.0, 0.0), (0.0, 1.0, -1.0), (-0.5, -0.4, 0.6), (0.3, 0.2, -1.0)],
)
def test_equirectangular_puts_a_direction_at_its_latitude_and_longitude(device, direction):
    """The camera looks along −z with +y up, the environment maps' frame (docs/scene-format.md): a direction d has
    θ = acos(d_y), φ = atan2(d_x, −d_z), and appears at column (φ + π)/2π · width, row θ/π · height. A small
    glowing sphere there has its brightness centroid within 0.3 pixel of that point (the sphere spans ~3 pixels,
    away from the poles)."""
    width, height = 128, 64
    d = np.asarray(direction) / np.linalg.norm(direction)
    image = _render(device, _equirect(), [_glowing_sphere(tuple(10.0 * d), 0.12)], width=width, height=height)
    y, x = np.mgrid[0:height, 0:width] + 0.5
    column, row = np.sum(x * image) / image.sum(), np.sum(y * image) / image.sum()
    expected_column = (math.atan2(d[0], -d[2]) + math.pi) / (2.0 * math.pi) * width
    expected_row = math.acos(d[1]) / math.pi * height
    assert abs(column - expected_column) < 0.3 and abs(row - expected_row) < 0.3, (column, row)


def test_equirectangular_capture_of_an_environment_map_is_the_map(device, tmp_path):
    """An envmap of 16 x 8 random texels seen by an equirectangular camera in the maps' frame (looking along −z, +y
    up) on a 16 x 8 film: each pixel covers one texel exactly, and each texel's radiance reproduces its linear sRGB
    (docs/scene-format.md), so the image's linear sRGB is the map, each pixel within 5 standard errors of 8
    independent renders."""
    from spectrace.io.exr import write_exr
    from spectrace.spectral import xyz_to_linear_srgb

    rgb = np.random.default_rng(7).uniform(0.1, 1.0, (8, 16, 3)).astype(np.float32)
    write_exr(tmp_path / "sky.exr", rgb, None, {})
    (tmp_path / "scene.toml").write_text(
        '[camera]\ntype = "equirectangular"\norigin = [0, 0, 0]\ntarget = [0, 0, -1]\n[film]\nwidth = 16\nheight = 8\n'
        '[materials]\n[[lights]]\ntype = "envmap"\nfile = "sky.exr"\n'
    )
    scene = spectrace.load_scene(tmp_path / "scene.toml")
    renders = []
    for seed in range(8):
        renderer = Renderer(scene.with_overrides(seed=seed), device)
        renderer.render(spp=8)
        renders.append(xyz_to_linear_srgb(renderer.image().xyz.astype(np.float64)))
    mean = np.mean(renders, axis=0)
    standard_error = np.std(renders, axis=0, ddof=1) / math.sqrt(len(renders))
    assert np.all(np.abs(mean - rgb) <= 5.0 * standard_error + 1e-4), np.max(np.abs(mean - rgb) / standard_error)
