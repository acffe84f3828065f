"""Light paths leaving a projector or a goniometric light are drawn in proportion to its image (kernels/
distribution_2d.cl through light_projector.cl and light_goniometric.cl), checked on sparse images (a few bright
texels on black) through kernels/testing/light_directions.cl and kernels/testing/lights.cl:
- the directions drawn fall in the image's texels with the probabilities the documented weights give (chi-square):
  a goniometric texel's value (every texel covers the same solid angle), a projector texel's luminance floored at
  1e-3 of the mean (docs/scene-format.md), the texels a lookup reaches through uv_scale, uv_offset and the filter,
  times cos³θ at the texel's centre for the intensity profile;
- the density BDPT's MIS reads for a direction is that texel's probability over the solid angle it covers;
- the first rays of light paths carry on average the light's flux, its intensity as next-event estimation reads it
  integrated over the image, within 4 standard errors, and with a much smaller variance than uniform directions."""

import numpy as np
import pytest
from tests.cameras.test_equal_area_camera import sphere_to_square
from tests.lights.test_light_harness import HARNESS, Lights, _scene

import spectrace
from spectrace.engine.scene_buffers import build_scene_buffers
from spectrace.geometry.bvh4 import traversal_defines
from stats_toolkit import assert_chi_square_fits, assert_within_standard_errors, mean_and_standard_error

DIRECTIONS = "testing/light_directions.cl"
SAMPLES = 40_000
SIGNIFICANCE = 0.01 / 6  # Bonferroni over the six chi-square tests

# 8 x 6 texels, black but for three: a projector's grey reflectance image (values in [0, 1]).
PROJECTOR_IMAGE = np.zeros((6, 8))
PROJECTOR_IMAGE[1, 2], PROJECTOR_IMAGE[4, 6], PROJECTOR_IMAGE[3, 0] = 1.0, 0.6, 0.25
# 8 x 8 equal-area texels, black but for four.
GONIO_IMAGE = np.zeros((8, 8))
GONIO_IMAGE[2, 5], GONIO_IMAGE[6, 1], GONIO_IMAGE[0, 0], GONIO_IMAGE[4, 4] = 6.0, 2.0, 1.0, 0.5
POSITION = np.array([0.3, 1.0, -0.2])


def _upload(runner, scene, uniform: bool) -> tuple:
    """(buffers, kernel arguments) of a scene whose light 0, when `uniform`, has its table set aside (the Light row's
    NO_DISTRIBUTION), as a light without one draws."""
    from spectrace.engine.renderer import upload_scene
    from spectrace.engine.scene_buffers import render_params

    buffers = build_scene_buffers(scene)
    if uniform:
        buffers.lights["triangle"][0] = -1
    return buffers, [runner.buffer(render_params(scene, buffers, 0, 1)), *upload_scene(runner.device.context, buffers)]


class Directions:
    """A scene's light 0 drawing light-path directions on the device."""

    def __init__(self, runner, scene):
        self.runner = runner
        _, self.scene_args = _upload(runner, scene, False)

    def sample(self, n: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
        u = np.random.default_rng(seed).random((n, 2), dtype=np.float32)
        out = np.zeros((n, 4), np.float32)
        args = [*self.scene_args, self.runner.buffer(u), self.runner.buffer(out, True), np.int32(n)]
        self.runner.run("light_direction_samples", n, args, {len(self.scene_args) + 1: out})
        return out[:, :3].astype(np.float64), out[:, 3].astype(np.float64)


@pytest.fixture(scope="module")
def runners(kernel_runner):
    return kernel_runner(DIRECTIONS, traversal_defines()), kernel_runner(HARNESS, traversal_defines())


def _projector(placement: dict, profile: str = "irradiance"):
    image = spectrace.bitmap(PROJECTOR_IMAGE, wrap="clamp", **placement)
    return spectrace.projector_light(
        tuple(POSITION), (0.5, -0.8, 0.1), 50.0, intensity="cie:D65", image=image, up=(0.0, 0.0, 1.0), profile=profile
    )


def _projector_frame(light) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    z = np.asarray(light.direction)
    x = np.asarray(light.image_x)
    return x, np.cross(z, x), z


def _projector_texels(light, d: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(row, column) of the uv cell each direction crosses the plane z = 1 in, and cos θ."""
    x, y, z = _projector_frame(light)
    cos_theta = d @ z
    u = 0.5 + 0.5 * (d @ x) / cos_theta / light.tan_x
    v = 0.5 + 0.5 * (d @ y) / cos_theta / light.tan_y
    height, width = PROJECTOR_IMAGE.shape
    rows = np.clip((v * height).astype(int), 0, height - 1)
    columns = np.clip((u * width).astype(int), 0, width - 1)
    return rows, columns, cos_theta


def _floored(weights: np.ndarray) -> np.ndarray:
    return np.maximum(weights, 1e-3 * weights.mean())


# The weights each placement's uv cells get: the texel a nearest lookup reads (mirrored across u by the pbrt
# importer's placement), and with bilinear filtering every texel within one of a cell's (wrap clamp).
def _dilated(image: np.ndarray) -> np.ndarray:
    padded = np.pad(image, 1, mode="edge")
    height, width = image.shape
    return np.max([padded[i : i + height, j : j + width] for i in range(3) for j in range(3)], axis=0)


PROJECTOR_CASES = {
    "nearest": ({"filter": "nearest"}, _floored(PROJECTOR_IMAGE)),
    "mirrored-u": (
        {"filter": "nearest", "uv_scale": (-1.0, 1.0), "uv_offset": (1.0, 0.0)},
        _floored(PROJECTOR_IMAGE[:, ::-1]),
    ),
    "bilinear": ({"filter": "bilinear"}, _floored(_dilated(PROJECTOR_IMAGE))),
    "intensity-profile": ({"filter": "nearest"}, _floored(PROJECTOR_IMAGE)),
}


@pytest.mark.parametrize("case", PROJECTOR_CASES, ids=list(PROJECTOR_CASES))
def test_projector_light_paths_follow_the_image(runners, case):
    placement, weights = PROJECTOR_CASES[case]
    light = _projector(placement, "intensity" if case == "intensity-profile" else "irradiance")
    if light.profile == "intensity":  # I = intensity·image: the weights take dω/dA = cos³θ at each cell's centre
        height, width = weights.shape
        u, v = np.meshgrid((np.arange(width) + 0.5) / width, (np.arange(height) + 0.5) / height)
        weights = weights * np.cos(np.arctan(np.hypot((2 * u - 1) * light.tan_x, (2 * v - 1) * light.tan_y))) ** 3
    d, pdf = Directions(runners[0], _scene(lights=[light])).sample(SAMPLES, seed=31)
    rows, columns, cos_theta = _projector_texels(light, d)
    observed = np.zeros(weights.shape)
    np.add.at(observed, (rows, columns), 1.0)
    probability = weights / weights.sum()
    assert_chi_square_fits(observed.ravel(), SAMPLES * probability.ravel(), SIGNIFICANCE, what=case)
    # The density per steradian: the cell's probability over its area on z = 1 (4 tan_x tan_y / cells), times
    # dA/dω = 1/cos³θ. A direction within a float's rounding of a cell's edge may be read in its neighbour.
    area = 4.0 * light.tan_x * light.tan_y / weights.size
    expected = probability[rows, columns] / (area * cos_theta**3)
    assert np.mean(~np.isclose(pdf, expected, rtol=1e-3)) <= 1e-3, case


@pytest.mark.parametrize("mirrored", [False, True], ids=["right-handed", "mirrored"])
def test_goniometric_light_paths_follow_the_image(runners, mirrored):
    light = spectrace.goniometric_light(
        tuple(POSITION), "cie:D65", image=GONIO_IMAGE, up=(0.2, 1.0, 0.1), front=(1.0, 0.0, 0.0), mirrored=mirrored
    )
    d, pdf = Directions(runners[0], _scene(lights=[light])).sample(SAMPLES, seed=32)
    x, y, z = light.frame()
    uv = sphere_to_square(np.stack([d @ x, d @ y, d @ z], axis=1))
    n = GONIO_IMAGE.shape[0]
    rows, columns = np.clip((uv[:, 1] * n).astype(int), 0, n - 1), np.clip((uv[:, 0] * n).astype(int), 0, n - 1)
    observed = np.zeros(GONIO_IMAGE.shape)
    np.add.at(observed, (rows, columns), 1.0)
    probability = GONIO_IMAGE / GONIO_IMAGE.sum()
    # None where the light sends nothing, but for directions within a float's rounding of a bright texel's edge.
    assert observed[GONIO_IMAGE == 0].sum() <= 1e-3 * SAMPLES, observed
    assert_chi_square_fits(observed.ravel(), SAMPLES * probability.ravel(), SIGNIFICANCE, what=mirrored)
    expected = probability[rows, columns] * n * n / (4.0 * np.pi)  # each texel covers 4π / n² sr
    assert np.mean(~np.isclose(pdf, expected, rtol=1e-3)) <= 1e-3, mirrored


def _intensity_grid(lights: Lights, directions: np.ndarray) -> np.ndarray:
    """I(d) at LAMBDA_NM, W/(sr nm), for unit directions leaving POSITION, as next-event estimation reads it
    (the irradiance at unit distance; none where it sends nothing)."""
    return lights.sample(POSITION + directions, len(directions), seed=3)["arriving"]


def _projector_flux(lights: Lights, light) -> np.ndarray:
    """∫ I dω over the field: the midpoint rule on the plane z = 1 (dω = cos³θ dA), 8 points a texel a side, so
    that no texel's edge crosses a cell."""
    x, y, z = _projector_frame(light)
    height, width = PROJECTOR_IMAGE.shape
    k = 8
    u = (np.arange(width * k) + 0.5) / (width * k)
    v = (np.arange(height * k) + 0.5) / (height * k)
    uu, vv = np.meshgrid(u, v)
    px, py = (2.0 * uu.ravel() - 1.0) * light.tan_x, (2.0 * vv.ravel() - 1.0) * light.tan_y
    points = px[:, None] * x + py[:, None] * y + z
    norm = np.linalg.norm(points, axis=1)
    cos_theta = 1.0 / norm
    intensity = _intensity_grid(lights, points / norm[:, None])
    cell = 4.0 * light.tan_x * light.tan_y / len(px)
    return np.sum(intensity * (cos_theta**3 * cell)[:, None], axis=0)


def _goniometric_flux(lights: Lights, light) -> np.ndarray:
    """∫ I dω: the value at each texel's centre times 4π / texel count (the map is equal-area)."""
    from tests.cameras.test_equal_area_camera import square_to_sphere

    n = GONIO_IMAGE.shape[0]
    centres = (np.stack(np.meshgrid(np.arange(n), np.arange(n)), axis=-1).reshape(-1, 2) + 0.5) / n
    m = square_to_sphere(centres)
    x, y, z = light.frame()
    d = m[:, :1] * x + m[:, 1:2] * y + m[:, 2:] * z
    return _intensity_grid(lights, d).sum(axis=0) * 4.0 * np.pi / (n * n)


FLUX_CASES = ["projector-irradiance", "projector-intensity", "goniometric"]


def _flux_light(case: str):
    if case == "goniometric":
        return spectrace.goniometric_light(tuple(POSITION), "cie:D65", image=GONIO_IMAGE, up=(0.2, 1.0, 0.1))
    return _projector({"filter": "nearest"}, case.split("-")[1])


@pytest.mark.parametrize("case", FLUX_CASES)
def test_light_paths_carry_the_flux_with_less_variance_than_uniform_directions(runners, case, record_property):
    """The mean flux of the first rays equals ∫ I dω (I as next-event estimation sees it) within 4 standard errors,
    drawn by the image and uniformly; the image's draw has at least 5 times less variance on these sparse images."""
    light = _flux_light(case)
    scene = _scene(lights=[light])
    lights = Lights(runners[1], scene)
    expected = _goniometric_flux(lights, light) if case == "goniometric" else _projector_flux(lights, light)
    variances = []
    for uniform in (False, True):
        drawn = Lights(runners[1], scene)
        drawn.buffers, drawn.scene_args = _upload(runners[1], scene, uniform)
        weight = drawn.emit(20_000, seed=71, radius=3.0)
        mean, standard_error = mean_and_standard_error(weight)
        assert_within_standard_errors(mean, expected, standard_error, slack=1e-4 * expected, what=(case, uniform))
        variances.append(weight.var(axis=0).sum())
    record_property("variance_ratio", float(variances[1] / variances[0]))
    assert variances[1] >= 5.0 * variances[0], (case, variances)
