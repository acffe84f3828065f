"""The white furnace for every integrator of the registry (spectrace.integrators.INTEGRATORS) and for every material
of the registry (spectrace.materials.MATERIALS), smooth and rough where it has a roughness; and each integrator
refuses exactly the features it declares (REFUSES), in one line that names it, and tiles and checkpoints as it
declares (SPLATS, CHECKPOINT_PROBLEM).

One white Lambertian sphere in a uniform environment of radiance 1 is the closed form every integrator renders: a
convex surface sees only the environment, so the light arriving directly is all there is and the image's mean Y is
1, for the local model (`direct`) too.

Two spheres side by side in a uniform environment of radiance 1 (light passes between them, and through them where
they transmit), seen whole with the environment around them, `max_depth` 16 (paths of three segments and more, where
the subpaths of BDPT go on past the vertices they are joined at), Russian roulette off (its rare heavy weights hide
from a standard error). A material that absorbs nothing returns the environment exactly: the image's mean Y is 1.
The closed form holds up to the paths longer than `max_depth` (inside and between the spheres), which the path
tracer puts below 1e-4 (6e-5 for the thin dielectric, whose passes count as segments); SLACK allows that much. A
material that absorbs (a metal, a tinted base, a rough lobe's single scattering) has no closed form here: each
integrator's mean agrees with the path tracer's, within 4 combined standard errors, and none exceeds 1.

Standard errors come from independent replicas (consecutive sample ranges of one render), as the splatting
integrators' pixels are not independent. BDPT runs with one pixel per light subpath, where the light-to-camera
strategy's share of each path, and with it an error in the weights that share it, is largest.

The integrators that carry light over every bounce (all but LOCAL) render the two spheres of every material case.
Where an integrator cannot see a material by design, the case is left out with its reason: the light tracer renders
a delta lobe seen from the camera black (docs/integrators.md), and SPPM refuses a material whose delta and non-delta
lobes share a surface (a smooth coat over a diffuse base, a mix of a delta and a non-delta material), which
test_sppm_refuses_exactly_the_mixed_lobes checks against the table."""

import dataclasses
import functools
from collections.abc import Callable

import numpy as np
import pytest

import spectrace
from replica_agreement import spectrace_replicas
from rgl_tensor import ggx_file
from spectrace.engine.checkpoint import read_checkpoint, save_checkpoint
from spectrace.engine.renderer import Renderer
from spectrace.engine.tiles import whole_film_rows
from spectrace.errors import SpectraceError
from spectrace.film.response import FilmResponse
from spectrace.integrators import INTEGRATORS
from spectrace.integrators.base import FEATURES
from spectrace.materials import MATERIALS
from spectrace.pixel_filters import PixelFilter
from spectrace.scene.model import Scene
from spectrace.spectral.grid import GRID_NM
from stats_toolkit import (
    assert_at_most_within_standard_errors,
    assert_within_standard_errors,
    mean_and_standard_error,
)

SLACK = 2e-4
SIDE = 16
REPLICAS = 16
# Samples per pixel of a replica, for every registered integrator (test_every_integrator_has_its_furnace keeps it
# complete): the light tracer's pixels are noisier at equal spp.
SPP = {"path": 16, "direct": 16, "bdpt": 16, "light": 64, "sppm": 16}
# The integrators that leave out light after its first bounce off a rough surface (the local model): the two spheres
# light each other, so only the single sphere's closed form holds for them.
LOCAL = {"direct"}


@dataclasses.dataclass(frozen=True)
class Case:
    name: str
    material: Callable[[], object]
    lossless: bool  # absorbs nothing: the closed form 1; otherwise the path tracer's mean is the reference
    delta_lobe: bool  # has a delta lobe, which the light tracer cannot see from the camera
    sppm_refused: bool = False  # delta and non-delta lobes on one surface
    fast: tuple[str, ...] = ()  # the integrators of the quick subset; the others are marked slow
    only: tuple[str, ...] = ()  # the integrators that render it, where the others refuse it (empty: all)


S = spectrace
_GREEN_BAND = np.where((GRID_NM >= 500) & (GRID_NM <= 560), 0.9, 0.0)
_RED_EMISSION = S.Spectrum(np.exp(-0.5 * ((GRID_NM - 650.0) / 20.0) ** 2))
# One list per registry entry: test_every_material_has_a_furnace_case keeps it complete.
CASES = {
    "diffuse": [Case("white", lambda: S.diffuse(1.0), True, False, fast=("bdpt",))],
    "conductor": [
        Case("gold", lambda: S.conductor("Au"), False, True),
        Case("rough gold", lambda: S.conductor("Au", roughness=0.3), False, False),
        # framed along the sphere's dp/du (material_frame), the same frame in every integrator
        Case("anisotropic gold", lambda: S.conductor("Au", roughness=0.05, roughness_v=0.5), False, False),
        Case(
            "anisotropic beckmann gold",
            lambda: S.conductor("Au", roughness=0.4, roughness_v=0.1, distribution="beckmann"),
            False,
            False,
        ),
    ],
    "mirror": [Case("white", lambda: S.mirror(1.0), True, True)],
    "plastic": [
        Case("white", lambda: S.plastic(1.0), True, True, sppm_refused=True, fast=("bdpt", "path")),
        Case("white ior 3", lambda: S.plastic(1.0, ior=3.0), True, True, sppm_refused=True, fast=("bdpt",)),
        Case("grey", lambda: S.plastic(0.3), False, True, sppm_refused=True, fast=("bdpt",)),
        Case("rough white", lambda: S.plastic(1.0, roughness=0.3), False, False),
        Case("rough coat", lambda: S.plastic(1.0, roughness=0.3, coat_transmission="rough"), False, False),
    ],
    "dielectric": [
        Case("smooth", lambda: S.dielectric(1.5), True, True),
        Case("rough", lambda: S.dielectric(1.5, roughness=0.3), False, False),
    ],
    "retroreflector": [
        Case("smooth", lambda: S.retroreflector(1.0, roughness=0.0), True, True),
        Case("rough", lambda: S.retroreflector(1.0, roughness=0.3), False, False),
    ],
    "thindielectric": [Case("smooth", lambda: S.thindielectric(1.5), True, True)],
    "diffusetransmission": [Case("white", lambda: S.diffusetransmission(0.3, 0.7), True, False)],
    "principled": [
        Case("white metal", lambda: S.principled(1.0, roughness=0.5, metallic=1.0), False, False, fast=("bdpt",)),
        # framed along the sphere's dp/du (material_frame), the same frame in every integrator
        Case(
            "anisotropic white metal",
            lambda: S.principled(1.0, roughness=0.5, metallic=1.0, anisotropic=0.9),
            False,
            False,
        ),
        Case("glass", lambda: S.principled(1.0, roughness=0.5, spec_trans=1.0), False, False, fast=("bdpt",)),
        Case("grey base with clearcoat", lambda: S.principled(0.5, roughness=0.5, clearcoat=1.0), False, False),
    ],
    # Rough sheets: where the specular transmission's test passes one way only (grazing angles), the light tracer's
    # and BDPT's light subpaths weigh their samples with the directions swapped (the adjoint BSDF).
    "principledthin": [
        Case(
            "white specular sheet",
            lambda: S.principledthin(1.0, roughness=0.8, spec_trans=1.0),
            False,
            False,
            fast=("bdpt",),
        ),
        Case(
            "grey sheet with every lobe",
            lambda: S.principledthin(0.5, roughness=0.7, spec_trans=0.5, diff_trans=1.0, sheen=0.5),
            False,
            False,
        ),
    ],
    # Sheets that only absorb: an ideal polariser passes at most what arrives, one of extinction 1 and a retarder
    # all of it, whatever the polarisation the other sphere left.
    "polarizer": [
        Case("ideal", lambda: S.polarizer(30.0), False, True, only=("path",)),
        Case("extinction 1", lambda: S.polarizer(30.0, extinction=1.0), True, True, only=("path",)),
    ],
    "retarder": [Case("quarter wave", lambda: S.retarder(20.0), True, True, only=("path",))],
    # Unpolarised here (the furnace has no polarising element): Mitsuba 3's unpolarised pplastic.
    "pplastic": [Case("white", lambda: S.pplastic(1.0, roughness=0.3), False, False, fast=("path",))],
    # Fibres along the spheres' dp/du, h from their v: S is not reciprocal, so the light tracer's and BDPT's light
    # subpaths weigh their samples by the adjoint (kernels/bsdf_hair.cl).
    "hair": [
        Case("white fibre", lambda: S.hair(sigma_a=0.0, beta_m=0.2, beta_n=0.5), True, False, fast=("bdpt", "light")),
        Case("brown fibre", lambda: S.hair(eumelanin=0.6), False, False),
    ],
    # A measurement written from GGX (tests/rgl_tensor.py): the sampler follows the file's luminance and visible
    # normals, and light subpaths weigh their samples by the adjoint (kernels/bsdf_measured.cl).
    "measured": [Case("ggx measurement", lambda: S.measured(ggx_file(0.3)), False, False, fast=("path",))],
    # Stochastic layered BSDFs (kernels/layered.cl): each integrator sees the same estimates of eval and pdf, and
    # the sampler's weights are right in expectation, so each agrees with the path tracer within its errors. A
    # metal that reflects everything (η = 0) under a clear coat and a slab of albedo 1 loses only the walks max_depth
    # cuts off (tests/materials/test_layered.py), not a closed form within SLACK: compared with the path tracer.
    "coatedconductor": [
        Case(
            "lossless smooth layers",
            lambda: S.coatedconductor(eta=0.0, k=1.0, albedo=1.0, thickness=0.2, max_depth=100),
            False,
            True,
            sppm_refused=True,
            fast=("path",),
        ),
        Case("rough gold", lambda: S.coatedconductor("Au", roughness=0.3, conductor_roughness=0.2), False, False),
    ],
    "coateddiffuse": [
        Case("white rough", lambda: S.coateddiffuse(1.0, roughness=0.3, thickness=0.0), False, False, fast=("bdpt",)),
        Case("grey smooth coat", lambda: S.coateddiffuse(0.5, albedo=0.5, g=0.3), False, True, sppm_refused=True),
    ],
    "mix": [
        Case(
            "diffuse and smooth plastic",
            lambda: S.mix([S.diffuse(1.0), S.plastic(1.0, ior=3.0)], amount=0.75),
            True,
            True,
            sppm_refused=True,
            fast=("bdpt",),
        ),
        Case("diffuse and mirror", lambda: S.mix([S.diffuse(1.0), S.mirror(1.0)]), True, True, sppm_refused=True),
        Case(
            "rough metal and diffuse",
            lambda: S.mix([S.conductor("Cu", roughness=0.2), S.diffuse(0.8)]),
            False,
            False,
        ),
    ],
    # Green light re-emitted in the red, where Y weighs it less: the image's Y stays below 1 as its energy does
    # (light moved toward a larger ȳ would raise Y without creating energy). The path and light tracers and BDPT
    # transport it.
    "fluorescent": [
        Case(
            "green to red dye over its complement",
            lambda: S.fluorescent(S.diffuse(S.Spectrum(1.0 - _GREEN_BAND)), S.Spectrum(_GREEN_BAND), _RED_EMISSION),
            False,
            False,
            fast=("path",),
            only=("path", "light", "bdpt"),
        )
    ],
}
ALL_CASES = [(name, case) for name, cases in CASES.items() for case in cases]


def _scene(case: Case, integrator: str, positions=(-1.25, 1.25)) -> Scene:
    material = case.material()
    shapes = [S.shape("sphere", material, transform=[{"translate": [x, 0.0, 0.0]}]) for x in positions]
    return Scene(
        camera=S.Camera(origin=(0.0, 1.0, -4.5), target=(0.0, 0.0, 0.0), fov_degrees=40.0),
        width=SIDE,
        height=SIDE,
        shapes=shapes,
        lights=[S.constant_environment(1.0)],
        max_depth=16,
        rr_depth=64,
        integrator=integrator,
        pixels_per_light_path=1 if integrator == "bdpt" else None,
        seed=7,
    )


@functools.cache
def _furnace(name: str, case_name: str, integrator: str, device) -> tuple[float, float]:
    """The image's mean Y and its standard error over REPLICAS independent replicas."""
    case = next(c for c in CASES[name] if c.name == case_name)
    images = spectrace_replicas(Renderer(_scene(case, integrator), device), REPLICAS, SPP[integrator])
    mean, standard_error = mean_and_standard_error(images[..., 1].mean(axis=(1, 2)))
    return float(mean), float(standard_error)


def _id(name: str, case: Case) -> str:
    return f"{name}-{case.name.replace(' ', '_')}"


def _params():
    for name, case in ALL_CASES:
        for integrator in INTEGRATORS:
            if integrator in LOCAL:
                continue
            if integrator == "light" and case.delta_lobe:
                continue  # seen in a delta lobe, black to the light tracer by design
            if integrator == "sppm" and case.sppm_refused:
                continue
            if case.only and integrator not in case.only:
                continue  # refused by the integrator (spectrace.integrators.scene_settings_problem)
            marks = () if integrator in case.fast else (pytest.mark.slow,)
            yield pytest.param(name, case.name, integrator, marks=marks, id=f"{_id(name, case)}-{integrator}")


def test_every_integrator_has_its_furnace():
    assert set(SPP) == set(INTEGRATORS)
    assert set(INTEGRATORS) > LOCAL


@pytest.mark.parametrize("integrator", list(INTEGRATORS))
def test_every_integrator_renders_the_white_sphere(device, integrator):
    white = CASES["diffuse"][0]
    assert white.lossless and not white.delta_lobe
    scene = _scene(white, integrator, positions=(0.0,))
    images = spectrace_replicas(Renderer(scene, device), REPLICAS, SPP[integrator])
    mean, standard_error = mean_and_standard_error(images[..., 1].mean(axis=(1, 2)))
    assert_within_standard_errors(mean, 1.0, standard_error, slack=SLACK, what=f"a white sphere under {integrator}")


GLOWING = [name for name, plugin in INTEGRATORS.items() if not {"media", "glowing media"} & set(plugin.REFUSES)]


@pytest.mark.parametrize("integrator", GLOWING)
def test_a_glowing_medium_in_the_furnace_shows_the_environment(device, integrator):
    """A scattering sphere of medium whose emission Le equals the environment's radiance 1: the radiative transfer
    equation's sources, σa Le + σs ∫ p L, then balance its losses σt L at L = 1 everywhere, so the image's mean Y
    is 1 whatever σa, σs and g, for every integrator that renders glowing media (the light tracer's paths starting
    in the medium and at the environment, BDPT's camera subpaths gathering the glow). Paths beyond max_depth 16
    in a sphere of optical radius 1.4 carry less than SLACK."""
    glow = S.shape("sphere", None, interior=S.medium(sigma_a=0.6, sigma_s=0.8, g=0.4, emission=1.0))
    scene = dataclasses.replace(_scene(CASES["diffuse"][0], integrator, positions=()), shapes=[glow])
    images = spectrace_replicas(Renderer(scene, device), REPLICAS, SPP[integrator])
    mean, standard_error = mean_and_standard_error(images[..., 1].mean(axis=(1, 2)))
    assert_within_standard_errors(
        mean, 1.0, standard_error, slack=SLACK, power=0.01, what=f"a glowing medium's furnace under {integrator}"
    )
    assert set(GLOWING) >= {"path", "light", "bdpt"}


def test_the_light_tracer_counts_a_point_in_overlapping_glow_boxes_once(device):
    """Its paths start uniformly in the boxes of the glowing shapes, so a point in two boxes has the sum of their
    densities: a cube turned 45° has a box with empty corners, and a small glowing cube sits in one, outside the
    big cube but inside its box. In the furnace (Le = the environment's radiance 1) every 2×2 block is 1 within
    4 standard errors. A start weighted by its own box's density alone makes the small cube glow too brightly:
    its blocks measured 1.107 and 1.072 (z above 5) with that error."""
    medium = S.medium(sigma_a=1.5, sigma_s=0.5, emission=1.0)
    turned = S.shape("cube", None, interior=medium, transform=[{"rotate": {"axis": [0, 0, 1], "angle": 45}}])
    corner = S.shape("cube", None, interior=medium, transform=[{"scale": 0.2}, {"translate": [1.05, 1.05, 0]}])
    scene = Scene(
        camera=S.Camera(origin=(0.0, 0.0, -6.0), target=(0.0, 0.0, 0.0), type="orthographic", view_width=3.0),
        width=12,
        height=12,
        shapes=[turned, corner],
        lights=[S.constant_environment(1.0)],
        max_depth=16,
        rr_depth=64,
        integrator="light",
        seed=5,
    )
    y = spectrace_replicas(Renderer(scene, device), 8, SPP["light"])[..., 1]
    blocks = y.reshape(8, 6, 2, 6, 2).mean(axis=(2, 4))
    mean, standard_error = mean_and_standard_error(blocks)
    assert_within_standard_errors(mean, np.ones_like(mean), standard_error, slack=SLACK, what="overlapping boxes")
    # the small cube's blocks (top left: looking along +z, +x is on the image's left) can tell those from 1
    assert standard_error[:2, 0].max() < 0.015


def _lit_sphere(integrator: str) -> Scene:
    """A white sphere lit by a point light and a small area light, seen by a pinhole with the box filter: a scene
    every integrator renders."""
    lamp = S.shape("rectangle", S.diffuse(0.5), emitter=S.area_emitter(1.0), transform=[{"translate": [0, 3, 0]}])
    return Scene(
        camera=S.Camera(origin=(0.0, 1.0, -4.5), target=(0.0, 0.0, 0.0), fov_degrees=40.0),
        width=8,
        height=8,
        shapes=[S.shape("sphere", S.diffuse(0.8)), lamp],
        lights=[S.point_light((2.0, 2.0, -2.0), intensity=1.0)],
        integrator=integrator,
    )


# Each feature of spectrace.integrators.base.FEATURES as a change of _lit_sphere's scene, media and spectral bands.
FEATURE_CHANGES = {
    "spectral bands": ({}, 0, 4),
    "AOVs": ({"aovs": ("albedo",)}, 0, 0),
    "pixel filters": ({"pixel_filter": PixelFilter("gaussian", stddev=0.5)}, 0, 0),
    "film responses": ({"film_response": FilmResponse(wavelengths=(400.0, 700.0))}, 0, 0),
    "media": ({}, 1, 0),
    "hidden area lights": ({"hide_emitters": True}, 0, 0),
    "glowing media": ({"shapes": [S.shape("sphere", None, interior=S.medium(sigma_a=0.5, emission=1.0))]}, 1, 0),
}


def test_every_feature_an_integrator_may_refuse_has_its_scene():
    assert tuple(FEATURE_CHANGES) == FEATURES
    for plugin in INTEGRATORS.values():
        assert set(plugin.REFUSES) <= set(FEATURES), plugin.NAME


@pytest.mark.parametrize("integrator", list(INTEGRATORS))
@pytest.mark.parametrize("feature", FEATURES)
def test_each_integrator_refuses_exactly_what_it_declares(integrator, feature):
    plugin = INTEGRATORS[integrator]
    assert plugin.problem(_lit_sphere(integrator), 0, 0) is None
    changes, media, bands = FEATURE_CHANGES[feature]
    problem = plugin.problem(_lit_sphere(integrator).with_overrides(**changes), media, bands)
    assert (problem is not None) == (feature in plugin.REFUSES), (integrator, feature, problem)
    if problem is not None:
        assert f"integrator '{integrator}'" in problem and "\n" not in problem


@pytest.mark.parametrize("integrator", [name for name, plugin in INTEGRATORS.items() if plugin.REFUSES])
def test_the_renderer_refuses_what_its_integrator_does_before_building_a_program(device, integrator, monkeypatch):
    changes, media, bands = FEATURE_CHANGES[INTEGRATORS[integrator].REFUSES[0]]
    scene = _lit_sphere(integrator).with_overrides(**changes)
    expected = INTEGRATORS[integrator].problem(scene, media, bands)
    # a medium counted (media) must be one the scene holds: a closed shape filled with it
    assert expected is not None and (media == 0 or "shapes" in changes)

    def no_build(*args, **kwargs):
        raise AssertionError("a program was built for a scene its integrator refuses")

    monkeypatch.setattr(type(device), "build_program", no_build)
    with pytest.raises(SpectraceError) as refused:
        Renderer(scene, device, spectral_bins=bands)
    assert str(refused.value).endswith(expected)


@pytest.mark.parametrize("integrator", list(INTEGRATORS))
def test_each_integrator_refuses_tiles_and_checkpoints_as_it_declares(device, integrator, tmp_path):
    """SPLATS (its contributions land in any pixel): a tile of the film is refused, by the renderer and by a tiled
    render's plan; CHECKPOINT_PROBLEM: a checkpoint is refused with that line."""
    plugin = INTEGRATORS[integrator]
    scene = _lit_sphere(integrator)
    tile = Renderer(scene, device)
    tile.pixel_range = (0, tile.pixel_count // 2)
    if plugin.SPLATS is None:
        tile.run_pass(1)
        assert whole_film_rows(scene, 4) == 4
    else:
        with pytest.raises(SpectraceError, match=f"its {plugin.SPLATS} land in any pixel"):
            tile.run_pass(1)
        with pytest.raises(SpectraceError, match="renders the whole film as one tile"):
            whole_film_rows(scene, 4)
    whole = Renderer(scene, device)
    whole.run_pass(1)
    if plugin.CHECKPOINT_PROBLEM is None:
        save_checkpoint(tmp_path / "state.npz", whole)
        assert read_checkpoint(tmp_path / "state.npz").state.samples_done == 1
    else:
        with pytest.raises(SpectraceError) as refused:
            save_checkpoint(tmp_path / "state.npz", whole)
        assert str(refused.value) == plugin.CHECKPOINT_PROBLEM and not (tmp_path / "state.npz").exists()


def test_every_material_has_a_furnace_case():
    assert set(CASES) == set(MATERIALS)
    roughness = {name for name, module in MATERIALS.items() if any(p.name == "roughness" for p in module.PARAMETERS)}
    for name in roughness - {n for n, m in MATERIALS.items() if getattr(m, "ALWAYS_ROUGH", False)}:
        # a smooth case (a delta lobe) and a rough one
        assert {c.delta_lobe for c in CASES[name]} == {True, False}, name


@pytest.mark.parametrize("name, case_name, integrator", list(_params()))
def test_furnace(device, name, case_name, integrator):
    case = next(c for c in CASES[name] if c.name == case_name)
    mean, standard_error = _furnace(name, case_name, integrator, device)
    what = f"{name} ({case_name}) under {integrator}"
    if case.lossless:
        assert_within_standard_errors(mean, 1.0, standard_error, slack=SLACK, what=what)
        return
    assert_at_most_within_standard_errors(mean, 1.0, standard_error, slack=SLACK, what=what)
    if integrator != "path":
        reference, reference_error = _furnace(name, case_name, "path", device)
        assert_within_standard_errors(mean, reference, np.hypot(standard_error, reference_error), what=what)


@pytest.mark.parametrize("name, case", ALL_CASES, ids=[_id(n, c) for n, c in ALL_CASES])
def test_sppm_refuses_exactly_the_mixed_lobes(name, case):
    problem = INTEGRATORS["sppm"].problem(_scene(case, "sppm"), 0, 0)
    assert (problem is not None) == case.sppm_refused, (name, case.name, problem)
