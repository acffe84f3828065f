"""The thin principled material (Mitsuba 3's `principledthin`), run on the device through kernels/testing/bsdf.cl
over the whole sphere of directions: reciprocity (the sheet has the same medium on both sides), the same value
from both faces, sample weights equal to eval/pdf, a chi-square fit of the sampler to its pdf from either face,
energy conservation of its white specular sheet, and two closed forms: a white sheet of pure diffuse transmission
transmits everything as a Lambertian, and a nearly smooth specular sheet transmits b (1 − F(θ)) straight through,
F the dielectric Fresnel reflectance written out in numpy.

Random numbers come from fixed seeds; tolerances come from each estimator's standard error."""

import numpy as np
import pytest

from materials.test_bsdfs import Bsdf
from materials.test_principled import _binned_pdf_mass, _direction, _uniform_sphere
from scene_text import camera_film
from spectrace.errors import SpectraceError
from spectrace.materials.principledthin import PrincipledthinMaterial, make
from spectrace.scene.loader import load_scene
from spectrace.spectral.spectrum import Spectrum
from stats_toolkit import assert_chi_square_fits, assert_furnace, assert_reciprocal

HARNESS = "testing/bsdf.cl"


def _sheet(base: float = 0.8, **weights) -> PrincipledthinMaterial:
    return PrincipledthinMaterial(Spectrum.constant(base), **weights)


CASES = [
    ("specular-r0.4", _sheet(spec_trans=1.0, roughness=0.4)),
    ("mixed-r0.5", _sheet(spec_trans=0.5, roughness=0.5, diff_trans=0.8, sheen=0.6, sheen_tint=0.5)),
    ("anisotropic-r0.6", _sheet(spec_trans=0.7, roughness=0.6, anisotropic=0.8, spec_tint=0.6, eta=1.33)),
    ("diffuse-r0.3", _sheet(roughness=0.3, diff_trans=1.2)),
]
IDS = [c[0] for c in CASES]


@pytest.fixture(scope="module")
def bsdf(kernel_runner):
    runner = kernel_runner(HARNESS)
    return lambda material: Bsdf(runner, material)


def _passes_transmission_test(wo: np.ndarray, wi: np.ndarray) -> np.ndarray:
    """Mitsuba's test of a pair across the sheet, written out: with both turned so that ωo lies above,
    h = normalize(ωo + (ωi.x, ωi.y, |ωi.z|)) and ωi must lie behind it (ωi·h < 0)."""
    side = np.where(wo[:, 2] < 0, -1.0, 1.0)[:, None]
    o, i = wo * side, wi * side
    h = o + i * np.array([1.0, 1.0, -1.0])
    return (i[:, 2] < 0) & (np.einsum("ij,ij->i", i, h) < 0)


@pytest.mark.parametrize("name, material", CASES, ids=IDS)
def test_reciprocal_and_the_same_from_both_faces(bsdf, name, material):
    """f(ωo, ωi) = f(ωi, ωo) except across the sheet where the specular transmission's test (made of the light's
    side, as Mitsuba makes it) passes one way only; of the specular sheet's pairs across it exactly those that
    fail the test are dark. f(−ωo, −ωi) = f(ωo, ωi): the sheet has no front."""
    rng = np.random.default_rng(51)
    a, b = _uniform_sphere(rng, 40_000), _uniform_sphere(rng, 40_000)
    device = bsdf(material)
    forward, _ = device.eval_pdf(a, b)
    backward, _ = device.eval_pdf(b, a)
    flipped, _ = device.eval_pdf(-a, -b)
    crossing = a[:, 2] * b[:, 2] < 0
    assert np.count_nonzero(forward[crossing, 0] > 0) > 1000, "pairs across the sheet carry light"
    tested = _passes_transmission_test(a, b)
    symmetric = ~crossing | (tested == _passes_transmission_test(b, a))
    assert np.mean(symmetric) > 0.7
    lhs, rhs = forward / np.abs(b[:, 2:3]), backward / np.abs(a[:, 2:3])
    assert_reciprocal(lhs[symmetric], rhs[symmetric], rtol=2e-3, what=name)
    if material.diff_trans == 0.0 and material.spec_trans == 1.0:
        np.testing.assert_array_equal(forward[crossing, 0] > 0, tested[crossing])
    np.testing.assert_allclose(flipped, forward, rtol=1e-5, atol=1e-7)


@pytest.mark.parametrize("name, material", CASES, ids=IDS)
def test_sample_weight_is_eval_over_pdf(bsdf, name, material):
    rng = np.random.default_rng(53)
    wo = _uniform_sphere(rng, 20_000)
    device = bsdf(material)
    s = device.sample(wo, len(wo), seed=54)
    keep = s.ok
    assert keep.mean() > 0.8 and np.any(s.wi[keep, 2] * wo[keep, 2] < 0)
    f_cos, pdf = device.eval_pdf(wo[keep], s.wi[keep])
    np.testing.assert_allclose(s.pdf[keep], pdf, rtol=2e-3)
    np.testing.assert_allclose(s.weight[keep], f_cos / pdf[:, None], rtol=2e-3, atol=1e-7)


@pytest.mark.parametrize("name, material", CASES[:3], ids=IDS[:3])
def test_importance_samples_weigh_the_swapped_value(bsdf, name, material):
    """Drawn for importance (wo the light's side), a sample weighs f(ωi, ωo) |cos θi| / pdf, radiance's value with
    the directions swapped, which differs from f(ωo, ωi) where the transmission's test passes one way only."""
    rng = np.random.default_rng(61)
    wo = _uniform_sphere(rng, 20_000)
    device = bsdf(material)
    s = device.sample(wo, len(wo), seed=62, importance=True)
    keep = s.ok
    forward, pdf = device.eval_pdf(wo[keep], s.wi[keep])
    swapped, _ = device.eval_pdf(s.wi[keep], wo[keep])
    swapped *= (np.abs(s.wi[keep, 2]) / np.abs(wo[keep, 2]))[:, None]
    assert np.count_nonzero(~np.isclose(forward[:, 0], swapped[:, 0], rtol=1e-2)) > 20, "some pairs differ"
    np.testing.assert_allclose(s.pdf[keep], pdf, rtol=2e-3)
    np.testing.assert_allclose(s.weight[keep], swapped / pdf[:, None], rtol=2e-3, atol=1e-6)


CHI2_CASES = [(name, material, theta) for name, material in CASES for theta in (35.0, 130.0)]
CHI2_SAMPLES = 200_000
BINS_COS, BINS_PHI = 24, 48


@pytest.mark.parametrize("name, material, theta", CHI2_CASES, ids=[f"{c[0]}-{c[2]:g}" for c in CHI2_CASES])
def test_sampler_matches_its_pdf_chi_square(bsdf, name, material, theta):
    """From the front (35°) and the back (130°), over the whole sphere; the pdf's missing mass is the sampler's
    failure rate, its own bin."""
    device = bsdf(material)
    wo = _direction(theta)
    s = device.sample(wo, CHI2_SAMPLES, seed=int(theta) + 7)
    wi = s.wi[s.ok]
    cos_bin = np.clip(((wi[:, 2] + 1) / 2 * BINS_COS).astype(int), 0, BINS_COS - 1)
    phi = np.mod(np.arctan2(wi[:, 1], wi[:, 0]), 2 * np.pi)
    phi_bin = np.clip((phi / (2 * np.pi) * BINS_PHI).astype(int), 0, BINS_PHI - 1)
    observed = np.zeros((BINS_COS, BINS_PHI))
    np.add.at(observed, (cos_bin, phi_bin), 1)
    mass = _binned_pdf_mass(device, wo)
    assert mass.sum() <= 1.0 + 2e-3
    observed = np.append(observed.ravel(), np.count_nonzero(~s.ok))
    expected = np.append(mass.ravel(), max(1.0 - mass.sum(), 0.0)) * CHI2_SAMPLES
    assert_chi_square_fits(observed, expected, 0.01 / len(CHI2_CASES), what=(name, theta))


@pytest.mark.parametrize("roughness", (0.0, 0.3, 0.8))
def test_white_specular_sheet_conserves_energy(bsdf, roughness):
    """spec_trans 1 and a white base: the Fresnel reflection and the rest transmitted, single-scattering microfacet
    lobes, so ∫ f |cos θi| dωi ≤ 1 from either face (roughness 0 is the clamp α = 0.001, losing almost nothing)."""
    device = bsdf(_sheet(1.0, spec_trans=1.0, roughness=roughness))
    n = 40_000
    for theta in (0.0, 40.0, 75.0, 140.0):
        s = device.sample(_direction(theta), n, seed=int(theta) + 11)
        mean, _ = assert_furnace(np.where(s.ok[:, None], s.weight, 0.0), 1.0, slack=1e-5, what=theta, at_most=True)
        if roughness == 0.0 and theta < 80.0:
            assert mean[0] > 0.99, (theta, mean)


def test_white_diffuse_transmitter_is_lambertian(bsdf):
    """spec_trans 0, diff_trans 2 (all of the diffuse part transmitted), a white base: f = 1/π to the other side,
    nothing reflected, whatever the directions."""
    rng = np.random.default_rng(57)
    wo, wi = _uniform_sphere(rng, 10_000), _uniform_sphere(rng, 10_000)
    f_cos, _ = bsdf(_sheet(1.0, roughness=0.5, diff_trans=2.0)).eval_pdf(wo, wi)
    expected = np.where(wo[:, 2] * wi[:, 2] < 0, np.abs(wi[:, 2]) / np.pi, 0.0)
    np.testing.assert_allclose(f_cos, np.repeat(expected[:, None], 4, axis=1), rtol=1e-5, atol=1e-7)


def _fresnel(cos_i: float, eta: float) -> float:
    """The unpolarised dielectric reflectance of light arriving from the rarer side (Born & Wolf)."""
    sin_t = np.sqrt(1.0 - cos_i**2) / eta
    cos_t = np.sqrt(1.0 - sin_t**2)
    rs = (cos_i - eta * cos_t) / (cos_i + eta * cos_t)
    rp = (eta * cos_i - cos_t) / (eta * cos_i + cos_t)
    return 0.5 * (rs**2 + rp**2)


@pytest.mark.parametrize("theta, eta", [(0.0, 1.5), (50.0, 1.5), (70.0, 1.33)])
def test_smooth_specular_sheet_transmits_straight_through(bsdf, theta, eta):
    """A nearly smooth sheet (α = 0.001) of spec_trans 1 and base b: the transmitted samples leave along −ωo
    and carry b (1 − F(θ)) in all, the reflected ones F(θ)."""
    base = 0.6
    device = bsdf(_sheet(base, spec_trans=1.0, roughness=0.0, eta=eta))
    wo = _direction(theta)
    n = 20_000
    s = device.sample(wo, n, seed=59)
    through = s.ok & (s.wi[:, 2] < 0)
    assert np.mean(s.wi[through] @ -wo > 0.999) > 0.98  # GGX's tails aside
    f = _fresnel(np.cos(np.radians(theta)), eta)
    transmitted = np.where(through[:, None], s.weight, 0.0)
    reflected = np.where((s.ok & ~through)[:, None], s.weight, 0.0)
    assert_furnace(transmitted, base * (1.0 - f), slack=3e-3, what=("transmitted", theta))
    assert_furnace(reflected, f, slack=3e-3, what=("reflected", theta))


def test_scene_file_and_api_agree_and_refuse_out_of_range(tmp_path):
    path = tmp_path / "scene.toml"
    lines = "base_color = { value = 0.6 }\nspec_trans = 0.4\ndiff_trans = 1.5\neta = 1.33\nroughness = 0.2"
    path.write_text(
        camera_film()
        + f'\n[materials.m]\ntype = "principledthin"\n{lines}\n[[shapes]]\ntype = "sphere"\nmaterial = "m"\n'
    )
    material = load_scene(path).shapes[0].material
    assert material == make(0.6, spec_trans=0.4, diff_trans=1.5, eta=1.33, roughness=0.2)
    assert material.has_transmission and not material.is_dispersive
    path.write_text(path.read_text().replace("diff_trans = 1.5", "diff_trans = 2.5"))
    with pytest.raises(SpectraceError, match="diff_trans"):
        load_scene(path)
    with pytest.raises(SpectraceError, match="eta"):
        make(0.5, eta=0.9)


def test_mitsuba_principledthin_imports_its_weights_and_refuses_flatness(tmp_path):
    """Mitsuba's names map one to one (diff_trans in its own range, 0–2); a bitmap weight becomes a grey texture;
    diff_trans beyond 2 and a flatness other than 0 are errors naming the file and the key."""
    from PIL import Image

    from spectrace.interop.mitsuba import load_mitsuba_scene
    from spectrace.textures import is_texture

    Image.fromarray(np.array([[0, 255]], np.uint8)).save(tmp_path / "mask.png")
    body = """<bsdf type="principledthin"><rgb name="base_color" value="0.3, 0.6, 0.2"/>
        <texture type="bitmap" name="spec_trans"><string name="filename" value="mask.png"/></texture>
        <float name="roughness" value="0.4"/><float name="diff_trans" value="{diff_trans}"/>
        <float name="eta" value="1.33"/><float name="sheen" value="0.5"/>{extra}</bsdf>"""
    scene = """<scene version="3.0.0"><sensor type="perspective"><film type="hdrfilm"><integer name="width" value="4"/>
        <integer name="height" value="4"/></film></sensor><shape type="rectangle">{body}</shape>
        <emitter type="constant"/></scene>"""
    xml = tmp_path / "scene.xml"
    xml.write_text(scene.format(body=body.format(diff_trans=1.5, extra='<float name="flatness" value="0"/>')))
    material = load_mitsuba_scene(xml).shapes[0].material
    assert isinstance(material, PrincipledthinMaterial) and is_texture(material.spec_trans)
    assert (material.roughness, material.diff_trans, material.eta, material.sheen) == (0.4, 1.5, 1.33, 0.5)
    assert material.has_transmission
    for diff_trans, extra, key in ((2.5, "", "diff_trans"), (1.0, '<float name="flatness" value="0.5"/>', "flatness")):
        xml.write_text(scene.format(body=body.format(diff_trans=diff_trans, extra=extra)))
        with pytest.raises(SpectraceError) as error:
            load_mitsuba_scene(xml)
        assert key in str(error.value) and "scene.xml" in str(error.value)


@pytest.mark.peer
def test_exported_to_mitsuba_as_its_principledthin(tmp_path, mitsuba_scalar_spectral):
    """The Mitsuba export writes the material back as Mitsuba's principledthin with the same numbers, and Mitsuba
    loads the scene."""
    from materials.test_mitsuba_principled import _principled_scene
    from spectrace.interop.mitsuba import load_mitsuba_scene
    from spectrace.interop.mitsuba.export import scene_to_mitsuba_dict

    parameters = {"spec_trans": 0.5, "diff_trans": 0.6, "roughness": 0.6, "eta": 1.33, "sheen": 0.25}
    xml = tmp_path / "scene.xml"
    xml.write_text(_principled_scene(parameters, "principledthin"))
    exported = scene_to_mitsuba_dict(load_mitsuba_scene(xml), tmp_path / "export", spp=4)
    (entry,) = [v for v in exported.values() if isinstance(v, dict) and v.get("type") == "principledthin"]
    assert all(entry[k] == pytest.approx(v) for k, v in parameters.items())
    mitsuba_scalar_spectral.load_dict(exported)
