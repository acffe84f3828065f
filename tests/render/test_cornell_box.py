"""Whole renders of the Cornell box: finite, seed-independent in expectation, split-invariant bit for bit, and
the right colours in the right places."""

import csv

import numpy as np
import pytest

from spectrace.engine.renderer import Renderer
from spectrace.resources import scenes_dir
from spectrace.scene import load_scene
from stats_toolkit import assert_within_standard_errors, mean_and_standard_error

SIZE = 32


@pytest.fixture(scope="module")
def cornell():
    return load_scene(scenes_dir() / "cornell_box.toml").with_overrides(width=SIZE, height=SIZE, spp=16)


def test_render_is_finite_and_lit(cornell, device):
    image = Renderer(cornell, device).render()
    assert image.dropped_samples == 0
    assert np.all(np.isfinite(image.xyz))
    assert np.all(image.xyz >= 0)
    assert image.xyz[..., 1].mean() > 0.01


def test_mean_agrees_across_seeds(cornell, device):
    """Per-pixel differences between two seeds are independent with mean zero if the estimator does not depend
    on the seed; their mean must lie within 4 standard errors of zero."""
    a = Renderer(cornell.with_overrides(seed=1), device).render().xyz
    b = Renderer(cornell.with_overrides(seed=2), device).render().xyz
    assert not np.array_equal(a, b)
    mean, standard_error = mean_and_standard_error((a - b).reshape(-1, 3))
    assert_within_standard_errors(mean, 0.0, standard_error, what="X, Y, Z")


@pytest.mark.parametrize("sampler", ["sobol", "independent"])
def test_pass_split_is_bit_identical(cornell, device, sampler):
    scene = cornell.with_overrides(sampler=sampler)
    one_pass = Renderer(scene, device)
    one_pass.run_pass(8)
    split = Renderer(scene, device)
    for count in (1, 3, 4):
        split.run_pass(count)
    film_a, rays_a = one_pass.read_film()
    film_b, rays_b = split.read_film()
    assert np.array_equal(film_a, film_b)
    assert np.array_equal(rays_a, rays_b)


def test_walls_have_their_colours(device):
    scene = load_scene(scenes_dir() / "cornell_box.toml").with_overrides(width=24, height=24, spp=32)
    rgb = Renderer(scene, device).render().to_linear_srgb()
    left, right = rgb[8:16, 1:3].reshape(-1, 3).mean(0), rgb[8:16, -3:-1].reshape(-1, 3).mean(0)
    assert left[0] > 2 * left[1], f"left wall should be red, got {left}"
    assert right[1] > 1.5 * right[0], f"right wall should be green, got {right}"


def test_max_depth_one_shows_only_the_light(device):
    scene = load_scene(scenes_dir() / "cornell_box.toml").with_overrides(width=32, height=32, spp=4, max_depth=1)
    y = Renderer(scene, device).render().xyz[..., 1]
    lit = y > 0
    assert 0 < lit.sum() < 0.05 * lit.size, "only the light's pixels are non-zero"
    assert lit[: SIZE // 4].any() and not lit[SIZE // 2 :].any(), "the light is in the ceiling, at the top"


def test_the_bundled_scene_is_the_published_box():
    """scenes/cornell_box.toml holds the Cornell Program of Computer Graphics' published geometry (millimetres in
    geometry_mm.csv, each quad split (0, 1, 2), (0, 2, 3); the light lowered 0.5 mm off the ceiling) and camera
    (at (278, 273, -800) mm looking along +z; 35 mm lens, 25 mm film)."""
    scene = load_scene(scenes_dir() / "cornell_box.toml")
    with open(scenes_dir() / "cornell_box" / "geometry_mm.csv", encoding="utf-8") as stream:
        rows = list(csv.DictReader(line for line in stream if not line.startswith("#")))
    by_surface = {"white": "white surfaces", "red": "left wall", "green": "right wall", "light": "light"}
    for surface, shape_name in by_surface.items():
        quads = (
            np.array(
                [
                    [[row[f"{axis}{corner}"] for axis in "xyz"] for corner in range(4)]
                    for row in rows
                    if row["surface"] == surface
                ],
                dtype=float,
            )
            / 1000.0
        )
        if surface == "light":
            quads[..., 1] -= 0.0005
        expected = np.concatenate([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]], axis=0)
        mesh = next(shape.mesh for shape in scene.shapes if shape.name == shape_name)
        found = np.stack(mesh.triangles(), axis=1)

        def key(triangles):
            return sorted(map(tuple, np.round(triangles.reshape(len(triangles), 9), 6)))

        assert key(found) == key(expected), shape_name
    np.testing.assert_allclose(scene.camera.origin, (0.278, 0.273, -0.800))
    direction = np.subtract(scene.camera.target, scene.camera.origin)
    np.testing.assert_allclose(direction / np.linalg.norm(direction), (0, 0, 1))
    assert scene.camera.fov_degrees == pytest.approx(np.degrees(2 * np.arctan(12.5 / 35.0)), abs=1e-4)
