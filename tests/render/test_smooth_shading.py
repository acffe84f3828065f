"""Smooth shading against closed-form radiometry.

A Lambertian sphere of albedo ρ lit by a distant light of irradiance E reflects L = ρ/π · E · max(0, n·l) toward
the camera, n the sphere's true normal where the pixel's ray meets it. An icosphere shaded with its vertex normals
must reproduce that pixel by pixel; shaded with its face normals it shows facets. Each pass of the renderer adds
one independent sample per pixel (independent sampler), so the passes are replicates for the standard errors.
"""

import numpy as np
from scipy import stats

import spectrace
from spectrace.engine.renderer import Renderer
from spectrace.geometry import primitives
from spectrace.geometry.mesh import TriangleMesh
from spectrace.scene.model import Scene
from stats_toolkit import assert_at_most_within_standard_errors, assert_within_standard_errors, mean_and_standard_error

ALBEDO = 0.5
IRRADIANCE = 2.0
TOWARD_LIGHT = np.array([0.5, 0.6, 0.62]) / np.linalg.norm([0.5, 0.6, 0.62])
CAMERA = spectrace.Camera(origin=(0.0, 0.0, 4.0), target=(0.0, 0.0, 0.0), fov_degrees=32.0)
SIZE = 20
FAMILY_FALSE_ALARM = 1e-3  # chance that some pixel of a correct render fails, split over the pixels (Bonferroni)


def _sphere_scene(face_normals: bool | None, seed: int = 7, one_sided_wound_inward: bool = False) -> Scene:
    # 1280 triangles: fine enough for interpolated normals to stay within 0.2° of the sphere's, coarse enough for
    # the facets to show through the noise.
    icosphere = primitives.sphere(subdivisions=3)
    material = spectrace.diffuse(ALBEDO)
    if one_sided_wound_inward:
        icosphere = TriangleMesh(icosphere.vertices, icosphere.faces[:, ::-1], icosphere.uvs, icosphere.normals)
        material = spectrace.diffuse(ALBEDO, two_sided=False)
    sphere = spectrace.shape(icosphere, material, face_normals=face_normals)
    light = spectrace.distant_light(tuple(-TOWARD_LIGHT), IRRADIANCE)
    # max_depth 2: emitters and direct light only, so the analytic value is the whole radiance.
    return Scene(
        camera=CAMERA, width=SIZE, height=SIZE, shapes=[sphere], lights=[light], max_depth=2, seed=seed,
        sampler="independent",
    )  # fmt: skip


def _per_sample_y(scene: Scene, device, samples: int) -> np.ndarray:
    """(samples, height, width) luminance of each pass of one sample per pixel."""
    renderer = Renderer(scene, device)
    values, previous = [], np.zeros(scene.width * scene.height, np.float64)
    for _ in range(samples):
        renderer.run_pass(1)
        total = renderer.read_film()[0][:, 1].astype(np.float64)
        values.append(total - previous)
        previous = total
    return np.array(values).reshape(samples, scene.height, scene.width)


def _analytic_sphere(sub: int = 12) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per pixel: the radiance averaged over the pixel (sub × sub stratified rays against the unit sphere), and the
    least and greatest n·v and n·l over those rays (-2 where a ray misses)."""
    origin, forward, right, up = CAMERA.basis(1.0)
    offsets = (np.arange(sub) + 0.5) / sub
    px = (np.arange(SIZE)[:, None] + offsets[None, :]).ravel()
    ndc_x = 2.0 * px / SIZE - 1.0
    ndc_y = 1.0 - 2.0 * px / SIZE
    directions = forward + ndc_x[None, :, None] * right + ndc_y[:, None, None] * up
    directions /= np.linalg.norm(directions, axis=-1, keepdims=True)
    b = directions @ origin
    disc = b * b - (origin @ origin - 1.0)
    hit = disc > 0
    t = -b - np.sqrt(np.where(hit, disc, 0.0))
    normal = origin + t[..., None] * directions
    n_dot_l = np.where(hit, normal @ TOWARD_LIGHT, -2.0)
    n_dot_v = np.where(hit, np.einsum("...k,...k", normal, -directions), -2.0)
    radiance = ALBEDO / np.pi * IRRADIANCE * np.maximum(n_dot_l, 0.0)

    def per_pixel(a: np.ndarray, how) -> np.ndarray:
        return how(a.reshape(SIZE, sub, SIZE, sub), axis=(1, 3))

    return per_pixel(radiance, np.mean), per_pixel(np.minimum(n_dot_v, n_dot_l), np.min), per_pixel(n_dot_l, np.max)


def _compared_pixels(least_cos: np.ndarray, greatest_n_dot_l: np.ndarray) -> np.ndarray:
    """Pixels wholly on the sphere, away from its silhouette (where an icosphere's outline and the fallback to the
    face normal for grazing views differ from a sphere) and away from the terminator (where any tessellation casts
    its own shadows), either lit throughout or dark throughout."""
    lit = least_cos > 0.15
    dark = (greatest_n_dot_l < -0.15) & (least_cos > -2.0)
    return lit | dark


def test_smooth_icosphere_matches_the_analytic_lambertian_sphere(device):
    expected, least_cos, greatest_n_dot_l = _analytic_sphere()
    compared = _compared_pixels(least_cos, greatest_n_dot_l)
    assert compared.sum() > 100 and (compared & (expected > 0)).sum() > 60  # lit and dark pixels both tested
    sigmas = stats.norm.isf(FAMILY_FALSE_ALARM / (2 * compared.sum()))
    scaled_deviations = {}
    for face_normals in (None, True):
        mean, standard_error = mean_and_standard_error(_per_sample_y(_sphere_scene(face_normals), device, 64))
        scaled_deviations[face_normals] = ((mean - expected) / np.maximum(standard_error, 1e-12))[compared]
        if face_normals is None:
            # float32 rounding of the normals and the film: far below the noise
            assert_within_standard_errors(
                mean[compared], expected[compared], standard_error[compared], sigmas=sigmas, slack=1e-4,
                what="smooth sphere vs analytic",
            )  # fmt: skip
    # In standard errors, the smooth sphere's deviations are noise (mean square near 1); the facets' are not.
    assert np.mean(scaled_deviations[None] ** 2) < 2.0 < 4.0 < np.mean(scaled_deviations[True] ** 2)


def test_a_one_sided_sphere_wound_inward_with_outward_normals_matches_the_analytic_sphere(device):
    """Its vertex normals, not its winding, say which side is its front (Mitsuba 3's shading-frame rule): one-sided,
    it shows its lit outside as the two-sided sphere does, pixel by pixel."""
    expected, least_cos, greatest_n_dot_l = _analytic_sphere()
    compared = _compared_pixels(least_cos, greatest_n_dot_l)
    sigmas = stats.norm.isf(FAMILY_FALSE_ALARM / (2 * compared.sum()))
    samples = _per_sample_y(_sphere_scene(None, one_sided_wound_inward=True), device, 64)
    mean, standard_error = mean_and_standard_error(samples)
    assert mean[compared].max() > 0.1  # lit, not the black back of the surface
    assert_within_standard_errors(
        mean[compared], expected[compared], standard_error[compared], sigmas=sigmas, slack=1e-4,
        what="one-sided inward-wound sphere vs analytic",
    )  # fmt: skip


def _white_furnace(face_normals: bool | None) -> Scene:
    sphere = spectrace.shape("sphere", spectrace.diffuse(1.0), face_normals=face_normals, tessellated=True)
    camera = spectrace.Camera(origin=(0.0, 0.0, 4.0), target=(0.0, 0.0, 0.0), fov_degrees=40.0)
    return Scene(
        camera=camera, width=16, height=16, shapes=[sphere], lights=[spectrace.constant_environment(1.0)],
        max_depth=64, rr_depth=64, spp=32, seed=5,
    )  # fmt: skip


def test_white_furnace_with_smooth_normals_conserves_energy(device):
    """A white Lambertian sphere inside a uniform environment of radiance 1 looks exactly like the environment: every
    path ends in it with throughput 1. Shading normals must neither create energy nor lose more than the thin wedge
    between the shading and the geometric tangent plane, which the light-leak rule discards."""
    y = Renderer(_white_furnace(None), device).render().xyz[..., 1]
    on_sphere = np.zeros_like(y, bool)
    on_sphere[5:11, 5:11] = True  # the sphere spans the middle 11 of the 16 pixels across
    mean, standard_error = mean_and_standard_error(y[on_sphere].ravel())
    assert standard_error < 0.01
    assert_at_most_within_standard_errors(mean, 1.0, standard_error, what="smooth white furnace")
    assert_within_standard_errors(mean, 1.0, standard_error, slack=2e-3, what="smooth white furnace")


def _quad(normals: np.ndarray | None) -> TriangleMesh:
    vertices = np.array([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]], dtype=np.float64)
    faces = np.array([[0, 1, 2], [0, 2, 3]])
    return TriangleMesh(vertices=vertices, faces=faces, normals=normals)


def test_a_flat_quad_with_its_face_normal_as_vertex_normals_renders_as_without(device):
    rotation = [{"rotate": {"axis": [1, 0.3, 0], "angle": -35}}]
    images = []
    for normals in (None, np.tile([0.0, 0.0, 1.0], (4, 1))):
        shape = spectrace.shape(_quad(normals), spectrace.plastic((0.6, 0.4, 0.2), roughness=0.3), transform=rotation)
        scene = Scene(
            camera=spectrace.Camera(origin=(0.0, 0.0, 3.0), target=(0.0, 0.0, 0.0), fov_degrees=60.0),
            width=12, height=12, shapes=[shape], max_depth=4, spp=16, seed=2,
            lights=[spectrace.point_light((1.0, 1.0, 2.0), intensity=4.0), spectrace.constant_environment(0.2)],
        )  # fmt: skip
        images.append(Renderer(scene, device).render().xyz[..., 1])
    flat, smooth = images
    # The same random numbers and, up to the rounding of the interpolated normal, the same frame: the same paths.
    np.testing.assert_allclose(smooth, flat, rtol=1e-3, atol=1e-5)
