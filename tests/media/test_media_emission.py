"""Glowing media (docs/media.md, kernels/medium_emission.cl): radiance σa Le per unit length, gathered by the path
tracer's and BDPT's camera paths and a source of the light tracer's paths (kernels/light_glowing_media.cl), checked
against the closed form of an absorbing, emitting slab, a quadrature for a varying emission grid, Planck's law for a
temperature grid, the homogeneous medium for a constant grid, and the path tracer on a scattering glowing medium;
pbrt-v4's `Le`, `Lescale` and `temperature` imported; the integrators that cannot gather it refuse it in one
line."""

from dataclasses import replace

import numpy as np
import pytest
from scipy import ndimage

import spectrace
from scene_text import CAMERA_FILM_GREY
from spectrace.engine.meters import RadianceMeter, measure
from spectrace.errors import SpectraceError
from spectrace.geometry import primitives
from spectrace.geometry.grid_volume import GridVolume, box_matrix, make_grid
from spectrace.scene.model import Camera, ConstantEnvironment, Medium, Scene, Shape
from spectrace.spectral.blackbody import blackbody
from spectrace.spectral.spectrum import Spectrum
from stats_toolkit import assert_within_standard_errors

LANES_NM = np.array([430.0, 510.0, 590.0, 660.0])
SIGMA_A = np.array([0.3, 0.5, 0.8, 1.1])  # per lane, 1/unit: the slab's absorption varies with λ
EMISSION = 2.0
BACKGROUND = 0.5
DEPTH = 2.0  # the cube [-1, 1]³ crossed along z
METER = RadianceMeter((0.3, 0.2, -3.0), (0.0, 0.0, 1.0))


def _absorption() -> Spectrum:
    """σa(λ) through the lanes' values (linear between them, held beyond): a spectrum the test knows at the lanes."""
    grid = np.arange(360.0, 831.0)
    return Spectrum(np.interp(grid, LANES_NM, SIGMA_A))


def _scene(medium: Medium, background: float = BACKGROUND) -> Scene:
    return Scene(
        camera=Camera((0.0, 0.0, -1.0), (0.0, 0.0, 0.0)),
        width=1,
        height=1,
        shapes=[Shape(mesh=primitives.cube(), material=None, interior=medium)],
        lights=[ConstantEnvironment(Spectrum.constant(background))],
        max_depth=16,
    )


def _read(scene: Scene, device, samples: int = 1024):
    return measure(scene, METER, wavelengths_nm=LANES_NM, streams=32, samples_per_item=samples, device=device)


def _slab_radiance(emission_at_lanes: np.ndarray) -> np.ndarray:
    """Radiance through the absorbing, emitting slab: k exp(−σa d) + Le (1 − exp(−σa d))."""
    transmitted = np.exp(-SIGMA_A * DEPTH)
    return BACKGROUND * transmitted + emission_at_lanes * (1.0 - transmitted)


def test_an_absorbing_emitting_slab_gives_the_closed_form(device):
    """Homogeneous: the emission is added in closed form and the pure absorber's transmittance applied directly,
    so the reading has no noise: k exp(−σa d) + Le (1 − exp(−σa d)) at each lane to float precision."""
    medium = Medium(_absorption(), Spectrum.zeros(), emission=Spectrum.constant(EMISSION))
    reading = _read(_scene(medium), device, samples=16)
    np.testing.assert_allclose(reading.spectral, _slab_radiance(np.full(4, EMISSION)), rtol=2e-5)
    dark = _read(_scene(Medium(_absorption(), Spectrum.zeros())), device, samples=16)
    assert np.all(reading.spectral > dark.spectral + 0.5)  # the emission is seen


def _grid_medium(emission=None, temperature=None, n=16, sigma_s=0.0) -> Medium:
    grid = make_grid(
        np.ones((n, 2, 2), np.float32),
        box_matrix((-1, -1, -1), (1, 1, 1)),
        emission=emission,
        temperature=temperature,
    )
    glow = Spectrum.constant(EMISSION if temperature is None else 1.0)
    return Medium(_absorption(), Spectrum.constant(sigma_s), density=grid, emission=glow)


def test_an_emitting_grid_slab_gives_the_closed_form(device):
    """Through a grid of density 1 the emission is estimated at delta tracking's tentative collisions (σa Le / μ
    times the weight so far): its mean is the closed form within 4 standard errors."""
    reading = _read(_scene(_grid_medium()), device)
    assert_within_standard_errors(
        reading.spectral, _slab_radiance(np.full(4, EMISSION)), reading.spectral_standard_error, power=0.02
    )


def test_a_varying_emission_grid_gives_the_quadrature(device):
    """An emission scale of 0.2 in the slab's near half and 1.5 in its far half (along the ray), trilinear between
    the voxel centres: ∫ exp(−σa t) σa E s(t) dt from a quadrature of scipy's interpolation of the voxels."""
    n = 16
    scale = np.full((n, 2, 2), 0.2, np.float32)
    scale[n // 2 :] = 1.5
    reading = _read(_scene(_grid_medium(emission=scale, n=n)), device, samples=2048)
    t = np.linspace(0.0, DEPTH, 20_001)  # from the near face (z = −1) inward
    s = ndimage.map_coordinates(scale[:, 0, 0].astype(np.float64), [t / DEPTH * n - 0.5], order=1, mode="nearest")
    integrand = np.exp(-np.outer(t, SIGMA_A)) * SIGMA_A * EMISSION * s[:, None]
    glow = np.trapezoid(integrand, t, axis=0)
    expected = BACKGROUND * np.exp(-SIGMA_A * DEPTH) + glow
    assert_within_standard_errors(reading.spectral, expected, reading.spectral_standard_error, power=0.02)
    assert abs(glow[0] - EMISSION * 0.85 * (1 - np.exp(-SIGMA_A[0] * DEPTH))) > 0.05  # the order along the ray shows


def test_a_temperature_grid_glows_as_planck_normalised_to_its_peak(device):
    """A grid at 2500 K throughout with an emission spectrum of 1: Le(λ) is Planck's law over its value at Wien's
    peak (spectrace.spectral.blackbody, computed apart from the kernel's), so the slab shows
    k exp(−σa d) + B̂(λ) (1 − exp(−σa d)) within 4 standard errors; the lanes differ (a red glow)."""
    temperature = np.full((4, 2, 2), 2500.0, np.float32)
    reading = _read(_scene(_grid_medium(temperature=temperature, n=4)), device)
    planck = blackbody(2500.0).evaluate(LANES_NM)
    expected = _slab_radiance(planck)
    assert_within_standard_errors(reading.spectral, expected, reading.spectral_standard_error, power=0.05)
    assert planck[3] > 5 * planck[0]


def test_a_constant_emission_grid_renders_as_the_homogeneous_glowing_medium(device):
    """With scattering too (σs = 0.6, g = 0): a grid of density 1 and emission scale 1 against the homogeneous
    medium of the same coefficients and emission, within 4 standard errors of their difference."""
    homogeneous = Medium(_absorption(), Spectrum.constant(0.6), emission=Spectrum.constant(EMISSION))
    gridded = _grid_medium(emission=np.ones((4, 2, 2), np.float32), n=4, sigma_s=0.6)
    expected, got = (_read(_scene(medium, background=0.0), device) for medium in (homogeneous, gridded))
    se = np.hypot(expected.spectral_standard_error, got.spectral_standard_error)
    assert_within_standard_errors(got.spectral, expected.spectral, se, power=0.05, what="constant emission grid")
    assert np.all(expected.spectral > 0.3)


@pytest.mark.parametrize("integrator", ["direct", "sppm"])
def test_integrators_that_cannot_gather_medium_emission_refuse_it_in_one_line(device, integrator):
    from spectrace.engine.renderer import Renderer

    medium = spectrace.medium(sigma_a=0.5, emission=1.0)
    scene = replace(_scene(medium), width=4, height=4, integrator=integrator)
    with pytest.raises(SpectraceError) as caught:
        Renderer(scene, device)
    text = str(caught.value)
    assert "\n" not in text and integrator in text and ("glowing" in text or "media" in text), text


# ---------------------------------------------------------------- light paths (kernels/light_glowing_media.cl)

FLAT_SIGMA_A = 0.5  # a grey slab, so that each pixel's Y is the radiance of the closed form
SIDE = 8


def _film_scene(medium: Medium, integrator: str, background: float = BACKGROUND) -> Scene:
    """The cube [-1, 1]³ filling an orthographic view along z: every pixel's rays cross DEPTH of it."""
    return Scene(
        camera=Camera((0.0, 0.0, -4.0), (0.0, 0.0, 0.0), type="orthographic", view_width=2.0),
        width=SIDE,
        height=SIDE,
        shapes=[Shape(mesh=primitives.cube(), material=None, interior=medium)],
        lights=[ConstantEnvironment(Spectrum.constant(background))],
        max_depth=16,
        integrator=integrator,
        seed=3,
    )


def _block_means(scene: Scene, device, spp: int, block: int = 1, replicas: int = 8):
    """Y over each block × block pixels: its mean over independent replicas and the standard error of that mean."""
    from replica_agreement import spectrace_replicas
    from spectrace.engine.renderer import Renderer
    from stats_toolkit import mean_and_standard_error

    y = spectrace_replicas(Renderer(scene, device), replicas, spp)[..., 1]
    blocks = y.reshape(replicas, SIDE // block, block, SIDE // block, block).mean(axis=(2, 4))
    return mean_and_standard_error(blocks)


def _flat_grid(emission=None) -> GridVolume:
    n = 16 if emission is None else emission.shape[0]
    return make_grid(np.ones((n, 2, 2), np.float32), box_matrix((-1, -1, -1), (1, 1, 1)), emission=emission)


@pytest.mark.parametrize("kind", ["homogeneous", "grid"])
@pytest.mark.parametrize("integrator", ["light", "bdpt"])
def test_light_paths_see_the_absorbing_emitting_slab_as_its_closed_form(device, integrator, kind):
    """Every 2×2 block of the slab, k exp(−σa d) + Le (1 − exp(−σa d)), within 4 standard errors of its replicas: the
    light tracer's paths start in the glowing cube (a point uniform in its box, σa Le over that density), BDPT's
    camera subpaths gather the glow as the path tracer's do."""
    density = _flat_grid() if kind == "grid" else None
    medium = Medium(Spectrum.constant(FLAT_SIGMA_A), Spectrum.zeros(), density=density, emission=Spectrum.constant(2.0))
    mean, se = _block_means(_film_scene(medium, integrator), device, spp=128 if integrator == "light" else 16, block=2)
    transmitted = np.exp(-FLAT_SIGMA_A * DEPTH)
    expected = np.full_like(mean, BACKGROUND * transmitted + 2.0 * (1.0 - transmitted))
    assert_within_standard_errors(mean, expected, se, power=0.15, what=f"{integrator}, {kind} slab, 2×2 blocks")


def test_light_paths_start_where_an_emission_grid_glows(device):
    """The two-valued emission grid of test_a_varying_emission_grid_gives_the_quadrature under the light tracer: its
    paths start with σa Le(x) at their points, so the image mean is the quadrature's, within 4 standard errors."""
    from scipy import ndimage

    n = 16
    scale = np.full((n, 2, 2), 0.2, np.float32)
    scale[n // 2 :] = 1.5
    medium = Medium(
        Spectrum.constant(FLAT_SIGMA_A), Spectrum.zeros(), density=_flat_grid(scale), emission=Spectrum.constant(2.0)
    )
    mean, se = _block_means(_film_scene(medium, "light", background=0.0), device, spp=64, block=SIDE)
    t = np.linspace(0.0, DEPTH, 20_001)
    s = ndimage.map_coordinates(scale[:, 0, 0].astype(np.float64), [t / DEPTH * n - 0.5], order=1, mode="nearest")
    glow = np.trapezoid(np.exp(-FLAT_SIGMA_A * t) * FLAT_SIGMA_A * 2.0 * s, t)
    assert_within_standard_errors(mean, glow, se, power=0.03, what="light tracer, emission grid")
    assert abs(glow - 2.0 * 0.85 * (1 - np.exp(-FLAT_SIGMA_A * DEPTH))) > 0.05  # the order along the ray shows


@pytest.mark.slow
def test_path_light_and_bdpt_agree_on_a_scattering_glowing_medium(device):
    """σa 0.4, σs 1.2, g 0.3, glowing in an environment of another radiance (no closed form): the light tracer's and
    BDPT's images agree with the path tracer's within 5 standard errors of the difference, per 4×4 block and
    over the image. The glow reaches the camera after scattering as well as straight."""
    from replica_agreement import assert_replicas_agree, spectrace_replicas
    from spectrace.engine.renderer import Renderer

    medium = Medium(Spectrum.constant(0.4), Spectrum.constant(1.2), g=0.3, emission=Spectrum.constant(2.0))
    scene = replace(_film_scene(medium, "path"), camera=replace(_film_scene(medium, "path").camera, view_width=2.4))
    spp = {"path": 32, "light": 64, "bdpt": 32}
    images = {name: spectrace_replicas(Renderer(replace(scene, integrator=name), device), 8, spp[name]) for name in spp}
    for name in ("light", "bdpt"):
        assert_replicas_agree(images[name], images["path"], block=4, what=f"{name} against path")


# Two placements of one glowing cube: squashed, turned about a slanted axis, one of them mirrored.
PLACEMENTS = (
    [{"scale": [0.7, 0.45, 0.5]}, {"rotate": {"axis": [1, 1, 0], "angle": 35}}, {"translate": [-0.6, 0.2, 0]}],
    [{"scale": [-0.5, 0.6, 0.4]}, {"rotate": {"axis": [0, 1, 1], "angle": -50}}, {"translate": [0.7, -0.3, 0.2]}],
)


def _placed_glow(integrator: str, instanced: bool) -> Scene:
    """The cubes as placements of one object, or as shapes of their own with the same transforms; nothing else
    lights them, so the light tracer starts every path in their glow."""
    medium = Medium(Spectrum.constant(0.6), Spectrum.constant(0.4), g=0.2, emission=Spectrum.constant(2.0))
    if instanced:
        ember = spectrace.instanced_object([Shape(mesh=primitives.cube(), material=None, interior=medium)])
        shapes, instances = [], [spectrace.instance(ember, steps) for steps in PLACEMENTS]
    else:
        shapes = [
            Shape(mesh=spectrace.transformed(primitives.cube(), steps), material=None, interior=medium)
            for steps in PLACEMENTS
        ]
        instances = []
    return Scene(
        camera=Camera((0.0, 0.0, -4.0), (0.0, 0.0, 0.0), type="orthographic", view_width=2.8),
        width=2 * SIDE,
        height=2 * SIDE,
        shapes=shapes,
        instances=instances,
        max_depth=16,
        integrator=integrator,
        seed=5,
    )


def test_the_light_tracer_starts_paths_in_glowing_media_inside_placed_objects(device):
    """Each placement glows in its own world-space box: the light tracer's image of the placed cubes agrees with
    its image of the same cubes as shapes of their own, and with the path tracer's of the placed cubes, within 5
    standard errors of the difference per 4×4 block and over the image (8 replicas each)."""
    from replica_agreement import assert_replicas_agree, spectrace_replicas
    from spectrace.engine.renderer import Renderer
    from spectrace.integrators import INTEGRATORS

    placed = _placed_glow("light", instanced=True)
    assert INTEGRATORS["light"].problem(placed, 1, 0) is None
    light = spectrace_replicas(Renderer(placed, device), 8, 64)
    own = spectrace_replicas(Renderer(_placed_glow("light", instanced=False), device), 8, 64)
    path = spectrace_replicas(Renderer(_placed_glow("path", instanced=True), device), 8, 16)
    assert light[..., 1].mean() > 0.1 and (light[..., 1].mean(axis=0) == 0).any()  # the glow, and room around it
    assert_replicas_agree(light, own, block=4, what="light tracer: placed against own shapes")
    assert_replicas_agree(light, path, block=4, what="light tracer against the path tracer, placed")


def test_scene_keys_of_a_glowing_medium(tmp_path):
    """`emission` on the interior, `emission_values` and `temperature_values` on its grid; a grid alone glows with
    an emission spectrum of 1; a temperature grid of the wrong size is one line naming the key."""
    base = CAMERA_FILM_GREY + '\n[[shapes]]\ntype = "cube"\n'
    path = tmp_path / "glow.toml"
    path.write_text(base + "interior = { sigma_a = { value = 0.5 }, emission = { blackbody = 3000, scale = 4 } }\n")
    medium = spectrace.load_scene(path).shapes[0].interior
    assert medium.emission.evaluate(550.0) == pytest.approx(4 * blackbody(3000).evaluate(550.0))
    path.write_text(
        base + "interior = { sigma_a = { value = 0.5 }, density = { values = [1, 1], resolution = [1, 1, 2],"
        " temperature_values = [1500, 2500], emission_values = [1, 3] } }\n"
    )
    medium = spectrace.load_scene(path).shapes[0].interior
    assert medium.emission.evaluate(550.0) == 1.0
    assert np.array_equal(medium.density.temperature.ravel(), [1500, 2500])
    assert np.array_equal(medium.density.emission.ravel(), [1, 3])
    path.write_text(
        base + "interior = { sigma_a = { value = 0.5 }, density = { values = [1, 1], resolution = [1, 1, 2],"
        " temperature_values = [1500] } }\n"
    )
    with pytest.raises(SpectraceError) as caught:
        spectrace.load_scene(path)
    text = str(caught.value)
    assert "\n" not in text and "temperature_values" in text and "glow.toml" in text, text


# ---------------------------------------------------------------- pbrt-v4's Le, Lescale and temperature

PBRT_CUBE = """LookAt 0.1 0.05 -5  0.1 0.05 0  0 1 0
Camera "perspective" "float fov" 1
Film "rgb" "integer xresolution" 4 "integer yresolution" 4
WorldBegin
MakeNamedMedium "glow" "string type" "{kind}" "rgb sigma_a" [0.5 0.5 0.5] "rgb sigma_s" [0 0 0] {extra}
MediumInterface "glow" ""
Material "interface"
Shape "trianglemesh" "point3 P" [{points}] "integer indices" [{indices}]
"""


def _pbrt_cube(tmp_path, kind: str, extra: str):
    corners = np.array([[x, y, z] for z in (-1, 1) for y in (-1, 1) for x in (-1, 1)])
    quads = [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]
    indices = " ".join(str(i) for a, b, c, d in quads for i in (a, b, c, a, c, d))
    path = tmp_path / "glow.pbrt"
    text = PBRT_CUBE.format(kind=kind, extra=extra, points=" ".join(f"{v:g}" for v in corners.ravel()), indices=indices)
    path.write_text(text)
    return path


def test_pbrt_homogeneous_le_and_lescale_glow_as_pbrt_normalises_them(tmp_path, device):
    """pbrt-v4 divides Le by its photometric integral and multiplies by Lescale, so an absorbing cube of
    Le = rgb (1, 1, 1) and Lescale 2 seen through shows luminance factor Y = 2 (1 − exp(−σa d)) (no light behind
    it), within 4 standard errors of the pixels' mean."""
    from spectrace.engine.renderer import Renderer
    from spectrace.interop.pbrt import load_pbrt_scene, pbrt_scene_data

    path = _pbrt_cube(tmp_path, "homogeneous", '"rgb Le" [1 1 1] "float Lescale" 2')
    interior = pbrt_scene_data(path)[0]["shapes"][0]["interior"]
    assert interior["emission"]["rgb"] == [1.0, 1.0, 1.0] and interior["emission"]["scale"] == pytest.approx(2.0)
    renderer = Renderer(load_pbrt_scene(path), device)
    renderer.render(spp=64)
    y = renderer.image().xyz[..., 1].astype(np.float64)
    expected = 2.0 * (1.0 - np.exp(-0.5 * DEPTH))
    se = max(y.std(ddof=1) / np.sqrt(y.size), 1e-6)
    assert abs(y.mean() - expected) <= 4 * se + 2e-3 * expected, (y.mean(), expected, se)


def test_pbrt_uniformgrid_temperature_and_lescale_import_as_grids(tmp_path):
    """A uniformgrid's temperature grid becomes temperature_values after its offset and scale, its Lescale grid
    emission_values; Le with temperature, or a grid of the wrong size, is one line naming the place."""
    from spectrace.interop.pbrt import pbrt_scene_data

    grid = '"integer nx" 2 "float density" [1 1] "float temperature" [1200 2200] "float temperatureoffset" 200'
    path = _pbrt_cube(tmp_path, "uniformgrid", grid + ' "float temperaturescale" 2 "float Lescale" [1 0.5]')
    interior = pbrt_scene_data(path)[0]["shapes"][0]["interior"]
    assert interior["density"]["temperature_values"] == [2000.0, 4000.0]
    assert interior["density"]["emission_values"] == [1.0, 0.5]
    assert "emission" not in interior
    for extra, words in ((' "rgb Le" [1 1 1]', "not both"), (' "float Lescale" [1 2 3]', "Lescale")):
        with pytest.raises(SpectraceError, match=words) as caught:
            pbrt_scene_data(_pbrt_cube(tmp_path, "uniformgrid", grid + extra))
        assert "\n" not in str(caught.value) and "glow.pbrt" in str(caught.value)


def test_a_glowing_medium_built_in_python_saves_and_loads_its_emission(tmp_path):
    """save_scene writes the medium's emission as a spectrum table the scene format reads back: the same values
    on the wavelength grid."""
    from spectrace.scene.model import Camera, Scene

    medium = spectrace.medium(sigma_a=0.5, emission=[0.2, 0.5, 0.9])
    scene = Scene(
        camera=Camera((0.0, 0.0, -4.0), (0.0, 0.0, 0.0)),
        width=4,
        height=4,
        shapes=[spectrace.shape("cube", None, interior=medium), spectrace.shape("sphere", spectrace.diffuse(0.5))],
    )
    spectrace.save_scene(scene, tmp_path / "glow.toml")
    loaded = spectrace.load_scene(tmp_path / "glow.toml").shapes[0].interior
    np.testing.assert_allclose(loaded.emission.values, medium.emission.values, rtol=1e-6)
    assert np.ptp(medium.emission.values) > 0.1  # a coloured glow, not a constant
