"""Fluorescent materials in the path and light tracers, against closed forms.

A Lambertian sphere in a uniform environment of radiance E(λ) sees only the environment (it is convex), so every
point of it sends the same radiance toward the camera. For the fluorescent model (spectrace.materials.fluorescent)
that radiance is, at each λo,

    L(λo) = ρ(λo) E(λo) + Q e(λo) / λo · ∫ a(λi) E(λi) λi dλi

(ρ the base's albedo, a the excitation, e the emission normalised to ∫ e dλ = 1, Q the yield). Its photon radiance
L λo / (h c) integrates to ρ's share plus Q times the absorbed photons, Q ∫ a E λ dλ / (h c): photons are counted,
and the emitted energy is smaller than the absorbed by the Stokes shift. The tests read the sphere's pixels in
spectral bands (band-averaged radiance), with standard errors from the spread of independent pixels (the independent
sampler; the light tracer's from independent replicas), and compare within 4 of them. The spectra are written here
(Gaussians and a box), not taken from the package's data. The renders here use two kernel programs (the general
kernels of each integrator, with spectral bands)."""

import numpy as np
import pytest

import spectrace as S
from spectrace.engine.renderer import Renderer
from spectrace.errors import SpectraceError
from spectrace.integrators import INTEGRATORS, scene_settings_problem
from spectrace.materials import fluorescent
from spectrace.scene.model import Scene
from spectrace.spectral.grid import GRID_NM
from spectrace.spectral.spectrum import Spectrum

SIDE = 16
BANDS = 47  # 10 nm bands over 360-830 nm
REGION = (slice(4, 12), slice(4, 12))  # 64 pixels, all on the sphere
SIGMAS = 4.0
Q = 0.8


def _gaussian(centre: float, width: float, peak: float = 1.0) -> np.ndarray:
    return peak * np.exp(-0.5 * ((GRID_NM - centre) / width) ** 2)


# A dye absorbing 0.8 of the photons at 420-470 nm (nothing elsewhere), emitting around 560 nm.
EXCITATION = np.where((GRID_NM >= 420) & (GRID_NM <= 470), 0.8, 0.0)
EMISSION = _gaussian(560.0, 25.0)
EMISSION_NORMALISED = EMISSION / np.trapezoid(EMISSION, GRID_NM)


def _dye(base, quantum_yield: float = Q):
    return S.fluorescent(base, Spectrum(EXCITATION), Spectrum(EMISSION), quantum_yield=quantum_yield)


def _scene(material, environment: np.ndarray, spp: int = 64, seed: int = 3, integrator: str = "path") -> Scene:
    return Scene(
        camera=S.Camera(origin=(0.0, 0.0, -4.0), target=(0.0, 0.0, 0.0), fov_degrees=30.0),
        width=SIDE,
        height=SIDE,
        shapes=[S.shape("sphere", material)],
        lights=[S.constant_environment(Spectrum(environment))],
        max_depth=2,
        spp=spp,
        seed=seed,
        sampler="independent",
        integrator=integrator,
    )


def _bands(device, scene: Scene, replicas: int = 1) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Band centres and edges (nm), and independent samples of the region's band radiance, (samples, bands): its
    pixels (a camera path's pixels are independent), or with `replicas` the region's mean over each of that many
    consecutive sample ranges of one render (a light path splats into any pixel, so only replicas are)."""
    renderer = Renderer(scene, device, spectral_bins=BANDS)
    if replicas == 1:
        renderer.render(spp=scene.spp)
        spectral = renderer.image().spectral
        assert spectral is not None
        return spectral.centres_nm, spectral.edges_nm, spectral.radiance[REGION].reshape(-1, BANDS).astype(np.float64)
    step = scene.spp // replicas
    sums = [np.zeros(BANDS)]
    for replica in range(1, replicas + 1):
        renderer.render(spp=replica * step, pass_spp=step)
        spectral = renderer.image().spectral
        assert spectral is not None
        sums.append(spectral.radiance[REGION].astype(np.float64).mean(axis=(0, 1)) * renderer.samples_done)
    return spectral.centres_nm, spectral.edges_nm, np.diff(np.stack(sums), axis=0) / step


def _closed_form_bands(edges: np.ndarray, radiance: np.ndarray) -> np.ndarray:
    """Band averages of a radiance given on the grid."""
    out = np.empty(len(edges) - 1)
    for i, (lo, hi) in enumerate(zip(edges[:-1], edges[1:])):
        inside = (lo <= GRID_NM) & (hi >= GRID_NM)
        out[i] = np.trapezoid(radiance[inside], GRID_NM[inside]) / (hi - lo)
    return out


def _fluorescent_radiance(environment: np.ndarray, quantum_yield: float = Q) -> np.ndarray:
    absorbed_photons = np.trapezoid(EXCITATION * environment * GRID_NM, GRID_NM)  # × 1/(h c)
    return quantum_yield * EMISSION_NORMALISED / GRID_NM * absorbed_photons


def _mean_and_error(pixels: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    return pixels.mean(axis=0), pixels.std(axis=0, ddof=1) / np.sqrt(len(pixels))


@pytest.mark.slow
@pytest.mark.parametrize("integrator", ["path", "light"])
def test_under_light_in_its_excitation_band_the_emission_follows_the_emission_spectrum(device, integrator):
    """Narrow-band blue light on a dye over a black base: the band radiance is the closed form's, the shape of the
    emission spectrum, and the emitted photons are Q times the absorbed ones while the energy drops by the Stokes
    shift."""
    light = _gaussian(445.0, 8.0)
    # samples, replicas (1: the pixels), and the largest relative standard error a bright group may have
    spp, replicas, precision = {"path": (512, 1, 0.15), "light": (2048, 16, 0.25)}[integrator]
    scene = _scene(_dye(S.diffuse(0.0)), light, spp=spp, integrator=integrator)
    centres, edges, pixels = _bands(device, scene, replicas)
    expected = _closed_form_bands(edges, _fluorescent_radiance(light))
    # 30 nm groups over the emission (each band alone gets too few samples for its spread to be its error) and the
    # rest of the range, where the closed form is below 1e-3 of the peak.
    groups = [(470, 500), (500, 530), (530, 560), (560, 590), (590, 620), (620, 680)]
    masks = [(centres > lo) & (centres < hi) for lo, hi in groups]
    masks.append(~np.any(masks, axis=0))
    grouped = np.stack([pixels[:, m].mean(axis=1) for m in masks], axis=1)
    grouped_expected = np.array([expected[m].mean() for m in masks])
    mean, error = _mean_and_error(grouped)
    assert np.all(np.abs(mean - grouped_expected) <= SIGMAS * error + 1e-3 * expected.max()), (
        mean,
        grouped_expected,
        error,
    )
    bright = grouped_expected > 0.1 * grouped_expected.max()
    assert bright.sum() >= 4 and np.all(error[bright] < precision * grouped_expected[bright])  # precise enough

    width = np.diff(edges)
    absorbed_photons = np.trapezoid(EXCITATION * light * GRID_NM, GRID_NM)
    emitted_photons = pixels @ (width * centres)  # per pixel, × 1/(h c)
    photons, photons_error = _mean_and_error(emitted_photons[:, None])
    assert abs(photons[0] - Q * absorbed_photons) <= SIGMAS * photons_error[0], (photons, Q * absorbed_photons)
    assert photons_error[0] < 0.05 * Q * absorbed_photons  # precise enough to tell a missing λi/λo

    absorbed_energy = np.trapezoid(EXCITATION * light, GRID_NM)
    energy, energy_error = _mean_and_error((pixels @ width)[:, None])
    stokes = Q * absorbed_photons * np.trapezoid(EMISSION_NORMALISED / GRID_NM, GRID_NM)
    assert stokes < 0.85 * Q * absorbed_energy  # 445 nm photons become ~560 nm ones
    assert abs(energy[0] - stokes) <= SIGMAS * energy_error[0], (energy, stokes)


@pytest.mark.parametrize("integrator", ["path", "light"])
def test_light_outside_the_excitation_band_is_not_re_emitted(device, integrator):
    light = _gaussian(620.0, 4.0)
    _, _, pixels = _bands(device, _scene(_dye(S.diffuse(0.0)), light, spp=16, integrator=integrator))
    assert np.all(pixels == 0.0)


@pytest.mark.parametrize("integrator", ["path", "light"])
def test_furnace_returns_no_more_energy_than_it_receives(device, integrator):
    """A white furnace (E = 1) on a dye over a base of albedo 1 − a: every photon the base does not reflect the
    dye absorbs. The band radiance is the closed form's, whose energy is below the environment's (the Stokes loss)."""
    light = np.ones_like(GRID_NM)
    base = S.diffuse(Spectrum(1.0 - EXCITATION))
    spp, replicas, precision = {"path": (64, 1, 0.01), "light": (512, 16, 0.03)}[integrator]
    _, edges, pixels = _bands(device, _scene(_dye(base, 1.0), light, spp=spp, integrator=integrator), replicas)
    expected = _closed_form_bands(edges, (1.0 - EXCITATION) * light + _fluorescent_radiance(light, 1.0))
    # 50 nm groups (the light tracer's single bands, at the ends of the range, are too skewed for their spread)
    groups = np.arange(BANDS) // 5
    grouped = np.stack([pixels[:, groups == g].mean(axis=1) for g in range(groups.max() + 1)], axis=1)
    grouped_expected = np.array([expected[groups == g].mean() for g in range(groups.max() + 1)])
    mean, error = _mean_and_error(grouped)
    assert np.all(np.abs(mean - grouped_expected) <= SIGMAS * error + 1e-4), (mean - grouped_expected) / error
    width = np.diff(edges)
    received = np.trapezoid(light, GRID_NM)
    energy, energy_error = _mean_and_error((pixels @ width)[:, None])
    assert energy[0] - SIGMAS * energy_error[0] <= received
    assert abs(energy[0] - expected @ width) <= SIGMAS * energy_error[0]
    assert expected @ width < received - 5.0  # the closed form's Stokes loss
    assert energy_error[0] < precision * received


def test_yield_zero_renders_its_base_bit_for_bit(device):
    light = 0.5 + 0.5 * _gaussian(500.0, 60.0)
    base = S.diffuse(Spectrum(0.2 + 0.6 * _gaussian(600.0, 50.0)))
    _, _, plain = _bands(device, _scene(base, light, spp=8))
    _, _, dyed = _bands(device, _scene(_dye(base, 0.0), light, spp=8))
    np.testing.assert_array_equal(dyed, plain)


def test_a_texture_of_the_yield_holding_one_number_renders_that_number_bit_for_bit(device):
    light = np.ones_like(GRID_NM)
    base = S.diffuse(0.3)
    _, _, number = _bands(device, _scene(_dye(base, Q), light, spp=8))
    _, _, textured = _bands(device, _scene(_dye(base, S.checkerboard(Q, Q)), light, spp=8))
    _, _, other = _bands(device, _scene(_dye(base, S.checkerboard(Q, 0.5 * Q)), light, spp=8))
    np.testing.assert_array_equal(textured, number)
    assert not np.array_equal(other, number)  # the texture is read


@pytest.mark.parametrize("integrator", ["path", "light"])
def test_a_render_split_into_passes_has_the_same_bits(device, integrator):
    scene = _scene(_dye(S.diffuse(0.3)), np.ones_like(GRID_NM), spp=8, integrator=integrator)
    whole = Renderer(scene, device, spectral_bins=BANDS)
    whole.render(spp=8)
    split = Renderer(scene, device, spectral_bins=BANDS)
    split.render(spp=8, pass_spp=3)
    np.testing.assert_array_equal(whole.image().xyz, split.image().xyz)
    np.testing.assert_array_equal(whole.image().spectral.radiance, split.image().spectral.radiance)


@pytest.mark.parametrize("integrator", [name for name in INTEGRATORS if name not in fluorescent.INTEGRATORS])
def test_the_integrators_that_keep_each_wavelength_refuse_it_in_one_line(integrator):
    scene = _scene(S.mix([S.diffuse(0.5), _dye(S.diffuse(0.2))]), np.ones_like(GRID_NM)).with_overrides(
        integrator=integrator
    )
    problem = scene_settings_problem(scene)
    assert problem is not None and f"integrator '{integrator}'" in problem and "\n" not in problem
    assert scene_settings_problem(scene.with_overrides(integrator="path")) is None


@pytest.mark.parametrize(
    "base, excitation, emission, quantum_yield, key",
    [
        (lambda: _dye(S.diffuse(0.2)), EXCITATION, EMISSION, Q, "base"),
        (lambda: S.diffuse(0.2), EXCITATION * 2.0, EMISSION, Q, "excitation"),
        (lambda: S.diffuse(0.2), EXCITATION, 0.0 * EMISSION, Q, "emission"),
        (lambda: S.diffuse(0.2), EXCITATION, EMISSION, 1.5, "quantum_yield"),
    ],
)
def test_the_api_refuses_bad_values_naming_the_key(base, excitation, emission, quantum_yield, key):
    with pytest.raises(SpectraceError, match=key):
        S.fluorescent(base(), Spectrum(excitation), Spectrum(emission), quantum_yield=quantum_yield)
