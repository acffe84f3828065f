"""The thin dielectric sheet (kernels/bsdf_thindielectric.cl) against optics computed here: the Fresnel
reflectance of one face from Fresnel's equations in their angle form (Hecht, "Optics", sec. 4.6), summed over the
light bouncing between the two faces, R' = R + T²R/(1 − R²); directions by the law of reflection and straight
through; a lossless sheet reflects and transmits everything (R' + T' = 1), so a sphere of it in a uniform sky
renders as the sky itself. The comparison with Mitsuba 3 is in test_mitsuba_materials.py."""

import numpy as np
import pytest

import spectrace
from materials.test_bsdfs import Bsdf
from spectrace.engine.renderer import Renderer
from spectrace.materials import material_row
from spectrace.scene.model import ThindielectricMaterial
from spectrace.spectral.spectrum import Spectrum
from spectrace.spectral.table import SpectrumTable
from stats_toolkit import assert_furnace, assert_within_standard_errors

HARNESS = "testing/bsdf.cl"
THETAS_DEG = (0.0, 20.0, 45.0, 60.0, 75.0, 85.0, 89.0)


@pytest.fixture(scope="module")
def sheet(kernel_runner):
    runner = kernel_runner(HARNESS)
    return lambda material: Bsdf(runner, material)


def _fresnel_one_face(theta_i: float, eta: float) -> float:
    """Unpolarised reflectance of one face from Fresnel's equations in the angle form (Hecht): r_s = −sin(θi − θt)
    / sin(θi + θt), r_p = tan(θi − θt) / tan(θi + θt), with Snell's sin θt = sin θi / η."""
    if theta_i == 0.0:
        return ((eta - 1.0) / (eta + 1.0)) ** 2
    theta_t = np.arcsin(np.sin(theta_i) / eta)
    r_s = np.sin(theta_i - theta_t) / np.sin(theta_i + theta_t)
    r_p = np.tan(theta_i - theta_t) / np.tan(theta_i + theta_t)
    return 0.5 * (r_s**2 + r_p**2)


def _sheet_reflectance(theta_i: float, eta: float) -> float:
    """The light reflected by the first face, plus what enters, bounces an odd number of times between the faces and
    leaves on the side it came from: R + T R T + T R³ T + ... = R + T² R / (1 − R²)."""
    r = _fresnel_one_face(theta_i, eta)
    t = 1.0 - r
    return r + t * t * r / (1.0 - r * r)


def _wo(theta_deg: float, side: float = 1.0) -> np.ndarray:
    t = np.radians(theta_deg)
    return np.array([np.sin(t) * np.cos(0.4), np.sin(t) * np.sin(0.4), side * np.cos(t)])


@pytest.mark.parametrize("eta", [1.33, 1.5, 2.4])
def test_reflectance_is_the_sum_over_both_faces(sheet, eta):
    """The probability the sampler reports for the reflected lobe is R'(θ), from either side."""
    device = sheet(ThindielectricMaterial(eta))
    for side in (1.0, -1.0):
        for theta in THETAS_DEG:
            s = device.sample(_wo(theta, side), 64, seed=1)
            reflected = s.wi[:, 2] * side > 0
            assert np.any(reflected) and np.all(s.ok) and np.all(s.is_delta)
            expected = _sheet_reflectance(np.radians(theta), eta)
            np.testing.assert_allclose(s.pdf[reflected], expected, rtol=2e-5, atol=1e-7, err_msg=f"{theta} {side}")
            np.testing.assert_allclose(s.pdf[~reflected], 1.0 - expected, rtol=2e-5, atol=1e-7)


def test_directions_are_mirror_reflection_and_straight_through(sheet):
    rng = np.random.default_rng(2)
    z = rng.uniform(-1.0, 1.0, 4000)
    phi = rng.uniform(0.0, 2.0 * np.pi, 4000)
    r = np.sqrt(1.0 - z * z)
    wo = np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=1)
    s = sheet(ThindielectricMaterial(1.5)).sample(wo, len(wo), seed=3)
    reflected = s.wi[:, 2] * wo[:, 2] > 0
    assert 0 < reflected.sum() < len(wo)
    np.testing.assert_allclose(s.wi[reflected], wo[reflected] * np.array([-1.0, -1.0, 1.0]), atol=2e-6)
    np.testing.assert_allclose(s.wi[~reflected], -wo[~reflected], atol=2e-6)


@pytest.mark.parametrize("theta", THETAS_DEG)
def test_lossless_sheet_conserves_energy_and_reflects_r_prime(sheet, theta):
    """Every sample of a clear sheet weighs exactly 1 (R' + T' = 1: nothing is absorbed), and the fraction reflected
    is R' within 4 standard errors."""
    n = 40_000
    s = sheet(ThindielectricMaterial(1.5)).sample(_wo(theta), n, seed=int(theta) + 4)
    assert np.all(s.ok)
    assert_furnace(s.weight, 1.0, slack=1e-6, what=theta)
    assert np.all(s.weight == 1.0)
    reflected = np.mean(s.wi[:, 2] > 0)
    expected = _sheet_reflectance(np.radians(theta), 1.5)
    assert_within_standard_errors(reflected, expected, np.sqrt(expected * (1 - expected) / n) + 1 / n, what=theta)


def test_tints_multiply_each_lobe(sheet):
    red, blue = Spectrum.constant(0.3), Spectrum.constant(0.7)
    s = sheet(ThindielectricMaterial(1.5, specular_reflectance=red, specular_transmittance=blue)).sample(
        _wo(50.0), 2000, seed=5
    )
    reflected = s.wi[:, 2] > 0
    np.testing.assert_allclose(s.weight[reflected], 0.3, rtol=1e-6)
    np.testing.assert_allclose(s.weight[~reflected], 0.7, rtol=1e-6)


def test_delta_lobes_have_no_density(sheet):
    rng = np.random.default_rng(6)
    f_cos, pdf = sheet(ThindielectricMaterial(1.5)).eval_pdf(rng.normal(size=(500, 3)), rng.normal(size=(500, 3)))
    assert np.all(f_cos == 0) and np.all(pdf == 0)
    assert not sheet(ThindielectricMaterial(1.5)).has_non_delta_lobe()


def test_material_row():
    table = SpectrumTable()
    row = material_row(ThindielectricMaterial(1.7, specular_transmittance=Spectrum.constant(0.5)), table)
    assert row["ior"] == np.float32(1.7)
    assert table.data[row["transmittance_offset"]] == np.float32(0.5)


def test_clear_sheet_in_a_uniform_sky_renders_as_the_sky(device):
    """Reflection and transmission keep every path's weight at 1, so a sphere of thin glass (seen through itself,
    front and back faces) in a uniform sky is the sky: each pixel equals, to float precision, the same render
    without the sphere (the same wavelengths, drawn first, times the same radiance; Russian roulette kept off)."""
    sky = spectrace.Scene(
        camera=spectrace.Camera(origin=(0.0, 0.0, 3.0), target=(0.0, 0.0, 0.0)),
        shapes=[],
        lights=[spectrace.constant_environment(1.0)],
        width=12,
        height=12,
        spp=8,
        max_depth=16,
        rr_depth=16,
    )
    glass = sky.with_overrides(shapes=[spectrace.shape("sphere", spectrace.thindielectric(1.5))])
    expected = Renderer(sky, device).render().xyz
    image = Renderer(glass, device).render().xyz
    np.testing.assert_allclose(image, expected, rtol=1e-5)
    tinted = sky.with_overrides(
        shapes=[spectrace.shape("sphere", spectrace.thindielectric(1.5, specular_transmittance=0.5))]
    )
    assert Renderer(tinted, device).render().xyz[6, 6, 1] < 0.9 * expected[6, 6, 1]  # the check can fail
