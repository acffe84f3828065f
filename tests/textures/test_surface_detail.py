"""Normal maps, bump maps and opacity against closed-form radiometry and independent geometry.

A Lambertian plane of albedo ρ under a distant light of irradiance E reflects L = ρ/π · E · max(0, n·l): a normal
map or bump map that tilts every normal by θ must give the value of the plane actually tilted by θ (the rectangle
rotated), and the closed form. Lit by a distant light only (a delta light, which BSDF sampling cannot reach), a
radiance meter's reading has no noise, so those comparisons are to float rounding. Opacity: a surface of opacity α
between a light and a meter passes the fraction 1 − α of the light; the meters' standard errors (fixed seeds) set
the tolerances.
"""

import dataclasses
import functools
import inspect

import numpy as np
import pytest
from PIL import Image as PILImage

import spectrace
from cli_runner import run_in_process, run_spectrace
from scene_text import camera_film
from spectrace.engine.meters import FluxMeter, IrradianceMeter, RadianceMeter, measure
from spectrace.engine.renderer import Renderer
from spectrace.engine.wavefront import make_renderer
from spectrace.errors import SpectraceError
from spectrace.geometry.mesh import TriangleMesh
from spectrace.materials import MATERIALS, surface
from spectrace.scene.loader import load_scene
from spectrace.scene.model import Scene
from stats_toolkit import assert_within_standard_errors

ALBEDO = 0.5
IRRADIANCE = 2.0
THETA = np.radians(25.0)  # the tilt
PHI = np.radians(40.0)  # the light's angle from the plane's normal
CAMERA = spectrace.Camera(origin=(0.0, 0.0, 4.0), target=(0.0, 0.0, 0.0), fov_degrees=30.0)
# The rectangle spans [-1, 1]² in z = 0, facing +z, u along +x and v down its image (so "up" in the image is +y).
X, Y = np.eye(3)[0], np.eye(3)[1]


def _plane_scene(material, toward_light, transform=(), lights=None) -> Scene:
    plane = spectrace.shape("rectangle", material, transform=list(transform))
    lights = lights if lights is not None else [spectrace.distant_light(tuple(-np.asarray(toward_light)), IRRADIANCE)]
    return Scene(camera=CAMERA, width=4, height=4, shapes=[plane], lights=lights, max_depth=2, seed=1)


def _radiance(scene: Scene, streams: int = 8, samples: int = 8, origin=(0.0, 0.0, 3.0)) -> tuple[float, float]:
    """Radiance seen straight down onto the plane's centre (u = v = ½), at 550 nm."""
    reading = measure(
        scene, RadianceMeter(origin, (0.0, 0.0, -1.0)), wavelengths_nm=[550.0], streams=streams,
        samples_per_item=samples, seed=3,
    )  # fmt: skip
    return float(reading.spectral[0]), float(reading.spectral_standard_error[0])


def _constant_normal_map(normal) -> object:
    """A raw 2 × 2 map whose every texel encodes `normal` (tangent space) as c = (n + 1) / 2."""
    return spectrace.bitmap(np.full((2, 2, 3), (np.asarray(normal, float) + 1.0) / 2.0))


def _toward(axis: np.ndarray, angle: float) -> np.ndarray:
    return np.sin(angle) * axis + np.cos(angle) * np.array([0.0, 0.0, 1.0])


# The red channel tilts toward +u (+x), the green toward the top of the image seen from the front (+y): OpenGL's
# convention, and Mitsuba 3's frame (x along dp/du, y = n × x). Rotations that tilt +z the same way:
TILTS = {
    "red (+u)": (X, {"rotate": {"axis": [0, 1, 0], "angle": float(np.degrees(THETA))}}),
    "green (up in the image)": (Y, {"rotate": {"axis": [1, 0, 0], "angle": -float(np.degrees(THETA))}}),
}


@pytest.mark.parametrize("name", list(TILTS))
def test_constant_normal_map_shades_like_the_tilted_plane(name):
    axis, rotation = TILTS[name]
    light = _toward(axis, PHI)
    expected = ALBEDO / np.pi * IRRADIANCE * np.cos(PHI - THETA)
    mapped, mapped_se = _radiance(
        _plane_scene(spectrace.diffuse(ALBEDO, normal_map=_constant_normal_map(_toward(axis, THETA))), light)
    )
    tilted, tilted_se = _radiance(_plane_scene(spectrace.diffuse(ALBEDO), light, [rotation]))
    assert_within_standard_errors(mapped, expected, mapped_se, slack=2e-6, what=f"normal map {name}")
    assert_within_standard_errors(tilted, expected, tilted_se, slack=2e-6, what=f"tilted plane {name}")
    # The tilt's sense matters: the same light on the opposite side sees cos(φ + θ).
    opposite, _ = _radiance(
        _plane_scene(
            spectrace.diffuse(ALBEDO, normal_map=_constant_normal_map(_toward(axis, THETA))), _toward(axis, -PHI)
        )
    )
    assert opposite == pytest.approx(ALBEDO / np.pi * IRRADIANCE * np.cos(PHI + THETA), rel=1e-5)


def test_constant_slope_bump_map_shades_like_the_tilted_plane():
    """Heights falling along u: h = 1 − u (a raw ramp, texel centres exact, clamped) times bump_scale. On the
    rectangle dp/du = 2, so the surface rises by −bump_scale / 2 per unit x: the normal tilts toward +x by θ when
    bump_scale = 2 tan θ."""
    width = 16
    ramp = np.tile(1.0 - (np.arange(width) + 0.5) / width, (4, 1))
    bumps = spectrace.bitmap(ramp, wrap="clamp")
    light = _toward(X, PHI)
    material = spectrace.diffuse(ALBEDO, bump_map=bumps, bump_scale=2.0 * np.tan(THETA))
    bumped, bumped_se = _radiance(_plane_scene(material, light))
    tilted, _ = _radiance(_plane_scene(spectrace.diffuse(ALBEDO), light, [TILTS["red (+u)"][1]]))
    expected = ALBEDO / np.pi * IRRADIANCE * np.cos(PHI - THETA)
    assert_within_standard_errors(bumped, expected, bumped_se, slack=2e-6, what="bump map")
    assert bumped == pytest.approx(tilted, rel=1e-5)


# Mitsuba 3's shadowing term (docs/textures.md, "Mitsuba's normalmap defaults"): a constant map tilted 27° across the
# plane of a distant light 26.6° above the surface (tan = ½), as in tests/interop/test_mitsuba_normal_map_convention.py.
SHADOW_TILT = np.radians(27.0)
SHADOW_ELEVATION = np.arctan(0.5)


def _conty_estevez(tilt: float, light_from_normal: float) -> float:
    """G = 2 / (1 + √(1 + α² tan² θl)), α² = min(1, tan²(tilt) / 8): Conty Estevez, Pearce & Kulla 2019, Ray
    Tracing Gems ch. 12, eq. 5 with their choice of α."""
    alpha2 = min(1.0, np.tan(tilt) ** 2 / 8.0)
    return 2.0 / (1.0 + np.sqrt(1.0 + alpha2 * np.tan(light_from_normal) ** 2))


def _shadowing_scene(shadowing: bool, bump: bool = False, **overrides) -> Scene:
    light = np.array([np.cos(SHADOW_ELEVATION), 0.0, np.sin(SHADOW_ELEVATION)])  # toward the light, along +x
    if bump:  # heights falling along v tilt the normal toward +y (the rectangle's v runs down its image, −y)
        width = 16
        ramp = np.tile((1.0 - (np.arange(width)[:, None] + 0.5) / width), (1, 4))
        detail = {"bump_map": spectrace.bitmap(ramp, wrap="clamp"), "bump_scale": -2.0 * np.tan(SHADOW_TILT)}
    else:
        detail = {"normal_map": _constant_normal_map(_toward(Y, SHADOW_TILT))}
    material = spectrace.diffuse(ALBEDO, shadowing_function=shadowing, **detail)
    return dataclasses.replace(_plane_scene(material, light), **overrides)


@pytest.mark.parametrize("bump", [False, True], ids=["normal map", "bump map"])
def test_shadowing_function_scales_the_tilted_planes_radiance_by_its_closed_form(bump):
    """L = ρ/π · E · (n'·l) · G, n' the tilted normal: a distant light is noise-free, so to float rounding. The tilt
    is across the light's plane, so n'·l = cos(tilt) sin(elevation); G = 0.9695, 3.0 % darker."""
    light_from_normal = np.pi / 2 - SHADOW_ELEVATION
    plain = ALBEDO / np.pi * IRRADIANCE * np.cos(SHADOW_TILT) * np.sin(SHADOW_ELEVATION)
    expected = plain * _conty_estevez(SHADOW_TILT, light_from_normal)
    on, on_se = _radiance(_shadowing_scene(True, bump))
    off, off_se = _radiance(_shadowing_scene(False, bump))
    assert_within_standard_errors(off, plain, off_se, slack=2e-6, what="without the term")
    assert_within_standard_errors(on, expected, on_se, slack=2e-6, what="with the term")
    assert on / off < 0.975


@pytest.mark.parametrize("integrator", ["path", "wavefront", "direct", "light", "bdpt", "sppm"])
def test_shadowing_function_darkens_every_integrators_image_by_g_of_the_lights_direction(device, integrator):
    """The term is part of the BSDF's value wherever it is evaluated or sampled. It changes no draw, so with one seed
    each pixel's ratio with and without it is G to float rounding. The light tracer and photons walk from the light,
    where the sampled direction is the viewer's: G of the viewer's direction (straight down, G = 1) there would
    leave the image unchanged."""
    scene_kind = "path" if integrator == "wavefront" else integrator
    images = []
    for shadowing in (False, True):
        scene = _shadowing_scene(shadowing, width=4, height=4, spp=8, integrator=scene_kind)
        renderer = make_renderer(scene, device, **({"kernel": "wavefront"} if integrator == "wavefront" else {}))
        images.append(renderer.render().xyz[..., 1].astype(np.float64))
    lit = images[0] > 0.0
    assert np.count_nonzero(lit) >= 8
    expected = _conty_estevez(SHADOW_TILT, np.pi / 2 - SHADOW_ELEVATION)
    assert images[1][lit] / images[0][lit] == pytest.approx(np.full(np.count_nonzero(lit), expected), rel=2e-6)
    assert not np.any(images[1][~lit])


def _wall_lit_by_the_floor() -> Scene:
    """A wall lit only by a normal-mapped floor under light 10° above it (G = 0.82 of the light's direction); the
    camera sees as much of the wall as it can without the floor."""
    elevation, tilt = np.radians(10.0), np.radians(27.0)
    normal_map = _constant_normal_map(np.array([np.sin(tilt), 0.0, np.cos(tilt)]))
    floor = spectrace.shape("rectangle", spectrace.diffuse(0.8, normal_map=normal_map, shadowing_function=True))
    wall = spectrace.shape(
        "rectangle",
        spectrace.diffuse(0.8),
        transform=[{"rotate": {"axis": [0, 1, 0], "angle": -90}}, {"translate": [0.2, 0, 1.0]}],
    )  # faces −x, edge-on to the light: lit by the floor alone
    light = spectrace.distant_light((0.0, -np.cos(elevation), -np.sin(elevation)), 2.0)
    camera = spectrace.Camera(origin=(-1.0, 0.0, 1.0), target=(0.2, 0.0, 1.0), fov_degrees=60.0)
    return Scene(camera=camera, width=6, height=6, shapes=[floor, wall], lights=[light], max_depth=3)


WALL_SPP = {"path": 512, "bdpt": 128, "sppm": 768, "light": 2048}


@functools.cache
def _wall_means(device, kind: str) -> tuple[float, float]:
    """The mean of the wall's image over 16 seeds and its standard error (their spread). The seeds are the same
    scene, so one renderer renders them all (a new seed uploads nothing: the film and the passes start again); the
    path tracer's means are every integrator's reference, rendered once."""
    scene = dataclasses.replace(_wall_lit_by_the_floor(), integrator=kind, spp=WALL_SPP[kind])
    renderer = make_renderer(scene, device)
    values = []
    for seed in range(1, 17):
        renderer.replace_scene(dataclasses.replace(scene, seed=seed), renderer.buffers, ())
        values.append(renderer.render().xyz[..., 1].mean())
    return float(np.mean(values)), float(np.std(values, ddof=1) / np.sqrt(len(values)))


@pytest.mark.slow
@pytest.mark.parametrize("integrator", ["light", "sppm", "bdpt"])
def test_shadowing_function_follows_the_light_when_paths_start_from_it(device, integrator):
    """A wall lit only by a normal-mapped floor under light 10° above it (G = 0.82 of the light's direction): walks
    from the light sample the floor's outgoing direction, so the term must take their incoming one (the light's) for
    the image to be the path tracer's (taking the sampled direction's instead makes the floor's bounce about 24 %
    brighter). The camera sees as much of the wall as it can without the floor, and each integrator renders enough
    that its mean resolves 5 % (its power, in the message; about 2 % for BDPT, 4 % for SPPM and the light tracer):
    BDPT a quarter of the path tracer's samples, SPPM 1.5 times them, the light tracer 4 times. Means of 16 seeds,
    their spread the standard error."""
    reference, reference_se = _wall_means(device, "path")
    ours, ours_se = _wall_means(device, integrator)
    assert_within_standard_errors(ours, reference, np.hypot(ours_se, reference_se), what=integrator, power=0.05)


@pytest.mark.parametrize("filter_name", ["bilinear", "trilinear", "nearest"])
def test_a_linear_height_field_turns_every_normal_to_its_closed_form(device, filter_name):
    """Heights h = a·u + b·v at the texel centres of an 8 × 8 raw map (clamped): the bilinear interpolant is that
    plane exactly between the outer texel centres, so its gradient is (a, b) at every point there, and on the
    rectangle (dp/du = 2 x̂, dp/dv = −2 ŷ: v runs down the image, whose top is +y) the bumped surface's tangents are
    (2, 0, s·a) and (0, −2, s·b): the normal is (−s·a/2, s·b/2, 1) normalised. The camera sees uv in about
    [0.15, 0.85], inside that region, so every pixel's normal AOV is the closed form. A nearest lookup is a step
    function with no derivative: the normal stays +z (Mitsuba 3's bitmap gives a zero gradient there too)."""
    size, texels, a, b, scale = 8, 8, 2.0 * np.tan(np.radians(25.0)), -2.0 * np.tan(np.radians(10.0)), 1.0
    centres = (np.arange(texels) + 0.5) / texels
    heights = 1.0 + a * centres[None, :] + b * centres[:, None]  # row j holds v = centres[j]; no negative heights
    bumps = spectrace.bitmap(heights, wrap="clamp", filter=filter_name)
    plane = spectrace.shape("rectangle", spectrace.diffuse(ALBEDO, bump_map=bumps, bump_scale=scale))
    camera = spectrace.Camera(origin=(0.0, 0.0, 4.0), target=(0.0, 0.0, 0.0), fov_degrees=20.0)
    scene = Scene(
        camera=camera, width=size, height=size, shapes=[plane], lights=[spectrace.constant_environment(1.0)],
        max_depth=1, spp=4, seed=1, aovs=("normal",),
    )  # fmt: skip
    normals = Renderer(scene, device).render().aovs["normal"].astype(np.float64)
    expected = np.array([-scale * a / 2.0, scale * b / 2.0, 1.0]) if filter_name != "nearest" else np.eye(3)[2]
    expected /= np.linalg.norm(expected)
    np.testing.assert_allclose(normals, np.broadcast_to(expected, normals.shape), atol=2e-5)


def test_normal_map_in_a_furnace_loses_only_the_wedge_below_the_surface():
    """A white Lambertian plane in a uniform environment of radiance 1 with every normal tilted by θ: directions
    above the tilted normal but below the plane are dropped (shading_normal.cl, rule 2), the cosine-weighted
    fraction (1 − cos θ)/2 of them (the great circle of the plane projects onto the tilted normal's unit disk as a
    half ellipse of semi-axes 1 and cos θ). So the reflected radiance is (1 + cos θ)/2: never above 1 (no energy is
    created), and exactly 1 for an untilted map."""
    furnace = [spectrace.constant_environment(1.0)]
    for tilt, expected in ((0.0, 1.0), (THETA, (1.0 + np.cos(THETA)) / 2.0), (np.radians(60.0), 0.75)):
        material = spectrace.diffuse(1.0, normal_map=_constant_normal_map(_toward(X, tilt)))
        scene = _plane_scene(material, X, lights=furnace)
        value, se = _radiance(dataclasses.replace(scene, max_depth=8), streams=32, samples=64)
        assert_within_standard_errors(value, expected, se, slack=1e-5, what=f"furnace, tilt {np.degrees(tilt):.0f}°")


def _view_factor_corner(a: float, b: float, c: float) -> float:
    """Point-to-parallel-rectangle view factor: a × b rectangle at distance c, the point below one corner."""
    A, B = a / c, b / c
    return (
        A / np.sqrt(1 + A * A) * np.arctan(B / np.sqrt(1 + A * A))
        + B / np.sqrt(1 + B * B) * np.arctan(A / np.sqrt(1 + B * B))
    ) / (2.0 * np.pi)


def _downward_light(height: float, radiance: float = 1.0):
    """A one-sided 2 × 2 emitting rectangle at z = height facing −z."""
    return spectrace.shape(
        "rectangle", spectrace.diffuse(0.0), emitter=spectrace.area_emitter(radiance),
        transform=[{"rotate": {"axis": [1, 0, 0], "angle": 180}}, {"translate": [0, 0, height]}],
    )  # fmt: skip


def test_constant_opacity_passes_the_rest_of_an_area_lights_irradiance():
    """E below the centre of a 2 × 2 light of radiance 1 at height 1 is π L · 4 F(1, 1, 1); a black sheet of opacity
    0.3 between them leaves 0.7 of it (next-event and BSDF-sampled rays both pass through it)."""
    sheet = spectrace.shape(
        "rectangle", spectrace.diffuse(0.0, opacity=0.3), transform=[{"scale": 3.0}, {"translate": [0, 0, 0.5]}]
    )
    scene = Scene(camera=CAMERA, width=4, height=4, shapes=[_downward_light(1.0), sheet], lights=[], max_depth=2)
    reading = measure(
        scene, IrradianceMeter((0, 0, 0), (0, 0, 1)), wavelengths_nm=[550.0], streams=64, samples_per_item=64, seed=2
    )
    expected = 0.7 * np.pi * 4.0 * _view_factor_corner(1.0, 1.0, 1.0)
    assert_within_standard_errors(
        reading.spectral[0], expected, reading.spectral_standard_error[0], what="E", power=0.05
    )


def test_checker_opacity_in_front_of_a_light_passes_half_its_flux():
    """A checkerboard of opacity 0 and 1 (2 × 2 squares) just below a one-sided light of radiance 1 and area 4
    covers half of it: the flux leaving the sphere around both is ½ π L A = 2π."""
    checker = spectrace.checkerboard(0.0, 1.0)
    mask = spectrace.shape(
        "rectangle", spectrace.diffuse(0.0, opacity=checker), transform=[{"translate": [0, 0, 0.999]}]
    )
    scene = Scene(camera=CAMERA, width=4, height=4, shapes=[_downward_light(1.0), mask], lights=[], max_depth=2)
    reading = measure(
        scene, FluxMeter((0.0, 0.0, 1.0), 3.0), wavelengths_nm=[550.0], streams=64, samples_per_item=640, seed=4
    )
    assert_within_standard_errors(
        reading.spectral[0], 2.0 * np.pi, reading.spectral_standard_error[0], slack=5e-3, what="Φ", power=0.05
    )


def test_half_transparent_occluder_halves_a_point_lights_irradiance():
    """E = I cos θ / d² from a point light, halved by a sheet of opacity 0.5 in between. The meter's shadow ray is
    the same ray every sample: the sensor's per-sample salt makes each sample's choice its own."""
    light = spectrace.point_light((0.3, 0.0, 2.0), intensity=5.0)
    sheet = spectrace.shape(
        "rectangle", spectrace.diffuse(0.0, opacity=0.5), transform=[{"scale": 3.0}, {"translate": [0, 0, 1.0]}]
    )
    scene = Scene(camera=CAMERA, width=4, height=4, shapes=[sheet], lights=[light], max_depth=2)
    reading = measure(
        scene, IrradianceMeter((0, 0, 0), (0, 0, 1)), wavelengths_nm=[550.0], streams=64, samples_per_item=128, seed=5
    )
    d2 = 0.3**2 + 2.0**2
    expected = 0.5 * 5.0 * (2.0 / np.sqrt(d2)) / d2
    assert_within_standard_errors(
        reading.spectral[0], expected, reading.spectral_standard_error[0], what="E", power=0.05
    )


def test_camera_rays_pass_a_cut_out_sheet_in_front_of_an_emitter(device):
    """Looking at an emitter of radiance 1 (Y = 1) through a black sheet of opacity 0.3 that covers the whole view:
    each sample sees 1 with probability 0.7. Passes of one sample are independent replicates."""
    emitter = spectrace.shape(
        "rectangle", spectrace.diffuse(0.0), emitter=spectrace.area_emitter(1.0), transform=[{"scale": 5.0}]
    )
    sheet = spectrace.shape(
        "rectangle", spectrace.diffuse(0.0, opacity=0.3), transform=[{"scale": 5.0}, {"translate": [0, 0, 1.0]}]
    )
    scene = Scene(
        camera=CAMERA, width=8, height=8, shapes=[emitter, sheet], lights=[], max_depth=2, seed=6, sampler="independent"
    )
    renderer = Renderer(scene, device)
    passes, previous = [], 0.0
    for _ in range(16):
        renderer.run_pass(1)
        total = float(renderer.read_film()[0][:, 1].astype(np.float64).sum())
        passes.append((total - previous) / 64.0)
        previous = total
    passes = np.array(passes)
    assert_within_standard_errors(passes.mean(), 0.7, passes.std(ddof=1) / np.sqrt(len(passes)), what="Y")


def test_cut_outs_render_the_same_however_split(device):
    sheet = spectrace.shape("rectangle", spectrace.diffuse(0.8, opacity=0.5), transform=[{"translate": [0, 0, 0.5]}])
    floor = spectrace.shape("rectangle", spectrace.diffuse(0.5), transform=[{"scale": 3.0}])
    scene = Scene(camera=CAMERA, width=8, height=8, shapes=[_downward_light(2.0), sheet, floor], spp=4, seed=2)
    whole, split = Renderer(scene, device), Renderer(scene, device)
    whole.run_pass(4)
    split.run_pass(1)
    split.run_pass(3)
    assert np.array_equal(whole.read_film()[0], split.read_film()[0])


# ---------------------------------------------------------------- bad input


SCENE = (
    camera_film(origin="[0, 0, 3]", target="[0, 0, 0]", fov="30", width="4", height="4")
    + """
[materials.m]
type = "diffuse"
reflectance = {{ value = 0.5 }}
{detail}
[[shapes]]
type = "rectangle"
material = "m"
{emitter}
[[lights]]
type = "constant"
radiance = {{ value = 1 }}
"""
)


def _bad_inputs(tmp_path) -> list[tuple[str, str, str]]:
    """(material keys, shape keys, what the one line must start with after the file)."""
    PILImage.fromarray(np.full((2, 2), 128, np.uint8)).save(tmp_path / "grey.png")
    PILImage.fromarray(np.full((2, 2, 3), 128, np.uint8)).save(tmp_path / "normals.png")
    return [
        (
            'normal_map = { texture = "bitmap", file = "grey.png", raw = true }',
            "",
            "materials.m.normal_map: normal map",
        ),
        ('normal_map = { texture = "bitmap", file = "normals.png" }', "", "materials.m.normal_map: normal map"),
        ("opacity = 1.5", "", "materials.m.opacity: opacity must lie in [0, 1]"),
        ("opacity = -0.1", "", "materials.m.opacity: opacity must lie in [0, 1]"),
        ('opacity = { texture = "bitmap", file = "normals.png", raw = true }', "", "materials.m.opacity: texture"),
        (
            'normal_map = { texture = "bitmap", file = "normals.png", raw = true }\n'
            'bump_map = { texture = "bitmap", file = "grey.png", raw = true }',
            "",
            "materials.m.bump_map: a material takes a normal map or a bump map, not both",
        ),
        ("normal_map = { value = 0.5 }", "", "materials.m.normal_map: normal_map takes a texture"),
        ('shadowing_function = "maybe"', "", "materials.m.shadowing_function"),
        (
            "opacity = 0.5",
            "emitter = { radiance = { value = 1 } }",
            "shapes[0].material: shape 'rectangle0': an emitter",
        ),
    ]


def test_bad_surface_detail_is_one_line(tmp_path, monkeypatch, capsys):
    for detail, emitter, expected in _bad_inputs(tmp_path):
        scene = tmp_path / "scene.toml"
        scene.write_text(SCENE.format(detail=detail, emitter=emitter))
        code, err = run_in_process(monkeypatch, capsys, ["render", str(scene), "-o", str(tmp_path / "x.png")])
        lines = err.strip().splitlines()
        assert code != 0 and len(lines) == 1 and "Traceback" not in err, (detail, err)
        assert lines[0].startswith(f"error: {scene}: {expected}"), (detail, lines[0])
        assert not (tmp_path / "x.png").exists()


def test_a_scene_file_turns_the_shadowing_term_on(tmp_path):
    PILImage.fromarray(np.full((2, 2, 3), 128, np.uint8)).save(tmp_path / "normals.png")
    scene = tmp_path / "scene.toml"
    for value in (True, False):
        normal_map = 'normal_map = { texture = "bitmap", file = "normals.png", raw = true }'
        detail = f"{normal_map}\nshadowing_function = {str(value).lower()}"
        scene.write_text(SCENE.format(detail=detail, emitter=""))
        assert load_scene(scene).shapes[0].material.detail.shadowing_function is value


@pytest.mark.slow
def test_a_one_channel_normal_map_is_one_line_from_a_real_process(tmp_path):
    PILImage.fromarray(np.full((2, 2), 128, np.uint8)).save(tmp_path / "grey.png")
    scene = tmp_path / "scene.toml"
    scene.write_text(
        SCENE.format(detail='normal_map = { texture = "bitmap", file = "grey.png", raw = true }', emitter="")
    )
    result = run_spectrace("render", str(scene), "-o", str(tmp_path / "x.png"))
    lines = result.stderr.strip().splitlines()
    assert result.returncode != 0 and len(lines) == 1 and "Traceback" not in result.stderr
    assert lines[0].startswith(f"error: {scene}: materials.m.normal_map: normal map '{tmp_path / 'grey.png'}' has 1")
    assert not (tmp_path / "x.png").exists()


def test_the_api_refuses_the_same():
    grey = spectrace.bitmap(np.full((2, 2), 0.5))
    with pytest.raises(SpectraceError, match="normal map 'array' has 1 channel"):
        spectrace.diffuse(0.5, normal_map=grey)
    with pytest.raises(SpectraceError, match="opacity must lie in"):
        spectrace.plastic(0.5, opacity=2.0)
    with pytest.raises(SpectraceError, match="not both"):
        spectrace.conductor("Au", normal_map=_constant_normal_map((0, 0, 1)), bump_map=grey)


# ---------------------------------------------------------------- docs


@pytest.mark.parametrize("name", list(MATERIALS))
def test_every_material_constructor_takes_the_surface_detail_keys(name):
    signature = inspect.signature(getattr(spectrace, name))
    for parameter in surface.PARAMETERS:
        given = signature.parameters[parameter.name]
        assert given.kind is inspect.Parameter.KEYWORD_ONLY and given.default == parameter.default, name


def test_degenerate_texture_coordinates_keep_the_normal_for_a_bump_map_and_stay_finite_for_a_normal_map():
    """A quad whose corners all share one uv has no dp/du: a bump map leaves the shading normal alone (the plain
    plane's radiance, exactly) and a normal map turns it in an arbitrary frame (by the map's angle: cos(φ − θ) or
    anything down to cos(φ + θ), here a finite value in that range)."""
    quad = TriangleMesh(
        vertices=np.array([[-1.0, -1.0, 0.0], [1.0, -1.0, 0.0], [1.0, 1.0, 0.0], [-1.0, 1.0, 0.0]]),
        faces=np.array([[0, 1, 2], [0, 2, 3]]),
        uvs=np.full((4, 2), 0.5),
    )
    light = _toward(X, PHI)
    ramp = spectrace.bitmap(np.tile(np.linspace(0.0, 1.0, 8), (4, 1)))

    def seen(material) -> float:
        scene = _plane_scene(spectrace.diffuse(ALBEDO), light)
        return _radiance(dataclasses.replace(scene, shapes=[spectrace.shape(quad, material)]))[0]

    plain = ALBEDO / np.pi * IRRADIANCE * np.cos(PHI)
    assert seen(spectrace.diffuse(ALBEDO, bump_map=ramp, bump_scale=3.0)) == pytest.approx(plain, rel=1e-6)
    mapped = seen(spectrace.diffuse(ALBEDO, normal_map=_constant_normal_map(_toward(X, THETA))))
    scale = ALBEDO / np.pi * IRRADIANCE
    assert scale * np.cos(PHI + THETA) - 1e-6 <= mapped <= scale * np.cos(PHI - THETA) + 1e-6


@pytest.mark.parametrize("maps, opacity", [(True, 1.0), (False, 0.4), (True, 0.4)])
def test_the_wavefront_renders_the_megakernels_image(device, maps, opacity):
    """Both kernel shapes run paths through the same path_segment: a normal-mapped floor and a bump-mapped sheet, a
    cut-out sheet, or both, give the same image. The two shapes' code can round a normal-mapped direction
    differently in the last bit; a cut-out's choice does not depend on a ray's bits (docs/textures.md, "Opacity"),
    so that cannot become a different choice and a different image."""
    normals = np.random.default_rng(3).uniform(0.2, 0.8, (4, 4, 3))
    normals[..., 2] = 1.0
    bumps = spectrace.bitmap(np.random.default_rng(4).uniform(0.0, 1.0, (4, 4)))
    floor = spectrace.shape("rectangle", spectrace.plastic(0.5, normal_map=spectrace.bitmap(normals) if maps else None))
    sheet = spectrace.shape(
        "rectangle",
        spectrace.diffuse(0.7, bump_map=bumps if maps else None, bump_scale=0.05, opacity=opacity),
        transform=[{"scale": 0.6}, {"translate": [0, 0, 0.5]}],
    )
    camera = spectrace.Camera(origin=(0.0, -2.0, 2.0), target=(0.0, 0.0, 0.0))
    scene = Scene(camera=camera, width=12, height=12, shapes=[floor, sheet, _downward_light(1.5)], spp=4, seed=3)
    megakernel = make_renderer(scene, device).render().xyz
    wavefront = make_renderer(scene, device, kernel="wavefront").render().xyz
    assert megakernel[..., 1].mean() > 0
    assert np.array_equal(megakernel.view(np.uint32), wavefront.view(np.uint32))
