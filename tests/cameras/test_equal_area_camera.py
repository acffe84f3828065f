"""The equal-area spherical camera (kernels/camera_equal_area.cl; pbrt-v4's spherical camera, mapping "equalarea"):
a numpy reference of Clarberg's octahedral mapping written from the paper (checked here to be equal-area and
invertible), a constant environment seen as a flat image, every pixel seeing the same solid angle (the light
tracer's image from inside a uniformly emitting sphere: each pixel gathers light in proportion to its solid angle),
known directions landing on the pixel the mapping gives, and pbrt-v4's own camera imported so."""

import math

import numpy as np
import pytest

import spectrace
from spectrace.engine.renderer import Renderer
from spectrace.errors import SpectraceError
from spectrace.scene.model import Scene
from stats_toolkit import mean_and_standard_error


def square_to_sphere(p: np.ndarray) -> np.ndarray:
    """Clarberg 2008 (J. Graphics Tools 13(3)), section 3: (u, v) = 2p − 1; the distance d = 1 − (|u| + |v|) from the
    diamond's edge picks the hemisphere (sign) and r = 1 − |d| the ring; z = ±(1 − r²), φ = π/4 (1 + (|v| − |u|)/r)
    in the quadrant of (u, v), the radius in the plane √(1 − z²) = r √(2 − r²)."""
    u, v = 2 * p[..., 0] - 1, 2 * p[..., 1] - 1
    d = 1 - (np.abs(u) + np.abs(v))
    r = 1 - np.abs(d)
    with np.errstate(invalid="ignore", divide="ignore"):
        phi = np.where(r > 0, (np.abs(v) - np.abs(u)) / r + 1, 1.0) * np.pi / 4
    ring = r * np.sqrt(np.maximum(0, 2 - r * r))
    return np.stack([np.sign(u) * np.cos(phi) * ring, np.sign(v) * np.sin(phi) * ring, np.sign(d) * (1 - r * r)], -1)


def sphere_to_square(w: np.ndarray) -> np.ndarray:
    """The inverse: r = √(1 − |z|), the position along the quadrant's edge t = φ/(π/2) gives |u| = r(1 − t),
    |v| = r t in the upper hemisphere, mirrored to (1 − r t, 1 − r(1 − t)) below; signs of (x, y)."""
    r = np.sqrt(np.maximum(0, 1 - np.abs(w[..., 2])))
    t = np.arctan2(np.abs(w[..., 1]), np.abs(w[..., 0])) / (np.pi / 2)
    a, b = r * (1 - t), r * t
    lower = w[..., 2] < 0
    a, b = np.where(lower, 1 - b, a), np.where(lower, 1 - a, b)
    return np.stack([(np.copysign(a, w[..., 0]) + 1) / 2, (np.copysign(b, w[..., 1]) + 1) / 2], -1)


def test_the_reference_mapping_is_equal_area_and_invertible():
    """|∂ω/∂u × ∂ω/∂v| = 4π everywhere on the square (by central differences away from the fold lines), and the
    inverse takes each direction back to its point."""
    p = np.random.default_rng(1).uniform(0.02, 0.98, (2000, 2))
    p = p[
        np.min(
            np.abs(np.stack([p[:, 0] - 0.5, p[:, 1] - 0.5, np.abs(p[:, 0] - 0.5) + np.abs(p[:, 1] - 0.5) - 0.5], 1)),
            axis=1,
        )
        > 0.01
    ]
    h = 1e-6
    du = (square_to_sphere(p + [h, 0]) - square_to_sphere(p - [h, 0])) / (2 * h)
    dv = (square_to_sphere(p + [0, h]) - square_to_sphere(p - [0, h])) / (2 * h)
    np.testing.assert_allclose(np.linalg.norm(np.cross(du, dv), axis=1), 4 * np.pi, rtol=1e-4)
    w = square_to_sphere(p)
    np.testing.assert_allclose(np.linalg.norm(w, axis=1), 1, atol=1e-12)
    np.testing.assert_allclose(sphere_to_square(w), p, atol=1e-9)


def _camera() -> spectrace.Camera:
    return spectrace.Camera(origin=(0.0, 0.0, 0.0), target=(0.0, 0.0, -1.0), type="equalarea")


def _render(device, shapes, lights=(), size=32, spp=16, integrator="path", seed=0) -> np.ndarray:
    scene = Scene(
        camera=_camera(),
        width=size,
        height=size,
        shapes=list(shapes),
        lights=list(lights),
        max_depth=1,
        spp=spp,
        seed=seed,
        integrator=integrator,
    )
    renderer = Renderer(scene, device)
    renderer.render(spp=spp)
    return renderer.image().xyz[..., 1].astype(np.float64)


def test_a_constant_environment_is_a_flat_image(device):
    """Every pixel sees radiance 1 whatever its direction (each pixel's spread is the spectral estimate's alone)."""
    image = _render(device, [], [spectrace.constant_environment(1.0)])
    standard_error = image.std(ddof=1) / math.sqrt(image.size)
    assert abs(image.mean() - 1.0) <= 5.0 * standard_error + 1e-6
    assert image.min() > 0.97 and image.max() < 1.03


def test_every_pixel_sees_the_same_solid_angle(device):
    """From inside a sphere emitting L = 1 inward, the light tracer lands each light path on the pixel of its
    direction with importance 1/(4π d²) (the equal-area camera's): a pixel's value is L · (pixel count) · Ω_pixel /
    4π, flat at 1 only if every pixel's solid angle is 4π / pixel count. Blocks of 4 x 4 pixels within 4 standard
    errors of 1, over 8 independent renders."""
    black = spectrace.diffuse(0.0)
    sphere = spectrace.shape("sphere", black, spectrace.area_emitter(1.0), radius=2.0, flip_normals=True)
    images = np.stack([_render(device, [sphere], size=16, spp=32, integrator="light", seed=seed) for seed in range(8)])
    blocks = images.reshape(8, 4, 4, 4, 4).mean(axis=(2, 4))
    mean, standard_error = mean_and_standard_error(blocks)
    assert np.all(standard_error < 0.03)
    assert np.all(np.abs(mean - 1.0) <= 4 * standard_error + 1e-3), (mean, standard_error)


def _glowing_sphere(centre, radius):
    return spectrace.shape("sphere", spectrace.diffuse(0.0), spectrace.area_emitter(10.0), center=centre, radius=radius)


@pytest.mark.parametrize("direction", [(0.3, 0.2, -1.0), (1.0, 0.1, 0.2), (-0.5, -0.6, 0.4), (0.2, 0.9, -0.3)])
def test_a_direction_lands_on_the_pixel_the_mapping_gives(device, direction):
    """The camera looks along −z with +y up: right = +x, and the local direction (d·right, −d·up, d·forward) sits at
    the film position sphere_to_square gives. A small glowing sphere there has its brightness centroid within
    0.3 pixel of it (directions away from the map's folds, where the sphere's image would be cut in two)."""
    size = 96
    d = np.asarray(direction) / np.linalg.norm(direction)
    image = _render(device, [_glowing_sphere(tuple(10.0 * d), 0.15)], size=size, spp=16)
    y, x = np.mgrid[0:size, 0:size] + 0.5
    column, row = np.sum(x * image) / image.sum(), np.sum(y * image) / image.sum()
    expected = sphere_to_square(np.array([d[0], -d[1], -d[2]])) * size
    assert abs(column - expected[0]) < 0.3 and abs(row - expected[1]) < 0.3, (column, row, expected)


@pytest.mark.parametrize("mirror", [False, True])
def test_pbrt_spherical_camera_imports_as_equal_area(tmp_path, device, mirror):
    """pbrt-v4's spherical camera (default mapping "equalarea") sends film position p along EqualAreaSquareToSphere(p)
    with y and z swapped, in camera space: a glowing sphere at a known direction of pbrt's world lands where the
    reference puts it, once the importer's handedness is applied to the scene, not to the camera's image."""
    from spectrace.interop.pbrt import load_pbrt_scene

    size = 64
    target = np.array([0.4, 0.7, 0.5])  # in pbrt's world, seen from the origin
    target /= np.linalg.norm(target)
    text = (
        ("Scale -1 1 1\n" if mirror else "")
        + f"""LookAt 0 0 0  0 0 1  0 1 0
Camera "spherical"
Film "rgb" "integer xresolution" {size} "integer yresolution" {size}
Integrator "path" "integer maxdepth" 1
WorldBegin
AttributeBegin
Translate {10 * target[0]} {10 * target[1]} {10 * target[2]}
AreaLightSource "diffuse" "rgb L" [10 10 10]
Material "diffuse" "rgb reflectance" [0 0 0]
Shape "sphere" "float radius" 0.15
AttributeEnd
"""
    )
    (tmp_path / "scene.pbrt").write_text(text)
    scene = load_pbrt_scene(tmp_path / "scene.pbrt")
    assert scene.camera.type == "equalarea"
    renderer = Renderer(scene.with_overrides(spp=16), device)
    renderer.render(spp=16)
    image = renderer.image().xyz[..., 1].astype(np.float64)
    y, x = np.mgrid[0:size, 0:size] + 0.5
    column, row = np.sum(x * image) / image.sum(), np.sum(y * image) / image.sum()
    # LookAt from the origin along +z with +y up: camera space is pbrt's world (x negated by a Scale -1 1 1 before
    # it, which pbrt applies to the camera's own transform); the camera direction (x, y, z) is the square's (x, z, y).
    sign = -1.0 if mirror else 1.0
    expected = sphere_to_square(np.array([sign * target[0], target[2], target[1]])) * size
    assert abs(column - expected[0]) < 0.3 and abs(row - expected[1]) < 0.3, (column, row, expected)


def test_bdpt_and_wide_filters_are_refused_in_one_line(device):
    for overrides, message in (
        ({"integrator": "bdpt"}, "not 'equalarea'"),
        (
            {"integrator": "light", "pixel_filter": spectrace.PixelFilter("gaussian", stddev=0.5)},
            "equalarea camera with the box",
        ),
    ):
        scene = Scene(camera=_camera(), width=8, height=8, shapes=[], lights=[spectrace.constant_environment(1.0)])
        with pytest.raises(SpectraceError, match=message) as error:
            Renderer(scene.with_overrides(**overrides), device)
        assert "\n" not in str(error.value)
