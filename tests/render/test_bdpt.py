"""Bidirectional path tracing (integrator 'bdpt') against closed-form radiometry and the path tracer.

- A closed enclosure of emitting, diffusely reflecting walls holds the radiance Le (1 − ρ^d) / (1 − ρ) truncated to
  d path segments; paths of exactly k segments carry Le ρ^(k−1), and every strategy (s, t) with s + t − 1 = k, kept
  alone and unweighted, must estimate that by itself (the camera walk, the light walk, next-event estimation, the
  connections and the light-to-camera splats each), while the MIS-weighted sum over them must too (the weights
  sum to one for every path).
- A spot light through a smooth glass slab onto a screen (a caustic the path tracer renders black): only the
  light-to-camera strategy reaches it, and its MIS weight must be one (delta vertices remapped): the screen's
  irradiance I T² Σ R^{2k}/(d − t + (2k + 1)t/n)² (tests/render/test_light_tracer.py).
- The Cornell box, a textured scene and a dispersive glass sphere: BDPT's and the path tracer's images agree within
  noise (block means, 5 standard errors from independent replicas).
- Lights at infinity and lens cameras: a scene of a distant light, a constant environment and an emitting sphere over
  rough glass, a smooth-shaded cube and plastic (tests/render/test_light_tracer.py's), seen through the pinhole,
  the thin lens and the orthographic camera, with an environment map for the constant environment, and a spot
  light's slide: BDPT's and the path tracer's images agree
  within noise. (tests/render/test_light_traced_cameras.py holds BDPT's lens cameras to the floor's closed form.)
- The same seed gives the same bits however the render is split into passes.
"""

import dataclasses
import re
from pathlib import Path

import numpy as np
import pytest
from tests.render.test_light_tracer import (
    ALBEDO,
    DISTANCE,
    EMITTED,
    FLOOR_ALBEDO,
    INTENSITY,
    IOR,
    THICKNESS,
    _camera,
    _floor_scene,
    _furnace_box,
    _mixed_scene,
    _slab_scene,
    _textured_scene,
    _write,
)

import spectrace
from replica_agreement import assert_replicas_agree, spectrace_replicas
from scene_text import camera_film
from spectrace.engine import renderer as renderer_module
from spectrace.engine.renderer import Renderer
from spectrace.engine.scene_buffers import render_params
from spectrace.errors import SpectraceError
from spectrace.integrators import bdpt
from spectrace.integrators import light as light_tracer
from spectrace.io.exr import write_exr
from spectrace.resources import resolve_scene_path
from stats_toolkit import assert_within_standard_errors, mean_and_standard_error


def _enclosure(max_depth: int):
    return dataclasses.replace(_furnace_box(max_depth), integrator="bdpt")


def _image_mean(renderer, replicas: int = 8, replica_spp: int = 16):
    """Mean and standard error of the whole image's Y over independent replicas (splats land in any pixel)."""
    return mean_and_standard_error(spectrace_replicas(renderer, replicas, replica_spp)[..., 1].mean(axis=(1, 2)))


@pytest.mark.parametrize("max_depth", [1, 3, 8])
def test_enclosure_radiance(device, max_depth):
    expected = EMITTED * (1 - ALBEDO**max_depth) / (1 - ALBEDO)
    mean, standard_error = _image_mean(Renderer(_enclosure(max_depth), device))
    assert_within_standard_errors(mean, expected, standard_error, power=0.05)


@pytest.mark.parametrize("pixels", [1, 3])
def test_any_number_of_pixels_per_light_subpath(device, pixels):
    """The enclosure's radiance whatever number of pixels share a light subpath: 3 does not divide the 32 × 32 film,
    so the last work-item has a pixel of its own; the t = 1 strategy's share and MIS weights follow the number."""
    expected = EMITTED * (1 - ALBEDO**3) / (1 - ALBEDO)
    scene = _enclosure(3).with_overrides(pixels_per_light_path=pixels)
    mean, standard_error = _image_mean(Renderer(scene, device))
    assert_within_standard_errors(mean, expected, standard_error, power=0.05)


def test_pixels_per_light_subpath_from_the_scene(tmp_path):
    """Four where every surface is diffuse (the enclosure), two where a smooth surface can make a caustic that the
    light-to-camera strategy mostly finds (the glass slab), what the scene says where it says it."""
    diffuse = _enclosure(3)
    glass = spectrace.load_scene(_slab_scene(tmp_path, "bdpt"))
    assert bdpt.pixels_per_light_path(diffuse) == 4
    assert bdpt.pixels_per_light_path(glass) == 2
    assert bdpt.pixels_per_light_path(glass.with_overrides(pixels_per_light_path=4)) == 4


@pytest.mark.parametrize(
    ("integrator", "pixels", "match"),
    [
        ("bdpt", 0, "pixels_per_light_path must lie in 1..16"),
        ("bdpt", 17, "pixels_per_light_path must lie in 1..16"),
        ("path", 2, "pixels_per_light_path is only for integrator 'bdpt'"),
    ],
)
def test_pixels_per_light_subpath_refused_in_one_line(tmp_path, integrator, pixels, match):
    text = _floor_scene(tmp_path, integrator).read_text()
    text = text.replace("[integrator]\n", f"[integrator]\npixels_per_light_path = {pixels}\n")
    with pytest.raises(SpectraceError, match=match) as error:
        spectrace.load_scene(_write(tmp_path, text))
    assert "integrator" in str(error.value) and "\n" not in str(error.value)


def test_pixels_per_light_subpath_out_of_range_refused_in_python(device, tmp_path):
    scene = spectrace.load_scene(_floor_scene(tmp_path, "bdpt"))
    with pytest.raises(SpectraceError, match="pixels_per_light_path must lie in 1..16"):
        Renderer(scene.with_overrides(pixels_per_light_path=0), device)
    # A BDPT scene switched to another integrator keeps the setting, unused.
    Renderer(scene.with_overrides(pixels_per_light_path=3, integrator="path"), device)


@pytest.fixture
def strategy_device(device, monkeypatch):
    """The device, building its programs with the test define that keeps one strategy (kernels/bdpt.cl); the
    strategy, chosen["s"] and chosen["t"], reaches the passes at run time, so one program serves every strategy.
    chosen["unweighted"] also drops the MIS weights (a define)."""
    build = device.build_program
    chosen: dict[str, int] = {}

    def build_with(entry, defines=None, **kwargs):
        test_defines = {"BDPT_ONE_STRATEGY": 1} | ({"BDPT_UNWEIGHTED": 1} if chosen.get("unweighted") else {})
        return build(entry, defines={**(defines or {}), **test_defines}, **kwargs)

    def params_with(*args, **kwargs):
        params = render_params(*args, **kwargs)
        params["bdpt_only_s"], params["bdpt_only_t"] = chosen["s"], chosen["t"]
        return params

    monkeypatch.setattr(device, "build_program", build_with)
    monkeypatch.setattr(renderer_module, "render_params", params_with)
    return device, chosen


SEGMENTS = 3


@pytest.mark.slow
@pytest.mark.parametrize("s", range(SEGMENTS + 1))
def test_each_strategy_alone_estimates_its_path_length(strategy_device, s):
    """Paths of exactly 3 segments in the enclosure carry Le ρ²: strategy (s, 4 − s) alone, unweighted, estimates
    it; weighted, the strategies' images add up to it."""
    device, chosen = strategy_device
    t = SEGMENTS + 1 - s
    chosen |= {"s": s, "t": t, "unweighted": 1}
    expected = EMITTED * ALBEDO ** (SEGMENTS - 1)
    mean, standard_error = _image_mean(Renderer(_enclosure(SEGMENTS), device), 8, 96)
    assert_within_standard_errors(mean, expected, standard_error, power=0.05)


@pytest.mark.slow
def test_weighted_strategies_of_one_length_add_up(strategy_device):
    device, chosen = strategy_device
    scene = _enclosure(SEGMENTS).with_overrides(spp=8)
    images = []
    for s in range(SEGMENTS + 1):
        chosen |= {"s": s, "t": SEGMENTS + 1 - s}
        images.append(Renderer(scene, device).render().xyz[..., 1].astype(np.float64))
    means = np.array([image.mean() for image in images])
    assert np.all(means > 0.0)  # each strategy takes a share of these paths
    # The replicas of the sum: independent seeds give the noise.
    sums = []
    for seed in range(8):
        total = 0.0
        for s in range(SEGMENTS + 1):
            chosen |= {"s": s, "t": SEGMENTS + 1 - s}
            total += Renderer(scene.with_overrides(seed=seed + 100), device).render().xyz[..., 1].mean()
        sums.append(total)
    mean, standard_error = mean_and_standard_error(np.array(sums))
    assert_within_standard_errors(mean, EMITTED * ALBEDO ** (SEGMENTS - 1), standard_error, power=0.05)


@pytest.mark.slow
def test_point_light_through_a_glass_slab(device, tmp_path):
    """Only the light-to-camera strategy reaches the caustic, with MIS weight one."""
    reflectance = ((IOR - 1) / (IOR + 1)) ** 2
    transmittance = 1 - reflectance
    k = np.arange(6)
    irradiance = INTENSITY * np.sum(
        transmittance**2 * reflectance ** (2 * k) / (DISTANCE - THICKNESS + (2 * k + 1) * THICKNESS / IOR) ** 2
    )
    expected = FLOOR_ALBEDO / np.pi * irradiance
    text = _slab_scene(tmp_path, "bdpt").read_text().replace("max_depth = -1", "max_depth = 16")
    scene = spectrace.load_scene(_write(tmp_path, text))
    images = spectrace_replicas(Renderer(scene, device), 8, 256)[:, 6:10, 6:10, 1]
    mean, standard_error = mean_and_standard_error(images.mean(axis=(1, 2)))
    assert standard_error < 0.01 * expected
    assert_within_standard_errors(mean, expected, standard_error)


CORNELL_SIZE = 32


@pytest.mark.slow
def test_cornell_box_agrees_with_the_path_tracer(device):
    scene = spectrace.load_scene(resolve_scene_path("cornell_box")).with_overrides(
        width=CORNELL_SIZE, height=CORNELL_SIZE, seed=11
    )
    path = spectrace_replicas(Renderer(scene, device), 8, 24)
    bdpt = spectrace_replicas(Renderer(scene.with_overrides(integrator="bdpt"), device), 8, 24)
    assert_replicas_agree(bdpt, path, block=8)


@pytest.mark.slow
def test_textured_scene_agrees_with_the_path_tracer(device, tmp_path):
    path = spectrace_replicas(Renderer(spectrace.load_scene(_textured_scene(tmp_path, "path")), device), 8, 32)
    bdpt = spectrace_replicas(Renderer(spectrace.load_scene(_textured_scene(tmp_path, "bdpt")), device), 8, 32)
    assert path.mean() > 0.01
    assert_replicas_agree(bdpt, path, block=4)


def _dispersive_scene(tmp_path: Path, integrator: str, lamp: str = "rectangle") -> Path:
    """A flint-glass sphere on a floor under a lamp (a rectangle, or an emitting analytic sphere, whose light points
    and densities come from its own parametrisation): the paths through glass keep their hero wavelength alone, on
    either subpath."""
    return _write(
        tmp_path,
        camera_film(origin="[0, 1.2, 2.2]", target="[0, 0.3, 0]", fov="50", width="16", height="16")
        + f"""
[integrator]
type = "{integrator}"
max_depth = 6

[materials.flint]
type = "dielectric"
ior = "SF11"

[materials.floor]
type = "diffuse"
reflectance = {{ rgb = [0.7, 0.6, 0.5] }}

[materials.black]
type = "diffuse"
reflectance = {{ value = 0 }}

[[shapes]]
type = "rectangle"
material = "floor"
transform = [{{ scale = 3 }}, {{ rotate = {{ axis = [1, 0, 0], angle = -90 }} }}]

[[shapes]]
type = "sphere"
material = "flint"
transform = [{{ scale = 0.5 }}, {{ translate = [0, 0.5, 0] }}]

[[shapes]]
type = "{lamp}"
material = "black"
emitter = {{ radiance = {{ rgb = [1, 0.9, 0.8], scale = 6 }} }}
transform = [{{ scale = 0.6 }}, {{ rotate = {{ axis = [1, 0, 0], angle = 90 }} }}, {{ translate = [0.3, 2, 0.2] }}]
""",
    )


@pytest.mark.slow
@pytest.mark.parametrize("lamp", ["rectangle", "sphere"])
def test_dispersive_glass_agrees_with_the_path_tracer(device, tmp_path, lamp):
    path_scene = spectrace.load_scene(_dispersive_scene(tmp_path, "path", lamp))
    path = spectrace_replicas(Renderer(path_scene, device), 8, 96)
    bdpt = spectrace_replicas(Renderer(spectrace.load_scene(_dispersive_scene(tmp_path, "bdpt", lamp)), device), 8, 96)
    assert path.mean() > 0.01
    assert_replicas_agree(bdpt, path, block=4)


@pytest.mark.parametrize("pixels", [None, 3])
def test_pass_split_gives_the_same_bits(device, tmp_path, monkeypatch, pixels):
    scene = spectrace.load_scene(_textured_scene(tmp_path, "bdpt")).with_overrides(
        max_depth=10, spp=6, pixels_per_light_path=pixels
    )
    one_pass = Renderer(scene, device).render(pass_spp=6).xyz
    split = Renderer(scene, device).render(pass_spp=1).xyz
    np.testing.assert_array_equal(one_pass, split)
    # Two record slots per launch: many pixel samples are launched again for their later records.
    monkeypatch.setattr(light_tracer, "MAX_RECORD_SLOTS", 2)
    relaunched = Renderer(scene, device).render(pass_spp=4).xyz
    np.testing.assert_array_equal(one_pass, relaunched)


def test_refusals_in_one_line(device, tmp_path):
    # The equirectangular camera's importance is over the sphere of directions: kernels/bdpt.cl's camera vertex and
    # MIS densities are the film-plane cameras' (media, lights at infinity and lens cameras are all taken now).
    text = _floor_scene(tmp_path, "bdpt").read_text().replace("[camera]\n", '[camera]\ntype = "equirectangular"\n')
    text = re.sub(r"\nfov = [^\n]*", "", text)  # an equirectangular camera has no field of view
    scene = spectrace.load_scene(_write(tmp_path, text))
    with pytest.raises(SpectraceError, match="'equirectangular'") as error:
        Renderer(scene, device)
    assert "\n" not in str(error.value)


def test_unbounded_depth_refused(device, tmp_path):
    scene = spectrace.load_scene(_floor_scene(tmp_path, "bdpt")).with_overrides(max_depth=-1)
    with pytest.raises(SpectraceError, match="max_depth"):
        Renderer(scene, device)


@pytest.mark.parametrize(
    ("changes", "spectral_bins", "match"),
    [
        ({"pixel_filter": spectrace.PixelFilter("gaussian")}, 0, "gaussian filter"),
        ({}, 4, "spectral bands"),
    ],
)
def test_what_the_light_tracer_has_but_bdpt_has_not_is_refused(device, tmp_path, changes, spectral_bins, match):
    """The light tracer's filter spreads and spectral bands are not in BDPT's kernels."""
    scene = spectrace.load_scene(_floor_scene(tmp_path, "bdpt"))
    with pytest.raises(SpectraceError, match=match) as error:
        Renderer(scene.with_overrides(**changes), device, spectral_bins=spectral_bins)
    assert "\n" not in str(error.value)


def _slide_scene(tmp_path: Path, integrator: str):
    """The floor under a spot light whose slide (a 2 × 2 image of different colours) projects onto it."""
    scene = spectrace.load_scene(_floor_scene(tmp_path, integrator)).with_overrides(seed=3)
    pixels = np.array([[[0.9, 0.2, 0.1], [0.1, 0.8, 0.2]], [[0.2, 0.3, 0.9], [0.7, 0.7, 0.7]]])
    spot = spectrace.spot_light((0.3, -0.2, 1.0), (0.3, -0.2, 0.0), 40.0, intensity=2.0, slide=spectrace.bitmap(pixels))
    return scene.with_overrides(lights=[spot])


def test_a_spot_lights_slide_agrees_with_the_path_tracer(device, tmp_path):
    path = spectrace_replicas(Renderer(_slide_scene(tmp_path, "path"), device), 8, 8)
    bdpt = spectrace_replicas(Renderer(_slide_scene(tmp_path, "bdpt"), device), 8, 8)
    assert path.mean() > 0.01
    assert_replicas_agree(bdpt, path, block=8)


CAMERAS = {  # each replaces the pinhole's field of view
    "pinhole": "fov = 30\n",
    "thinlens": 'fov = 30\ntype = "thinlens"\naperture_radius = 0.08\nfocus_distance = 1.6\n',
    "orthographic": 'type = "orthographic"\nview_width = 1.4\n',
}


def _lights_at_infinity(tmp_path: Path, integrator: str, target: str, camera: str, sky: bool = False):
    """test_light_tracer.py's scene of a distant light, a constant environment (seen past the objects) and an
    emitting sphere, seen through `camera`; sky: an environment map with a small bright sun instead of the constant
    environment (its importance sampling's density in the MIS weights)."""
    text = _mixed_scene(tmp_path, integrator, target).read_text().replace("fov = 30\n", CAMERAS[camera])
    if sky:
        rgb = np.random.default_rng(4).uniform(0.0, 0.2, (8, 16, 3)).astype(np.float32)
        rgb[2, 5] = (30.0, 25.0, 10.0)
        write_exr(tmp_path / "sky.exr", rgb, None, {})
        constant = 'type = "constant"\nradiance = { value = 0.1 }'
        assert constant in text
        text = text.replace(constant, 'type = "envmap"\nfile = "sky.exr"\nscale = 0.5')
    return spectrace.load_scene(_write(tmp_path, text))


@pytest.mark.slow
@pytest.mark.parametrize(
    ("target", "camera", "sky"),
    [
        ("[-0.5, 0.45, 0]", "pinhole", False),
        ("[0.6, 0.3, -0.3]", "thinlens", False),
        ("[0, 0.3, 0]", "orthographic", False),
        ("[0, 0.3, 0]", "pinhole", True),
    ],
    ids=["rough-glass", "cube-thin-lens", "orthographic", "environment-map"],
)
def test_lights_at_infinity_and_lens_cameras_agree_with_the_path_tracer(device, tmp_path, target, camera, sky):
    path = spectrace_replicas(Renderer(_lights_at_infinity(tmp_path, "path", target, camera, sky), device), 8, 40)
    bdpt = spectrace_replicas(Renderer(_lights_at_infinity(tmp_path, "bdpt", target, camera, sky), device), 8, 40)
    assert path.mean() > 0.05
    assert_replicas_agree(bdpt, path, block=4)


@pytest.mark.parametrize("hidden", [False, True])
def test_environment_seen_directly(device, tmp_path, hidden):
    """Nothing but a constant environment of radiance 0.3: every pixel sees exactly it (the camera path's own
    vertex at infinity, weight 1), or nothing when hidden."""
    text = (
        _camera("[0, 0, 0]", "[0, 0, -1]", 60, 8)
        + f"""
[integrator]
type = "bdpt"
max_depth = 3
hide_environment = {"true" if hidden else "false"}

[materials.grey]
type = "diffuse"
reflectance = {{ value = 0.5 }}

[[lights]]
type = "constant"
radiance = {{ value = 0.3 }}
"""
    )
    y = Renderer(spectrace.load_scene(_write(tmp_path, text)), device).render(spp=64).xyz[..., 1]
    if hidden:
        assert np.all(y == 0.0)
    else:
        mean, standard_error = mean_and_standard_error(y.ravel())
        assert standard_error < 0.01 * 0.3
        assert_within_standard_errors(mean, 0.3, standard_error)


def test_lights_at_infinity_and_a_thin_lens_split_into_passes_give_the_same_bits(device, tmp_path):
    scene = _lights_at_infinity(tmp_path, "bdpt", "[0.6, 0.3, -0.3]", "thinlens").with_overrides(spp=4)
    one_pass = Renderer(scene, device).render(pass_spp=4).xyz
    split = Renderer(scene, device).render(pass_spp=1).xyz
    np.testing.assert_array_equal(one_pass, split)
