"""AOVs (kernels/aov.cl, spectrace.film.aovs) against what they measure.

A camera looks straight down the -z axis at a large diffuse square in the plane z = 0, lit by a uniform
environment. Every camera ray meets the square, so: each pixel's depth is the mean over its samples of the ray
length d·√(1 + x² + y²) (x, y: the ray's direction on the image plane at unit distance), which lies between its
values at the pixel's nearest and farthest points; every position has z = 0; every normal is the square's +z; the
albedo of the Lambertian square is its reflectance's x̄-, ȳ- and z̄-weighted means, computed here from
colour-science's CIE 1931 tables. The standard error of Y is checked against the spread of independent renders.
"""

import colour
import numpy as np
import pytest

import spectrace
from spectrace.engine.renderer import Renderer
from spectrace.errors import SpectraceError
from spectrace.film.aovs import AOV_NAMES, parse_aovs
from spectrace.scene.model import Scene

DISTANCE = 4.0
FOV_DEGREES = 20.0
SIZE = 9  # odd: the middle pixel's centre is on the axis
WAVELENGTHS = np.arange(360.0, 831.0)
# A reddish reflectance, tabulated at 1 nm so the renderer's grid holds it exactly.
REFLECTANCE = 0.15 + 0.7 * np.exp(-(((WAVELENGTHS - 610.0) / 60.0) ** 2))


def _plane_scene(aovs=AOV_NAMES, spp: int = 16, seed: int = 0, near_clip: float = 0.0) -> Scene:
    camera = spectrace.Camera(
        origin=(0.0, 0.0, DISTANCE), target=(0.0, 0.0, 0.0), fov_degrees=FOV_DEGREES, near_clip=near_clip
    )
    square = spectrace.shape(
        "rectangle", spectrace.diffuse(spectrace.spectrum((WAVELENGTHS, REFLECTANCE))), transform=[{"scale": 10.0}]
    )
    return Scene(
        camera=camera,
        width=SIZE,
        height=SIZE,
        shapes=[square],
        lights=[spectrace.constant_environment(1.0)],
        spp=spp,
        seed=seed,
        sampler="independent",
        aovs=tuple(aovs),
    )


def _render(device, scene: Scene, spp: int | None = None, pass_spp: int | None = None):
    return Renderer(scene, device).render(spp=spp, pass_spp=pass_spp)


@pytest.mark.parametrize("near_clip", [0.0, 1.0])
def test_depth_position_and_normal_of_a_plane(device, near_clip):
    """With a near clip the camera rays start on the clip plane and depth is measured from there, as Mitsuba 3's
    depth AOV is (its perspective camera moves the ray origin onto that plane too)."""
    image = _render(device, _plane_scene(near_clip=near_clip))
    distance = DISTANCE - near_clip
    tan_half = np.tan(np.radians(FOV_DEGREES / 2))
    edges = (2.0 * np.arange(SIZE + 1) / SIZE - 1.0) * tan_half  # pixel edges on the image plane
    # Ray length over a pixel: smallest where |x|, |y| are smallest, largest at the farthest corner.
    nearest = np.where(edges[:-1] * edges[1:] <= 0, 0.0, np.minimum(abs(edges[:-1]), abs(edges[1:])))
    farthest = np.maximum(abs(edges[:-1]), abs(edges[1:]))
    low = distance * np.sqrt(1 + nearest[:, None] ** 2 + nearest[None, :] ** 2)
    high = distance * np.sqrt(1 + farthest[:, None] ** 2 + farthest[None, :] ** 2)
    depth = image.aovs["depth"].astype(np.float64)
    assert np.all(depth >= low * (1 - 1e-6)) and np.all(depth <= high * (1 + 1e-6))
    middle = SIZE // 2
    assert depth[middle, middle] == pytest.approx(distance, rel=high[middle, middle] / distance - 1 + 1e-6)
    position = image.aovs["position"]
    np.testing.assert_allclose(position[..., 2], 0.0, atol=1e-6)
    # x, y lie within the pixel's footprint on the plane (image right is world -x, see Camera.basis).
    assert np.all(np.abs(position[..., :2]) <= DISTANCE * tan_half * (1 + 1e-6))
    np.testing.assert_allclose(image.aovs["normal"], np.broadcast_to([0.0, 0.0, 1.0], (SIZE, SIZE, 3)), atol=1e-6)


def test_albedo_of_a_diffuse_wall_is_its_reflectances_weighted_mean(device):
    spp = 64
    image = _render(device, _plane_scene(("albedo",), spp=spp))
    expected = _weighted_means(REFLECTANCE)
    albedo = image.aovs["albedo"].reshape(-1, 3).astype(np.float64)
    # The albedo's only noise is the film's wavelength sampling; pixels are independent (independent sampler).
    mean = albedo.mean(axis=0)
    standard_error = albedo.std(axis=0, ddof=1) / np.sqrt(len(albedo))
    # 1e-4: the kernels interpolate the tables linearly between the 1 nm points, this sums at them.
    assert np.all(np.abs(mean - expected) <= 5 * standard_error + 1e-4), (mean, expected, standard_error)
    assert np.all(standard_error < 0.01 * expected)  # the check is sharp enough to mean something


def _weighted_means(reflectance: np.ndarray) -> np.ndarray:
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"].copy().align(colour.SpectralShape(360, 830, 1))
    weights = cmfs.values  # (471, 3) x̄, ȳ, z̄ at 1 nm
    return (reflectance[:, None] * weights).sum(axis=0) / weights.sum(axis=0)


@pytest.mark.parametrize("integrator", ["path", "direct"])
def test_albedo_follows_the_specular_chain(device, integrator):
    """A mirror of reflectance R at z = 0 faces the camera; behind the camera a diffuse wall of reflectance ρ at
    z = 8 faces it. Depth and normal are the mirror's; the albedo is the wall's seen through the mirror: R·ρ."""
    mirror_reflectance = 0.9 - 0.5 * (WAVELENGTHS - 360.0) / 470.0  # bluish
    camera = spectrace.Camera(origin=(0.0, 0.0, DISTANCE), target=(0.0, 0.0, 0.0), fov_degrees=FOV_DEGREES)
    mirror = spectrace.shape(
        "rectangle", spectrace.mirror(spectrace.spectrum((WAVELENGTHS, mirror_reflectance))), transform=[{"scale": 10}]
    )
    wall = spectrace.shape(
        "rectangle",
        spectrace.diffuse(spectrace.spectrum((WAVELENGTHS, REFLECTANCE))),
        transform=[{"scale": 20.0}, {"translate": [0.0, 0.0, 2 * DISTANCE]}],
    )
    scene = Scene(
        camera=camera,
        width=SIZE,
        height=SIZE,
        shapes=[mirror, wall],
        lights=[spectrace.constant_environment(1.0)],
        integrator=integrator,
        sampler="independent",
        aovs=("albedo", "normal", "depth"),
    )
    image = _render(device, scene, spp=64)
    np.testing.assert_allclose(image.aovs["normal"], np.broadcast_to([0.0, 0.0, 1.0], (SIZE, SIZE, 3)), atol=1e-6)
    assert np.all(image.aovs["depth"] < DISTANCE * 1.05)  # the mirror's (the wall's would be about 3x this)
    albedo = image.aovs["albedo"].reshape(-1, 3).astype(np.float64)
    mean, standard_error = albedo.mean(axis=0), albedo.std(axis=0, ddof=1) / np.sqrt(len(albedo))
    expected = _weighted_means(mirror_reflectance * REFLECTANCE)
    assert np.all(np.abs(mean - expected) <= 5 * standard_error + 1e-4), (mean, expected, standard_error)
    assert not np.allclose(expected, _weighted_means(REFLECTANCE), rtol=0.05)  # the mirror's colour matters


def test_the_standard_error_of_y_matches_the_spread_of_independent_renders(device):
    """Each pixel's reported standard error of its mean Y, squared and averaged over replicas, against the variance
    of its mean Y over independent replicas (different seeds); the difference's mean over the pixels within 5 of
    its own standard errors, and the ratio of the averages near 1."""
    scene = spectrace.load_scene(spectrace.resources.scenes_dir() / "cornell_box.toml").with_overrides(
        width=12, height=12, sampler="independent", aovs=("variance",), max_depth=3
    )
    replicas, spp = 12, 8
    means, reported = [], []
    for seed in range(replicas):
        image = _render(device, scene.with_overrides(seed=100 + seed), spp=spp)
        means.append(image.xyz[..., 1].astype(np.float64).ravel())
        reported.append(image.aovs["variance"].astype(np.float64).ravel() ** 2)
    empirical = np.var(np.array(means), axis=0, ddof=1)
    predicted = np.mean(np.array(reported), axis=0)
    difference = empirical - predicted
    standard_error = difference.std(ddof=1) / np.sqrt(difference.size)
    assert abs(difference.mean()) <= 5 * standard_error, (difference.mean(), standard_error)
    assert 0.7 < empirical.mean() / predicted.mean() < 1.4


def test_aovs_are_split_invariant_and_leave_the_image_alone(device):
    scene = _plane_scene(spp=6)
    whole = _render(device, scene)
    split = _render(device, scene, pass_spp=4)  # passes of 4 and 2
    for name in AOV_NAMES:
        assert np.array_equal(whole.aovs[name], split.aovs[name], equal_nan=True), name
    assert np.array_equal(whole.xyz, split.xyz)
    plain = _render(device, _plane_scene(aovs=(), spp=6))
    assert plain.aovs == {}
    # The same paths: the colour agrees to float rounding (the compiler may contract differently).
    np.testing.assert_allclose(whole.xyz, plain.xyz, rtol=1e-5, atol=1e-7)


def test_a_checkpoint_carries_the_aovs(device):
    scene = _plane_scene(spp=4)
    first = Renderer(scene, device)
    first.render(spp=2)
    state = first.film.save_state()
    assert "aov_film" in state.buffers
    resumed = Renderer(scene, device)
    resumed.film.restore_state(state)
    continued = resumed.render(spp=4)
    uninterrupted = _render(device, scene, spp=4)
    for name in AOV_NAMES:
        assert np.array_equal(continued.aovs[name], uninterrupted.aovs[name]), name
    plain = Renderer(_plane_scene(aovs=(), spp=4), device)
    with pytest.raises(SpectraceError, match="aov_film"):
        plain.film.restore_state(state)


def test_film_aovs_in_a_scene_file(tmp_path):
    from scene_text import CAMERA_FILM_GREY

    path = tmp_path / "scene.toml"
    text = CAMERA_FILM_GREY + '[[shapes]]\ntype = "rectangle"\nmaterial = "grey"\n'
    path.write_text(text.replace("height = 6\n", 'height = 6\naovs = ["variance", "albedo"]\n'))
    assert spectrace.load_scene(path).aovs == ("albedo", "variance")
    path.write_text(text.replace("height = 6\n", 'height = 6\naovs = ["shadow"]\n'))
    with pytest.raises(SpectraceError, match=r"film\.aovs"):
        spectrace.load_scene(path)


def test_aov_names_are_checked():
    assert parse_aovs("normal, albedo,normal") == ("albedo", "normal")
    assert parse_aovs(["variance"]) == ("variance",)
    with pytest.raises(SpectraceError, match="unknown AOV 'bogus'"):
        parse_aovs("albedo,bogus", where="--aov")
    with pytest.raises(SpectraceError, match="unknown AOV"):
        spectrace.render(_plane_scene(aovs=()), aovs=["depth", "z"], progress=False)


@pytest.mark.parametrize("scene_kind", ["plane", "cornell"])
def test_the_wavefront_records_the_megakernels_aovs(device, scene_kind):
    """The two kernel shapes run the same per-segment function and add each pixel's samples in the same order, so
    their AOVs (and images) agree: bit for bit where the compiler contracts the two kernels alike, else to float
    rounding. The Cornell box brings a directly seen light (the emission AOV) and bounces."""
    from spectrace.engine.wavefront import make_renderer
    from spectrace.resources import scenes_dir

    if scene_kind == "plane":
        scene = _plane_scene(spp=6)
    else:
        scene = spectrace.load_scene(scenes_dir() / "cornell_box.toml").with_overrides(
            width=12, height=12, aovs=AOV_NAMES, spp=3
        )
    mega = make_renderer(scene, device, "megakernel").render(pass_spp=4)
    wave = make_renderer(scene, device, "wavefront").render(pass_spp=4)
    assert set(wave.aovs) == set(mega.aovs)
    identical_colour = np.array_equal(wave.xyz, mega.xyz)
    for name, values in mega.aovs.items():
        if identical_colour:
            assert np.array_equal(wave.aovs[name], values, equal_nan=True), name
        np.testing.assert_allclose(wave.aovs[name], values, rtol=1e-5, atol=1e-6, err_msg=name)
    np.testing.assert_allclose(wave.xyz, mega.xyz, rtol=1e-5, atol=1e-6)
    if scene_kind == "cornell":
        assert mega.aovs["emission"].any()  # the light is in view


# A greenish-yellow emission spectrum, tabulated at 1 nm like REFLECTANCE.
EMISSION = 0.5 + 2.0 * np.exp(-(((WAVELENGTHS - 560.0) / 40.0) ** 2))


def _film_xyz(radiance: np.ndarray) -> np.ndarray:
    """Film XYZ of a radiance on the 1 nm grid: ∫ L x̄ȳz̄ dλ / ∫ȳ (trapezoid rule), from colour-science's tables."""
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"].copy().align(colour.SpectralShape(360, 830, 1))
    weights = np.ones(len(WAVELENGTHS))
    weights[[0, -1]] = 0.5
    table = cmfs.values * weights[:, None]
    return (radiance[:, None] * table).sum(axis=0) / table[:, 1].sum()


@pytest.mark.parametrize("integrator", ["path", "direct"])
@pytest.mark.parametrize("where", ["environment", "area light"])
def test_the_emission_aov_is_the_expected_value_of_the_emission_seen(device, where, integrator):
    """A camera sees only emission (a constant environment, or an emitting square filling the view in front of a
    black one): the emission AOV is its spectrum's film XYZ in every pixel (colour-science's tables), without the
    colour noise of sampled wavelengths, and emission_sampled is the image itself (all of it is that emission).
    Both integrators that follow camera paths record it."""
    spectrum = spectrace.spectrum((WAVELENGTHS, EMISSION))
    scene = _plane_scene(aovs=("emission",), spp=8).with_overrides(integrator=integrator)
    if where == "environment":
        scene = scene.with_overrides(shapes=[], lights=[spectrace.constant_environment(spectrum)])
    else:
        emitter = spectrace.shape(
            "rectangle", spectrace.diffuse(0.0), emitter=spectrace.area_emitter(spectrum), transform=[{"scale": 10}]
        )
        scene = scene.with_overrides(shapes=[emitter], lights=[])
    image = _render(device, scene)
    assert set(image.aovs) == {"emission", "emission_sampled"}
    expected = _film_xyz(EMISSION)
    # 2e-4: the kernels integrate the linear interpolation of the tables, this sums at the 1 nm points.
    np.testing.assert_allclose(
        image.aovs["emission"].reshape(-1, 3), np.broadcast_to(expected, (SIZE * SIZE, 3)), rtol=2e-4
    )
    np.testing.assert_allclose(image.aovs["emission_sampled"], image.xyz, rtol=1e-5, atol=1e-6)
    # The sampled emission does carry colour noise, and its mean over pixels is the expected value.
    sampled = image.aovs["emission_sampled"].reshape(-1, 3).astype(np.float64)
    standard_error = sampled.std(axis=0, ddof=1) / np.sqrt(len(sampled))
    assert np.all(standard_error > 1e-3 * expected)
    assert np.all(np.abs(sampled.mean(axis=0) - expected) <= 5 * standard_error)


def test_the_emission_aov_holds_only_what_the_camera_rays_meet(device):
    """The lit diffuse plane sends no emission of its own: emission and emission_sampled are 0 there, though the
    image is not."""
    image = _render(device, _plane_scene(aovs=("emission",), spp=2))
    assert image.xyz[..., 1].min() > 0
    assert not image.aovs["emission"].any() and not image.aovs["emission_sampled"].any()
