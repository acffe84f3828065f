"""Fluorescent materials in BDPT (kernels/bdpt_fluorescence.cl): elastic paths by every strategy, inelastic ones by
the path tracer's estimator from the camera side, checked against a closed form, the path and light tracers, and the
base's own bits; and in the local model (`direct`), whose direct light a dye re-emits, against the same closed form.

The closed form is test_fluorescent_path.py's: a Lambertian sphere in a uniform environment E(λ) sends
L(λo) = ρ(λo) E(λo) + Q e(λo)/λo ∫ a(λi) E(λi) λi dλi toward the camera, all of it direct light; BDPT has no
spectral bands, so its film XYZ (and the local model's) is compared with that radiance integrated here against
colour-science's CIE 1931 2° functions (film XYZ is ∫ L cmf dλ / ∫ ȳ dλ, docs/colour.md).

The Cornell box has its white surfaces (floor, ceiling, back wall and both blocks) dyed and its lamp replaced by one
that shines in the dye's excitation band alone, so that the green the image shows is re-emitted light (nine tenths
of its Y) and the blue is reflected: BDPT, the path tracer and the light tracer, which reach the two parts by
different strategies, agree region and block by block within 5 standard errors from independent replicas
(tests/replica_agreement.py).

The closed enclosure of tests/render/test_bdpt.py (walls emitting Le and reflecting ρ diffusely) with its walls dyed
(excitation at 400-460 nm, emission around 560 nm, so that a path re-emits at most once): its elastic paths of k
segments still carry Le ρ^(k−1) at every wavelength (the base is the whole elastic part), so each BDPT strategy
kept alone estimates that for k = 3, and their MIS-weighted images add up to it: the weights, whose densities at the
dyes carry each side's probability of keeping the base, still sum to one. The whole render adds the paths that
re-emit once, at any of their k − 1 inner vertices: L(λo) = Le Σ_{k≤d} ρ^(k−1) + Le C(λo) Σ_{2≤k≤d} (k − 1) ρ^(k−2)
with C(λo) = Q e(λo)/λo ∫ a λ dλ."""

import dataclasses

import numpy as np
import pytest
from tests.render import test_bdpt
from tests.render.test_bdpt import SEGMENTS, _enclosure, _image_mean
from tests.render.test_light_tracer import ALBEDO, EMITTED

import spectrace as S
from replica_agreement import assert_replicas_agree, spectrace_replicas
from spectrace.engine.renderer import Renderer
from spectrace.materials.fluorescent import FluorescentMaterial
from spectrace.resources import resolve_scene_path
from spectrace.scene.model import Scene
from spectrace.spectral.grid import GRID_NM
from spectrace.spectral.spectrum import Spectrum
from stats_toolkit import assert_within_standard_errors, mean_and_standard_error

one_strategy = test_bdpt.strategy_device  # the fixture building BDPT with one strategy kept

SIDE = 16
REGION = (slice(4, 12), slice(4, 12))  # 64 pixels, all on the sphere
REPLICAS = 16
SIGMAS = 4.0
Q = 0.8
# A dye absorbing 0.8 of the photons at 420-470 nm (nothing elsewhere), emitting around 560 nm.
EXCITATION = np.where((GRID_NM >= 420) & (GRID_NM <= 470), 0.8, 0.0)
EMISSION = np.exp(-0.5 * ((GRID_NM - 560.0) / 25.0) ** 2)


def _dye(base, quantum_yield=Q):
    return S.fluorescent(base, Spectrum(EXCITATION), Spectrum(EMISSION), quantum_yield=quantum_yield)


def _sphere(material, environment: np.ndarray, spp: int, integrator: str = "bdpt") -> Scene:
    return Scene(
        camera=S.Camera(origin=(0.0, 0.0, -4.0), target=(0.0, 0.0, 0.0), fov_degrees=30.0),
        width=SIDE,
        height=SIDE,
        shapes=[S.shape("sphere", material)],
        lights=[S.constant_environment(Spectrum(environment))],
        max_depth=2,
        spp=spp,
        seed=3,
        integrator=integrator,
        pixels_per_light_path=1 if integrator == "bdpt" else None,
    )


def _closed_form_xyz(radiance: np.ndarray) -> np.ndarray:
    colour = pytest.importorskip("colour")
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
    inside = np.abs(GRID_NM - cmfs.wavelengths.mean()) <= np.ptp(cmfs.wavelengths) / 2  # where the table has values
    cmf = np.stack([np.interp(GRID_NM, cmfs.wavelengths, cmfs.values[:, k]) for k in range(3)], axis=1)
    weights = np.trapezoid(cmf[inside] * radiance[inside, None], GRID_NM[inside], axis=0)
    return weights / np.trapezoid(cmf[inside, 1], GRID_NM[inside])


def _fluorescent_radiance(environment: np.ndarray, quantum_yield: float) -> np.ndarray:
    normalised = EMISSION / np.trapezoid(EMISSION, GRID_NM)
    return quantum_yield * normalised / GRID_NM * np.trapezoid(EXCITATION * environment * GRID_NM, GRID_NM)


@pytest.mark.parametrize("integrator", ["bdpt", "direct"])
@pytest.mark.parametrize(
    "case",
    [
        # blue light on a dye over a black base: all that is seen is re-emitted (the camera side's inelastic part)
        "blue light, black base",
        # a white furnace on a dye over a base of albedo 1 - a: both parts, reflected and re-emitted
        "furnace, base of albedo 1 - a",
    ],
)
def test_the_closed_form_of_a_dyed_sphere(device, case, integrator):
    if case.startswith("blue"):
        light, base, quantum_yield = np.exp(-0.5 * ((GRID_NM - 445.0) / 8.0) ** 2), S.diffuse(0.0), Q
        elastic = np.zeros_like(GRID_NM)
    else:
        light, base, quantum_yield = np.ones_like(GRID_NM), S.diffuse(Spectrum(1.0 - EXCITATION)), 1.0
        elastic = (1.0 - EXCITATION) * light
    expected = _closed_form_xyz(elastic + _fluorescent_radiance(light, quantum_yield))
    spp = {"bdpt": 16, "direct": 64}[integrator]  # the local model's re-emission has next-event estimation alone
    scene = _sphere(_dye(base, quantum_yield), light, spp=spp, integrator=integrator)
    images = spectrace_replicas(Renderer(scene, device), REPLICAS, spp)
    for k in range(3):
        mean, error = mean_and_standard_error(images[:, REGION[0], REGION[1], k].mean(axis=(1, 2)))
        assert_within_standard_errors(mean, expected[k], error, sigmas=SIGMAS, what=f"{case}: XYZ[{k}]")
        # precise enough to tell a missing λi/λo (a fifth of the re-emission) where the channel sees light
        assert expected[k] < 0.1 * expected.max() or error < 0.05 * expected[k]


@pytest.mark.parametrize("integrator", ["bdpt", "direct"])
def test_light_outside_the_excitation_band_is_not_re_emitted(device, integrator):
    light = np.exp(-0.5 * ((GRID_NM - 620.0) / 4.0) ** 2)
    renderer = Renderer(_sphere(_dye(S.diffuse(0.0)), light, spp=16, integrator=integrator), device)
    renderer.render(spp=16)
    assert np.all(renderer.image().xyz[REGION] == 0.0)


def _box(quantum_yield: float, size: int) -> Scene:
    """The Cornell box with its white surfaces dyed over their own white and a lamp of 20 W/(m² sr nm) at 420-480
    nm, in the dye's excitation band (absorbing 0.7 of the photons at 400-500 nm, emitting around 540 nm)."""
    excitation = np.where((GRID_NM >= 400) & (GRID_NM <= 500), 0.7, 0.0)
    emission = np.exp(-0.5 * ((GRID_NM - 540.0) / 20.0) ** 2)
    lamp = np.where((GRID_NM >= 420) & (GRID_NM <= 480), 20.0, 0.0)
    scene = S.load_scene(resolve_scene_path("cornell_box")).with_overrides(width=size, height=size, seed=5)
    shapes = []
    for shape in scene.shapes:
        if shape.name == "white surfaces":
            dye = S.fluorescent(shape.material, Spectrum(excitation), Spectrum(emission), quantum_yield=quantum_yield)
            shape = dataclasses.replace(shape, material=dye)
        if shape.emitter is not None:
            shape = dataclasses.replace(shape, emitter=S.area_emitter(Spectrum(lamp)))
        shapes.append(shape)
    assert any(isinstance(s.material, FluorescentMaterial) for s in shapes)
    return scene.with_overrides(shapes=shapes)


def _undyed(scene: Scene) -> Scene:
    shapes = [
        dataclasses.replace(s, material=s.material.base) if isinstance(s.material, FluorescentMaterial) else s
        for s in scene.shapes
    ]
    return scene.with_overrides(shapes=shapes)


@pytest.mark.slow
def test_bdpt_the_path_tracer_and_the_light_tracer_agree_on_a_fluorescent_cornell_box(device):
    scene = _box(0.9, 32)
    bdpt = spectrace_replicas(Renderer(scene.with_overrides(integrator="bdpt"), device), 16, 32)
    path = spectrace_replicas(Renderer(scene.with_overrides(integrator="path"), device), 16, 32)
    light = spectrace_replicas(Renderer(scene.with_overrides(integrator="light"), device), 16, 32)
    assert_replicas_agree(bdpt, path, block=8, what="BDPT and the path tracer on a fluorescent Cornell box")
    assert_replicas_agree(bdpt, light, block=8, what="BDPT and the light tracer on a fluorescent Cornell box")
    # What is compared is mostly re-emitted: without the dye the image's Y is under a fifth of it.
    plain = spectrace_replicas(Renderer(_undyed(scene).with_overrides(integrator="bdpt"), device), 4, 16)
    assert plain[..., 1].mean() < 0.2 * bdpt[..., 1].mean()


@pytest.mark.parametrize("integrator", ["bdpt", "direct"])
def test_yield_zero_renders_its_base_bit_for_bit(device, integrator):
    scene = _box(0.0, 16).with_overrides(integrator=integrator)
    dyed = Renderer(scene, device)
    dyed.render(spp=8)
    plain = Renderer(_undyed(scene), device)
    plain.render(spp=8)
    np.testing.assert_array_equal(dyed.image().xyz, plain.image().xyz)


def test_a_bdpt_render_split_into_passes_has_the_same_bits(device):
    scene = _box(0.9, 16).with_overrides(integrator="bdpt")
    whole = Renderer(scene, device)
    whole.render(spp=8)
    split = Renderer(scene, device)
    split.render(spp=8, pass_spp=3)
    np.testing.assert_array_equal(whole.image().xyz, split.image().xyz)


ENCLOSURE_EXCITATION = np.where((GRID_NM >= 400) & (GRID_NM <= 460), 0.8, 0.0)


def _dyed_enclosure(max_depth: int) -> Scene:
    scene = _enclosure(max_depth)
    dyed = [
        dataclasses.replace(
            shape, material=S.fluorescent(shape.material, Spectrum(ENCLOSURE_EXCITATION), Spectrum(EMISSION), 1.0)
        )
        for shape in scene.shapes
    ]
    return scene.with_overrides(shapes=dyed)


@pytest.mark.slow
@pytest.mark.parametrize("s", range(SEGMENTS + 1))
def test_each_strategy_alone_estimates_the_elastic_paths_of_its_length_in_a_dyed_enclosure(one_strategy, s):
    device, chosen = one_strategy
    chosen |= {"s": s, "t": SEGMENTS + 1 - s, "unweighted": 1}
    # unweighted next-event estimation's 1/d² near the box's edges makes its replicas the noisiest
    replica_spp = 384 if s == 1 else 96
    mean, standard_error = _image_mean(Renderer(_dyed_enclosure(SEGMENTS), device), 8, replica_spp)
    assert_within_standard_errors(mean, EMITTED * ALBEDO ** (SEGMENTS - 1), standard_error, power=0.05)


@pytest.mark.slow
def test_weighted_strategies_add_up_in_a_dyed_enclosure(one_strategy):
    device, chosen = one_strategy
    scene = _dyed_enclosure(SEGMENTS).with_overrides(spp=8)
    sums = []
    for seed in range(8):
        total = 0.0
        for s in range(SEGMENTS + 1):
            chosen |= {"s": s, "t": SEGMENTS + 1 - s}
            total += Renderer(scene.with_overrides(seed=seed + 100), device).render().xyz[..., 1].mean()
        sums.append(total)
    mean, standard_error = mean_and_standard_error(np.array(sums))
    assert_within_standard_errors(mean, EMITTED * ALBEDO ** (SEGMENTS - 1), standard_error, power=0.05)


def test_a_dyed_enclosure_holds_its_closed_form(device):
    colour = pytest.importorskip("colour")
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
    y_bar = np.interp(GRID_NM, cmfs.wavelengths, cmfs.values[:, 1], left=0.0, right=0.0)
    emission = EMISSION / np.trapezoid(EMISSION, GRID_NM)
    reemitted = emission / GRID_NM * np.trapezoid(ENCLOSURE_EXCITATION * GRID_NM, GRID_NM)  # C(λo), Q = 1
    depth = 3
    elastic = sum(ALBEDO ** (k - 1) for k in range(1, depth + 1))
    inelastic = sum((k - 1) * ALBEDO ** (k - 2) for k in range(2, depth + 1))
    expected = EMITTED * (elastic + inelastic * np.trapezoid(reemitted * y_bar, GRID_NM) / np.trapezoid(y_bar, GRID_NM))
    mean, standard_error = _image_mean(Renderer(_dyed_enclosure(depth), device), 16, 16)
    assert_within_standard_errors(mean, expected, standard_error, power=0.02)
    assert expected > 1.1 * EMITTED * elastic  # the re-emission is a tenth of it or more
