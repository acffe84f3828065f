"""The light tracer (integrator 'light') against closed-form radiometry, the path tracer and Mitsuba 3's ptracer.

- A closed enclosure of emitting, diffusely reflecting walls holds the radiance Le (1 − ρ^d) / (1 − ρ) truncated to
  d path segments (as for the path tracer, tests/render/test_path_integrator.py).
- A point light of intensity I at height h over a diffuse floor of albedo ρ: the floor's radiance is
  ρ/π · I cos θ / r², averaged over each pixel's footprint.
- The same through a smooth glass slab of index n and thickness t between a point light and a screen, which a path
  tracer cannot see (next-event estimation is blocked by the glass; BSDF sampling never hits a point): near the axis
  E = I T² Σ_k R^{2k} / (d − t + (2k + 1) t / n)², T = 1 − R, R = ((n − 1)/(n + 1))² (normal incidence Fresnel), the
  k-th term light that bounced 2k times inside the slab, d − t + t/n the paraxial apparent distance of the source.
- Cornell box and a textured scene (checkerboard walls, an image on the lamp): the light tracer's and the path
  tracer's images agree within noise (block means, 5 standard errors from independent replicas).
- A scene of the other light types (distant, constant environment seen directly, an emitting analytic sphere) with
  rough glass, a cube shaded smooth and a rough-coated plastic: light tracer and path tracer agree. Sharper tests of
  what differs when a BSDF is traced from the light: rough glass seen from below under a spot light (the connection
  evaluates the BTDF for light arriving from inside the glass, so refraction's radiance scaling must be the one for
  that direction), and a ceiling lit only by a cube whose corner-averaged shading normals are far from its faces'
  (the sampled directions need Veach's shading-normal factor).
- The same seed gives the same bits however the render is split into passes, including paths re-launched for
  their later splat records.
"""

from pathlib import Path

import numpy as np
import pytest

import spectrace
from replica_agreement import assert_replicas_agree, spectrace_replicas
from scene_text import camera_film
from spectrace.engine.renderer import Renderer
from spectrace.errors import SpectraceError
from spectrace.geometry import primitives
from spectrace.geometry.transforms import apply_transform, transform_matrix
from spectrace.integrators import light as light_tracer
from spectrace.io.raster import write_display_image as write_png
from spectrace.resources import resolve_scene_path
from spectrace.scene.model import AreaEmitter, Camera, DiffuseMaterial, Scene, Shape
from spectrace.spectral.grid import GRID_NM
from spectrace.spectral.spectrum import Spectrum
from stats_toolkit import assert_within_standard_errors, mean_and_standard_error


def _constant(value: float) -> Spectrum:
    return Spectrum(np.full(len(GRID_NM), value), name=f"constant {value}")


EMITTED, ALBEDO = 0.5, 0.6


def _furnace_box(max_depth: int) -> Scene:
    box = apply_transform(primitives.cube(), transform_matrix([{"scale": [1.0, 0.7, 1.3]}], where="test"))
    shape = Shape(
        mesh=box, material=DiffuseMaterial(_constant(ALBEDO)), emitter=AreaEmitter(_constant(EMITTED), two_sided=True)
    )
    camera = Camera(origin=(0.1, -0.2, 0.3), target=(0.5, 0.1, -1.0), fov_degrees=100.0)
    return Scene(
        camera=camera, width=32, height=32, shapes=[shape], max_depth=max_depth, rr_depth=3, spp=16, seed=5,
        integrator="light",
    )  # fmt: skip


@pytest.mark.parametrize("max_depth", [1, 3, -1])
def test_enclosure_radiance(device, max_depth):
    expected = EMITTED * ((1 - ALBEDO**max_depth) if max_depth > 0 else 1.0) / (1 - ALBEDO)
    renderer = Renderer(_furnace_box(max_depth), device)
    # A light path's splats land in any pixel: the image means of independent replicas are what is independent.
    mean, standard_error = mean_and_standard_error(spectrace_replicas(renderer, 8, 16)[..., 1].mean(axis=(1, 2)))
    assert_within_standard_errors(mean, expected, standard_error, power=0.05)


def _write(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "scene.toml"
    path.write_text(text, encoding="utf-8")
    return path


def _camera(origin, target, fov, size, up="[0, 1, 0]") -> str:
    return camera_film(origin=origin, target=target, fov=fov, width=size, height=size, camera=f"up = {up}")


INTENSITY, HEIGHT, FLOOR_ALBEDO = 2.0, 1.0, 0.5


def _floor_scene(tmp_path: Path, integrator: str, extra: str = "") -> Path:
    return _write(
        tmp_path,
        _camera("[0.3, -0.2, 3]", "[0.3, -0.2, 0]", 50, 32)
        + f"""
[integrator]
type = "{integrator}"
max_depth = 2

[sampler]
spp = 8

[materials.floor]
type = "diffuse"
reflectance = {{ value = {FLOOR_ALBEDO} }}

[[shapes]]
type = "rectangle"
material = "floor"
transform = [{{ scale = 4 }}]

[[lights]]
type = "point"
position = [0, 0, {HEIGHT}]
intensity = {{ value = {INTENSITY} }}
{extra}""",
    )


def _floor_radiance_per_pixel(scene: Scene, supersample: int = 8) -> np.ndarray:
    """ρ/π · I h / r³ averaged over each pixel (camera looking straight down at the floor z = 0)."""
    origin, forward, right, up = scene.camera.basis(scene.width / scene.height)
    offsets = (np.arange(supersample) + 0.5) / supersample
    px = (np.arange(scene.width)[:, None] + offsets[None, :]).ravel()
    py = (np.arange(scene.height)[:, None] + offsets[None, :]).ravel()
    ndc_x = 2 * px / scene.width - 1
    ndc_y = 1 - 2 * py / scene.height
    d = forward + ndc_x[None, :, None] * right + ndc_y[:, None, None] * up
    t = -origin[2] / d[..., 2]
    p = origin + t[..., None] * d
    r2 = p[..., 0] ** 2 + p[..., 1] ** 2 + HEIGHT**2
    radiance = FLOOR_ALBEDO / np.pi * INTENSITY * HEIGHT / r2**1.5
    return radiance.reshape(scene.height, supersample, scene.width, supersample).mean(axis=(1, 3))


def _replica_blocks(renderer, replicas: int, replica_spp: int, block: int) -> np.ndarray:
    images = spectrace_replicas(renderer, replicas, replica_spp)[..., 1]
    n = images.shape[1] // block
    return images.reshape(replicas, n, block, n, block).mean(axis=(2, 4))


def test_point_light_over_a_diffuse_floor(device, tmp_path):
    scene = spectrace.load_scene(_floor_scene(tmp_path, "light"))
    # Quarters of the image, each to 5 %: the falloff from the light's foot to the corners.
    expected = _floor_radiance_per_pixel(scene).reshape(2, 16, 2, 16).mean(axis=(1, 3))
    blocks = _replica_blocks(Renderer(scene, device), 8, 64, 16)
    mean, standard_error = mean_and_standard_error(blocks)
    assert_within_standard_errors(mean, expected, standard_error, power=0.05)


IOR, THICKNESS, DISTANCE = 1.5, 0.1, 1.0


def _slab_scene(tmp_path: Path, integrator: str) -> Path:
    """A screen at z = 0, a glass slab over z in [0.45, 0.55], a point light at z = 1 shining into a 10° cone (a
    spot: light tracing spends its paths where the camera looks); the camera sits between the slab and the screen
    looking straight down, so it sees the screen without the glass, its 4 x 4 central pixels a spot 5 cm across."""
    return _write(
        tmp_path,
        _camera("[0, 0, 0.3]", "[0, 0, 0]", 40, 16)
        + f"""
[integrator]
type = "{integrator}"
max_depth = -1
rr_depth = 40

[materials.screen]
type = "diffuse"
reflectance = {{ value = {FLOOR_ALBEDO} }}

[materials.glass]
type = "dielectric"
ior = {IOR}

[[shapes]]
type = "rectangle"
material = "screen"
transform = [{{ scale = 2 }}]

[[shapes]]
type = "cube"
material = "glass"
transform = [{{ scale = [0.4, 0.4, {THICKNESS / 2}] }}, {{ translate = [0, 0, 0.5] }}]

[[lights]]
type = "spot"
position = [0, 0, {DISTANCE}]
target = [0, 0, 0]
cutoff_angle = 10
falloff_start = 9
intensity = {{ value = {INTENSITY} }}
""",
    )


def test_point_light_through_a_glass_slab(device, tmp_path):
    """The light tracer shows the light the slab lets through; the path tracer sees a black screen."""
    reflectance = ((IOR - 1) / (IOR + 1)) ** 2
    transmittance = 1 - reflectance
    k = np.arange(6)
    irradiance = INTENSITY * np.sum(
        transmittance**2 * reflectance ** (2 * k) / (DISTANCE - THICKNESS + (2 * k + 1) * THICKNESS / IOR) ** 2
    )
    expected = FLOOR_ALBEDO / np.pi * irradiance
    scene = spectrace.load_scene(_slab_scene(tmp_path, "light"))
    images = spectrace_replicas(Renderer(scene, device), 8, 128)[:, 6:10, 6:10, 1]
    mean, standard_error = mean_and_standard_error(images.mean(axis=(1, 2)))
    assert standard_error < 0.01 * expected
    assert_within_standard_errors(mean, expected, standard_error)
    path_traced = Renderer(scene.with_overrides(integrator="path", spp=4), device).render().xyz[..., 1]
    assert path_traced.max() == 0.0


CORNELL_SIZE = 32


@pytest.mark.slow
def test_cornell_box_agrees_with_the_path_tracer(device):
    scene = spectrace.load_scene(resolve_scene_path("cornell_box")).with_overrides(
        width=CORNELL_SIZE, height=CORNELL_SIZE, seed=11
    )
    path = spectrace_replicas(Renderer(scene, device), 8, 8)
    light = spectrace_replicas(Renderer(scene.with_overrides(integrator="light"), device), 8, 8)
    assert_replicas_agree(light, path, block=8)


def _textured_scene(tmp_path: Path, integrator: str) -> Path:
    """A room of checkerboard walls lit by a lamp showing a 2 x 2 image, with a sphere and a spot light."""
    image = np.array([[[1.0, 0.2, 0.1], [0.1, 0.9, 0.2]], [[0.2, 0.3, 1.0], [1.0, 1.0, 0.8]]])
    write_png(tmp_path / "lamp.png", image, {})
    return _write(
        tmp_path,
        _camera("[0, 0, 2.5]", "[0, 0, 0]", 70, 16)
        + f"""
[integrator]
type = "{integrator}"
max_depth = 4

[textures.tiles]
type = "checkerboard"
color0 = {{ rgb = [0.8, 0.5, 0.3] }}
color1 = {{ rgb = [0.2, 0.4, 0.7] }}
uv_scale = 4

[materials.walls]
type = "diffuse"
reflectance = {{ texture = "tiles" }}

[materials.ball]
type = "diffuse"
reflectance = {{ rgb = [0.7, 0.7, 0.7] }}

[materials.black]
type = "diffuse"
reflectance = {{ value = 0 }}

[[shapes]]
type = "cube"
material = "walls"
transform = [{{ scale = 3 }}]

[[shapes]]
type = "sphere"
material = "ball"
transform = [{{ scale = 0.6 }}, {{ translate = [0.5, -0.8, -0.5] }}]

[[shapes]]
type = "rectangle"
material = "black"
emitter = {{ radiance = {{ texture = "bitmap", file = "lamp.png", filter = "nearest" }}, scale = 4 }}
transform = [{{ rotate = {{ axis = [1, 0, 0], angle = 90 }} }}, {{ scale = 0.8 }}, {{ translate = [0, 2.9, 0] }}]

[[lights]]
type = "spot"
position = [-2, 2, 2]
target = [0.5, -0.8, -0.5]
cutoff_angle = 20
intensity = {{ value = 3 }}
""",
    )


@pytest.mark.slow
def test_textured_scene_agrees_with_the_path_tracer(device, tmp_path):
    path_scene = spectrace.load_scene(_textured_scene(tmp_path, "path"))
    light_scene = spectrace.load_scene(_textured_scene(tmp_path, "light"))
    path = spectrace_replicas(Renderer(path_scene, device), 8, 32)
    light = spectrace_replicas(Renderer(light_scene, device), 8, 32)
    assert path.mean() > 0.01
    assert_replicas_agree(light, path, block=4)


def test_pass_split_gives_the_same_bits(device, tmp_path, monkeypatch):
    scene = spectrace.load_scene(_textured_scene(tmp_path, "light")).with_overrides(max_depth=-1, spp=6)
    one_pass = Renderer(scene, device).render(pass_spp=6).xyz
    split = Renderer(scene, device).render(pass_spp=1).xyz
    np.testing.assert_array_equal(one_pass, split)
    # Two record slots per launch: most paths are launched again, some several times, for their later splats.
    monkeypatch.setattr(light_tracer, "MAX_RECORD_SLOTS", 2)
    relaunched = Renderer(scene, device).render(pass_spp=4).xyz
    np.testing.assert_array_equal(one_pass, relaunched)


BANDS_NM, TEMPERATURE = (400.0, 700.0, 3), 4000.0


def _planck_band_means(temperature: float, lo: float, hi: float, bins: int) -> np.ndarray:
    """Planck's law normalised to 1 at its peak (Wien's λ = b / T), averaged over each band."""
    h, c, k = 6.62607015e-34, 2.99792458e8, 1.380649e-23

    def planck(nm):
        m = np.asarray(nm) * 1e-9
        return 1.0 / (m**5 * np.expm1(h * c / (m * k * temperature)))

    peak = planck(2.897771955e-3 / temperature * 1e9)
    edges = np.linspace(lo, hi, bins + 1)
    fine = [np.linspace(a, b, 2001) for a, b in zip(edges[:-1], edges[1:], strict=True)]
    return np.array([np.trapezoid(planck(x), x) / (x[-1] - x[0]) for x in fine]) / peak


def test_spectral_bands_of_a_lit_floor(device, tmp_path):
    """--spectral-bins from light paths: each band holds the floor's band-averaged radiance ρ/π · I_band h / r³,
    I_band the light's (a 4000 K Planck spectrum) mean over the band, and the pass split keeps the bits."""
    lo, hi, bins = BANDS_NM
    text = (
        _floor_scene(tmp_path, "light")
        .read_text()
        .replace(
            f"intensity = {{ value = {INTENSITY} }}",
            f"intensity = {{ blackbody = {TEMPERATURE:g}, scale = {INTENSITY} }}",
        )
    )
    scene = spectrace.load_scene(_write(tmp_path, text))
    renderer = Renderer(scene, device, spectral_bins=bins, spectral_range_nm=(lo, hi))
    replicas, replica_spp, sums = 8, 16, []
    for replica in range(1, replicas + 1):
        renderer.render(spp=replica * replica_spp, pass_spp=replica_spp)
        sums.append(renderer.read_spectral_film().astype(np.float64))
    bands = np.diff(np.stack([np.zeros_like(sums[0]), *sums]), axis=0) / replica_spp
    blocks = bands.reshape(replicas, 4, 8, 4, 8, bins).mean(axis=(2, 4))
    geometry = _floor_radiance_per_pixel(scene).reshape(4, 8, 4, 8).mean(axis=(1, 3)) / INTENSITY
    expected = geometry[..., None] * INTENSITY * _planck_band_means(TEMPERATURE, lo, hi, bins)
    # Each band over the whole floor is the quantity held to 5 %; each block's bands only to their own noise.
    mean, standard_error = mean_and_standard_error(blocks.mean(axis=(1, 2)))
    assert_within_standard_errors(mean, expected.mean(axis=(0, 1)), standard_error, what="bands", power=0.05)
    mean, standard_error = mean_and_standard_error(blocks)
    assert_within_standard_errors(mean, expected, standard_error, what="bands per block")
    split = Renderer(scene, device, spectral_bins=bins, spectral_range_nm=(lo, hi))
    split.render(spp=4, pass_spp=1)
    whole = Renderer(scene, device, spectral_bins=bins, spectral_range_nm=(lo, hi))
    whole.render(spp=4, pass_spp=4)
    np.testing.assert_array_equal(split.read_spectral_film(), whole.read_spectral_film())


def _mixed_scene(tmp_path: Path, integrator: str, target: str) -> Path:
    origin = "[{}, 0.9, {}]".format(*np.add(eval(target)[::2], [0.0, 1.8]))  # 1.8 in front of the target
    return _write(
        tmp_path,
        _camera(origin, target, 30, 16)
        + f"""
[integrator]
type = "{integrator}"
max_depth = 5

[materials.floor]
type = "plastic"
reflectance = {{ rgb = [0.5, 0.4, 0.3] }}
roughness = 0.3

[materials.frosted]
type = "dielectric"
ior = 1.5
roughness = 0.5

[materials.matte]
type = "diffuse"
reflectance = {{ rgb = [0.3, 0.6, 0.4] }}

[[shapes]]
type = "rectangle"
material = "floor"
transform = [{{ rotate = {{ axis = [1, 0, 0], angle = -90 }} }}, {{ scale = 1.2 }}]

[[shapes]]
type = "sphere"
material = "frosted"
transform = [{{ scale = 0.45 }}, {{ translate = [-0.5, 0.45, 0] }}]

[[shapes]]
type = "cube"
face_normals = false
material = "matte"
transform = [{{ scale = 0.3 }}, {{ rotate = {{ axis = [0, 1, 0], angle = 30 }} }}, {{ translate = [0.6, 0.3, -0.3] }}]

[[shapes]]
type = "sphere"
material = "matte"
emitter = {{ radiance = {{ value = 3 }} }}
transform = [{{ scale = 0.15 }}, {{ translate = [0.2, 1.3, 0.6] }}]

[[lights]]
type = "distant"
direction = [0.4, -1, -0.3]
irradiance = {{ value = 0.8 }}

[[lights]]
type = "constant"
radiance = {{ value = 0.1 }}
""",
    )


@pytest.mark.slow
def test_other_lights_and_adjoint_bsdfs_agree_with_the_path_tracer(device, tmp_path):
    """The camera fills its view with the smooth-shaded cube on the plastic floor, under the distant, constant and
    spherical area lights; the image's mean is held to 5 %. The rough glass sphere stays out of view: lit by large
    lights it makes heavy-tailed light-traced pixels that would take some 200 times these samples to resolve 5 %,
    and test_rough_glass_seen_from_below is the test of its BTDF."""
    target = "[0.6, 0.3, -0.3]"
    path = spectrace_replicas(Renderer(spectrace.load_scene(_mixed_scene(tmp_path, "path", target)), device), 8, 128)
    light = spectrace_replicas(Renderer(spectrace.load_scene(_mixed_scene(tmp_path, "light", target)), device), 8, 128)
    assert path.mean() > 0.05
    assert_replicas_agree(light, path, block=4)


def _rough_slab_scene(tmp_path: Path, integrator: str) -> Path:
    """A spot light over a rough glass slab, seen from below: every pixel is light the slab lets through toward the
    camera, which the light tracer finds by evaluating the rough BTDF at the slab's lower face for light arriving
    from inside the glass (where refraction's radiance scaling decides the value)."""
    return _write(
        tmp_path,
        _camera("[0, 0, 0]", "[0, 0, 1]", 50, 16)
        + f"""
[integrator]
type = "{integrator}"
max_depth = 3

[materials.frosted]
type = "dielectric"
ior = 1.5
roughness = 0.5

[[shapes]]
type = "cube"
material = "frosted"
transform = [{{ scale = [1.5, 1.5, 0.05] }}, {{ translate = [0, 0, 0.5] }}]

[[lights]]
type = "spot"
position = [0.1, 0, 1]
target = [0, 0, 0]
cutoff_angle = 60
intensity = {{ value = 1 }}
""",
    )


@pytest.mark.slow
def test_rough_glass_seen_from_below(device, tmp_path):
    """The light through the slab, to 5 %: the light tracer's estimate is the noisier (its BTDF evaluated toward
    the camera is heavy-tailed; less so for a rougher slab: at roughness 0.2 it would take ten times the samples),
    so it takes the more samples."""
    path = spectrace_replicas(Renderer(spectrace.load_scene(_rough_slab_scene(tmp_path, "path")), device), 16, 64)
    light = spectrace_replicas(Renderer(spectrace.load_scene(_rough_slab_scene(tmp_path, "light")), device), 16, 128)
    assert path.mean() > 0.01
    assert_replicas_agree(light, path, block=4)


def _shading_normals_scene(tmp_path: Path, integrator: str) -> Path:
    """A spot light whose narrow cone lands on the top of a cube shaded smooth (its vertex normals the average of
    three faces', far from each face's own), under a ceiling lit only by what the cube reflects, which the camera
    looks at: the light tracer's sampled directions at the cube carry Veach's shading-normal factor. The ceiling is
    small, so no part of it sees the cube at so grazing an angle that the path tracer would hardly ever find it."""
    # Eight shared corners: the normals computed from the faces point along the diagonals.
    corners = [(x, y, z) for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]
    quads = [(1, 2, 4, 3), (5, 7, 8, 6), (1, 5, 6, 2), (3, 4, 8, 7), (1, 3, 7, 5), (2, 6, 8, 4)]
    (tmp_path / "cube.obj").write_text(
        "".join(f"v {x} {y} {z}\n" for x, y, z in corners)
        + "".join(f"f {a} {b} {c}\nf {a} {c} {d}\n" for a, b, c, d in quads)
    )
    return _write(
        tmp_path,
        _camera("[1.2, 0, 0.1]", "[0.2, 0, 1]", 70, 16, up="[0, 0, 1]")
        + f"""
[integrator]
type = "{integrator}"
max_depth = 3

[materials.white]
type = "diffuse"
reflectance = {{ value = 0.8 }}

[[shapes]]
type = "mesh"
file = "cube.obj"
face_normals = false
material = "white"
transform = [{{ scale = 0.3 }}]

[[shapes]]
type = "rectangle"
material = "white"
transform = [{{ rotate = {{ axis = [1, 0, 0], angle = 180 }} }}, {{ translate = [0, 0, 1.0] }}]

[[lights]]
type = "spot"
position = [0.05, 0.1, 0.95]
target = [0.05, 0.1, 0]
cutoff_angle = 15
intensity = {{ value = 5 }}
""",
    )


@pytest.mark.slow
def test_shading_normals_seen_by_their_light(device, tmp_path):
    """The ceiling's light, to 5 %: the path tracer, which must find the cube's small lit spot from the ceiling by
    sampling its BSDF, is the noisier and takes the more samples."""
    path = spectrace_replicas(Renderer(spectrace.load_scene(_shading_normals_scene(tmp_path, "path")), device), 8, 768)
    light = spectrace_replicas(Renderer(spectrace.load_scene(_shading_normals_scene(tmp_path, "light")), device), 8, 64)
    assert path.mean() > 0.005
    # The image's lowest rows see the ceiling's and the cube's edges almost edge-on: nearly black, and lit only by
    # rare paths, whose spread a few replicas do not estimate.
    assert_replicas_agree(light[:, :12, 2:14], path[:, :12, 2:14], block=4)


@pytest.mark.parametrize("hidden", [False, True])
def test_environment_seen_directly(device, tmp_path, hidden):
    """Nothing but a constant environment of radiance 0.3: every pixel sees exactly it (the camera ray each
    work-item traces for its own pixel), or black with hide_environment."""
    scene = spectrace.load_scene(
        _write(
            tmp_path,
            _camera("[0, 0, 0]", "[0, 0, 1]", 60, 8)
            + f"""
[integrator]
type = "light"
hide_environment = {str(hidden).lower()}

[materials.grey]
type = "diffuse"
reflectance = {{ value = 0.5 }}

[[lights]]
type = "constant"
radiance = {{ value = 0.3 }}
""",
        )
    )
    y = Renderer(scene.with_overrides(spp=64), device).render().xyz[..., 1]
    if hidden:
        assert np.all(y == 0.0)
    else:
        mean, standard_error = mean_and_standard_error(y.ravel())
        assert standard_error < 0.01 * 0.3
        assert_within_standard_errors(mean, 0.3, standard_error)


def test_a_tile_of_the_film_is_refused(device, tmp_path):
    """Splats land in any pixel, so a renderer asked for a pixel range (a tile of a split render) refuses."""
    renderer = Renderer(spectrace.load_scene(_floor_scene(tmp_path, "light")), device)
    renderer.pixel_range = (0, 10)
    with pytest.raises(SpectraceError, match="tiles"):
        renderer.render(spp=1)


@pytest.mark.parametrize(
    ("changes", "words"),
    [
        ({"film_response": spectrace.FilmResponse(observer="CIE 1964 10°")}, "default CIE 1931 film"),
        ({"aovs": ("depth",)}, "AOVs"),
    ],
)
def test_what_splats_cannot_give_is_refused_in_one_line(device, tmp_path, changes, words):
    """A splat is added with the film's CIE 1931 weights at the end of a light path: another film's curves and the
    camera path's first surface are not there to be had."""
    scene = spectrace.load_scene(_floor_scene(tmp_path, "light")).with_overrides(**changes)
    with pytest.raises(SpectraceError, match=words) as error:
        Renderer(scene, device)
    assert "\n" not in str(error.value)


@pytest.mark.slow
@pytest.mark.parametrize("pixel_filter", ['{ type = "gaussian", stddev = 0.5 }', '{ type = "mitchell" }'])
def test_pixel_filters_agree_with_the_path_tracer(device, tmp_path, pixel_filter):
    """A splat spread over the pixels whose filter covers it (with its weight f(dx) f(dy) / (∫f)², negative lobes
    included, and from points up to radius − ½ pixels beyond the film's edge) against the path tracer's filter
    importance sampling, on the checkerboard room (sharp texture edges, so the filter changes the image)."""
    texts = [
        _textured_scene(tmp_path, integrator).read_text().replace("[film]\n", f"[film]\nfilter = {pixel_filter}\n")
        for integrator in ("path", "light")
    ]
    path_scene = spectrace.load_scene(_write(tmp_path, texts[0]))
    light_scene = spectrace.load_scene(_write(tmp_path, texts[1]))
    path = spectrace_replicas(Renderer(path_scene, device), 8, 48)
    light = spectrace_replicas(Renderer(light_scene, device), 8, 48)
    # The image's mean to 5 % (a splat weight off by a constant factor); the filter's shape, per 2 x 2 block.
    assert_replicas_agree(light, path, block=2)
    one_pass = Renderer(light_scene, device).render(spp=4, pass_spp=4).xyz
    np.testing.assert_array_equal(one_pass, Renderer(light_scene, device).render(spp=4, pass_spp=1).xyz)
