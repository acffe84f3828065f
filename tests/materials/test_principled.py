"""The principled material's transmitting lobes and its reductions, run on the device through kernels/testing/bsdf.cl
over the whole sphere of directions: generalised reciprocity f(ωo, ωi)/n(ωo)² = f(ωi, ωo)/n(ωi)², sample weights
equal to eval/pdf, a chi-square fit of the sampler to its pdf from outside and from inside, energy conservation of
its glass from both sides, and its reductions to the dielectric (white glass) and to a Schlick metal, evaluated
independently. The reflecting cases join every BSDF's checks in test_bsdfs.py.

Random numbers come from fixed seeds; tolerances come from each estimator's standard error."""

import numpy as np
import pytest

from materials.test_bsdfs import Bsdf
from scene_text import camera_film
from spectrace.errors import SpectraceError
from spectrace.materials.dielectric import DielectricMaterial
from spectrace.materials.principled import PrincipledMaterial, eta_from_specular, make
from spectrace.scene.loader import load_scene
from spectrace.spectral.glasses import index_of_refraction
from spectrace.spectral.spectrum import Spectrum
from spectrace.textures import is_texture
from stats_toolkit import assert_chi_square_fits, assert_furnace, assert_reciprocal

HARNESS = "testing/bsdf.cl"
ETA = 1.5


def _glass(roughness: float, base: float = 1.0, **weights) -> PrincipledMaterial:
    return PrincipledMaterial(
        Spectrum.constant(base), index_of_refraction(ETA), roughness=roughness, spec_trans=1.0, **weights
    )


TRANSMITTING = [
    ("glass-r0.55", _glass(0.55)),
    ("glass-r0.7-tinted", _glass(0.7, base=0.6)),
    ("half-glass-r0.5", _glass(0.5, metallic=0.3, clearcoat=1.0, sheen=0.5, base=0.8)),
    ("glass-anisotropic", _glass(0.6, anisotropic=0.7)),
]
# Every lobe partly: specular transmission half of the dielectric part, the rest Burley's base.
MIXED = (
    "mixed-r0.5",
    PrincipledMaterial(Spectrum.constant(0.7), index_of_refraction(ETA), roughness=0.5, spec_trans=0.5),
)


@pytest.fixture(scope="module")
def bsdf(kernel_runner):
    runner = kernel_runner(HARNESS)
    return lambda material: Bsdf(runner, material)


def _uniform_sphere(rng, n):
    z = rng.uniform(-1.0, 1.0, n)
    phi = rng.uniform(0.0, 2.0 * np.pi, n)
    r = np.sqrt(1.0 - z * z)
    return np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=1)


def _index(z):
    return np.where(z > 0, 1.0, ETA)


def _direction(theta_deg, phi=0.4):
    t = np.radians(theta_deg)
    return np.array([np.sin(t) * np.cos(phi), np.sin(t) * np.sin(phi), np.cos(t)])


@pytest.mark.parametrize("name, material", [*TRANSMITTING, MIXED], ids=[c[0] for c in [*TRANSMITTING, MIXED]])
def test_generalised_reciprocity(bsdf, name, material):
    rng = np.random.default_rng(31)
    a, b = _uniform_sphere(rng, 40_000), _uniform_sphere(rng, 40_000)
    device = bsdf(material)
    forward, _ = device.eval_pdf(a, b)
    backward, _ = device.eval_pdf(b, a)
    lhs = forward / np.abs(b[:, 2:3]) / _index(a[:, 2])[:, None] ** 2
    rhs = backward / np.abs(a[:, 2:3]) / _index(b[:, 2])[:, None] ** 2
    crossing = a[:, 2] * b[:, 2] < 0
    assert np.count_nonzero(lhs[crossing, 0] > 0) > 1000, "refracting pairs carry light"
    assert_reciprocal(lhs, rhs, rtol=2e-3, what=name)


@pytest.mark.parametrize("name, material", [*TRANSMITTING, MIXED], ids=[c[0] for c in [*TRANSMITTING, MIXED]])
def test_sample_weight_is_eval_over_pdf(bsdf, name, material):
    rng = np.random.default_rng(37)
    wo = _uniform_sphere(rng, 20_000)
    device = bsdf(material)
    s = device.sample(wo, len(wo), seed=38)
    keep = s.ok
    assert keep.mean() > 0.8 and np.any(s.wi[keep, 2] * wo[keep, 2] < 0)
    f_cos, pdf = device.eval_pdf(wo[keep], s.wi[keep])
    np.testing.assert_allclose(s.pdf[keep], pdf, rtol=2e-3)
    np.testing.assert_allclose(s.weight[keep], f_cos / pdf[:, None], rtol=2e-3, atol=1e-7)


CHI2_CASES = [(name, material, theta) for name, material in (*TRANSMITTING, MIXED) for theta in (35.0, 130.0)]
CHI2_SAMPLES = 200_000
BINS_COS, BINS_PHI, SUB = 24, 48, 12


def _binned_pdf_mass(device, wo):
    """∫ pdf dω over each (cos θ, φ) bin by the midpoint rule on sub-cells split evenly in θ, each weighted by its
    exact solid angle."""
    cos_edges = np.linspace(-1.0, 1.0, BINS_COS + 1)
    theta_edges = np.concatenate(
        [np.linspace(a, b, SUB + 1)[:-1] for a, b in zip(np.arccos(cos_edges[:-1]), np.arccos(cos_edges[1:]))] + [[0.0]]
    )
    theta_mid = 0.5 * (theta_edges[:-1] + theta_edges[1:])
    cell_cos = np.abs(np.cos(theta_edges[1:]) - np.cos(theta_edges[:-1]))
    nphi = BINS_PHI * SUB
    phi = (np.arange(nphi) + 0.5) * (2 * np.pi / nphi)
    tt, pp = np.meshgrid(theta_mid, phi, indexing="ij")
    wi = np.stack([np.sin(tt) * np.cos(pp), np.sin(tt) * np.sin(pp), np.cos(tt)], axis=-1).reshape(-1, 3)
    _, pdf = device.eval_pdf(wo, wi)
    fine = pdf.reshape(len(theta_mid), nphi) * cell_cos[:, None] * (2 * np.pi / nphi)
    return fine.reshape(BINS_COS, SUB, BINS_PHI, SUB).sum(axis=(1, 3))


@pytest.mark.parametrize("name, material, theta", CHI2_CASES, ids=[f"{c[0]}-{c[2]:g}" for c in CHI2_CASES])
def test_sampler_matches_its_pdf_chi_square(bsdf, name, material, theta):
    """From outside (35°) and from inside the glass (130°), over the whole sphere; the pdf's missing mass is the
    sampler's failure rate, its own bin."""
    device = bsdf(material)
    wo = _direction(theta)
    s = device.sample(wo, CHI2_SAMPLES, seed=int(theta))
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
def test_white_glass_conserves_energy_from_both_sides(bsdf, roughness):
    """∫ (f_r + f_t (n_i/n_o)²) |cos θi| dωi ≤ 1 from outside and inside: the flux of a sample undoes the radiance's
    (n_o/n_i)²; roughness 0 is Mitsuba's clamp α = 0.001, nearly smooth, which loses almost nothing."""
    device = bsdf(_glass(roughness))
    n = 40_000
    for theta in (0.0, 40.0, 75.0, 140.0, 175.0):
        wo = np.repeat(_direction(theta)[None, :], n, axis=0)
        s = device.sample(wo, n, seed=int(theta) + 3)
        flux = np.where(s.ok[:, None], s.weight, 0.0) * (_index(s.wi[:, 2]) / _index(wo[:, 2]))[:, None] ** 2
        mean, _ = assert_furnace(flux, 1.0, slack=1e-5, what=(roughness, theta), at_most=True)
        if roughness == 0.0:
            assert mean[0] > 0.995, (theta, mean)


@pytest.mark.parametrize("roughness", (0.3, 0.6, 0.9))
def test_white_glass_is_the_rough_dielectric(bsdf, roughness):
    """spec_trans = 1, metallic = 0 and a white base leave the dielectric's two lobes: the same f on pairs over the
    whole sphere as the `dielectric` of α = roughness², another kernel."""
    rng = np.random.default_rng(41)
    wo, wi = _uniform_sphere(rng, 20_000), _uniform_sphere(rng, 20_000)
    principled, _ = bsdf(_glass(roughness)).eval_pdf(wo, wi)
    dielectric, _ = bsdf(DielectricMaterial(index_of_refraction(ETA), roughness=roughness**2)).eval_pdf(wo, wi)
    assert np.count_nonzero(dielectric[:, 0] > 0) > 5000
    np.testing.assert_allclose(principled, dielectric, rtol=2e-3, atol=1e-6)


def test_metal_is_schlicks_fresnel_on_ggx(bsdf):
    """metallic = 1: f = F_Schlick(b, ωo·h) D G2 / (4 cos θo cos θi), with D and the height-correlated G2 of GGX
    written out here in numpy."""
    base, roughness = 0.7, 0.5
    alpha = roughness**2
    rng = np.random.default_rng(43)
    wo = rng.normal(size=(5000, 3))
    wi = rng.normal(size=(5000, 3))
    wo[:, 2], wi[:, 2] = np.abs(wo[:, 2]), np.abs(wi[:, 2])
    wo /= np.linalg.norm(wo, axis=1, keepdims=True)
    wi /= np.linalg.norm(wi, axis=1, keepdims=True)
    f_cos, _ = bsdf(make(base_color=base, metallic=1.0, roughness=roughness)).eval_pdf(wo, wi)
    h = wo + wi
    h /= np.linalg.norm(h, axis=1, keepdims=True)
    d = alpha**2 / (np.pi * (h[:, 2] ** 2 * (alpha**2 - 1) + 1) ** 2)

    def lam(w):
        return 0.5 * (np.sqrt(1 + alpha**2 * (1 - w[:, 2] ** 2) / w[:, 2] ** 2) - 1)

    g2 = 1 / (1 + lam(wo) + lam(wi))
    fresnel = base + (1 - base) * (1 - np.sum(wo * h, axis=1)) ** 5
    expected = fresnel * d * g2 / (4 * wo[:, 2])
    np.testing.assert_allclose(f_cos[:, 0], expected, rtol=2e-3, atol=1e-7)


def test_specular_is_the_index_as_a_reflectance_level():
    """Burley's specular level: F0 = 0.08 specular, so 0.5 is the index 1.5, and eta and specular are one key."""
    for specular in (0.1, 0.5, 0.9):
        eta = eta_from_specular(specular)
        np.testing.assert_allclose(((eta - 1) / (eta + 1)) ** 2, 0.08 * specular, rtol=1e-12)
    assert make(specular=0.5).eta.at(550.0) == pytest.approx(1.5)


def _scene_file(tmp_path, lines: str):
    path = tmp_path / "scene.toml"
    path.write_text(
        camera_film(width="4", height="4")
        + f'\n[materials.m]\ntype = "principled"\n{lines}\n[[shapes]]\ntype = "sphere"\nmaterial = "m"\n',
        encoding="utf-8",
    )
    return path


def test_scene_file_takes_eta_or_specular_and_textured_weights(tmp_path):
    """eta by a glass name disperses; specular is the index another way; a weight takes a texture; eta and specular
    together are one error naming the key."""
    glass = load_scene(_scene_file(tmp_path, 'eta = "SF11"\nspec_trans = 1.0')).shapes[0].material
    assert glass.is_dispersive and glass.has_transmission
    assert load_scene(_scene_file(tmp_path, "specular = 0.5")).shapes[0].material.eta.at(550.0) == pytest.approx(1.5)
    textured = load_scene(_scene_file(tmp_path, 'metallic = { texture = "checkerboard" }')).shapes[0].material
    assert is_texture(textured.metallic)
    path = _scene_file(tmp_path, "eta = 1.4\nspecular = 0.5")
    with pytest.raises(SpectraceError) as error:
        load_scene(path)
    assert error.value.where == f"{path}: materials.m.eta" and "not both" in str(error.value)


FLAT = '<float name="flatness" value="0.3"/></bsdf>'


def test_mitsuba_principled_imports_its_weights_and_their_textures(tmp_path):
    """Mitsuba's names map one to one; a bitmap weight becomes a grey texture; an out-of-range weight and a
    flatness other than 0 (the fake subsurface, not modelled) are errors naming the file."""
    from PIL import Image

    from spectrace.interop.mitsuba import load_mitsuba_scene

    Image.fromarray(np.array([[0, 255]], np.uint8)).save(tmp_path / "metal.png")
    body = """<bsdf type="principled"><rgb name="base_color" value="0.8, 0.2, 0.1"/>
        <texture type="bitmap" name="metallic"><string name="filename" value="metal.png"/></texture>
        <float name="roughness" value="0.3"/><float name="spec_trans" value="0.25"/><float name="eta" value="1.33"/>
        <float name="clearcoat" value="0.5"/><float name="sheen" value="{sheen}"/></bsdf>"""
    scene = """<scene version="3.0.0"><sensor type="perspective"><film type="hdrfilm"><integer name="width" value="4"/>
        <integer name="height" value="4"/></film></sensor><shape type="sphere">{body}</shape>
        <emitter type="constant"/></scene>"""
    xml = tmp_path / "scene.xml"
    xml.write_text(scene.format(body=body.format(sheen=0.75)))
    material = load_mitsuba_scene(xml).shapes[0].material
    assert isinstance(material, PrincipledMaterial) and is_texture(material.metallic)
    assert (material.roughness, material.spec_trans, material.clearcoat, material.sheen) == (0.3, 0.25, 0.5, 0.75)
    assert material.eta.at(550.0) == pytest.approx(1.33)
    for bad, key in ((body.format(sheen=1.5), "sheen"), (body.format(sheen=0.5).replace("</bsdf>", FLAT), "flatness")):
        xml.write_text(scene.format(body=bad))
        with pytest.raises(SpectraceError) as error:
            load_mitsuba_scene(xml)
        assert key in str(error.value) and "scene.xml" in str(error.value)


def test_kernel_index_from_a_textured_specular_level_is_the_hosts(kernel_runner):
    """A textured specular level becomes the index per hit in the kernel by the formula the host applies to an
    untextured one: both give the index whose Schlick F0 is 0.08 specular."""
    runner = kernel_runner("testing/principled_specular.cl")
    levels = np.array([1e-3, 0.1, 0.25, 0.5, 0.75, 0.9, 1.0], np.float32)
    out = np.zeros_like(levels)
    runner.run("eta_from_specular", levels.size, [runner.buffer(levels), runner.buffer(out, True)], {1: out})
    np.testing.assert_allclose(out, [eta_from_specular(float(s)) for s in levels], rtol=2e-6)
    np.testing.assert_allclose(((out - 1) / (out + 1)) ** 2, 0.08 * levels, rtol=1e-4)


def test_a_textured_specular_level_is_one_of_the_materials_textures():
    """A mesh without texture coordinates is refused for a textured material: the specular level's texture counts
    (materials.material_textures), a number does not."""
    import spectrace
    from spectrace.materials import material_textures

    textured = make(specular=spectrace.bitmap(np.full((2, 2), 0.5)))
    assert set(material_textures(textured)) == {"specular"}
    assert material_textures(make(specular=0.5)) == {}


def test_a_direction_texture_is_one_of_the_materials_textures_and_must_be_raw_rgb():
    """anisotropic_direction counts among the material's textures (a mesh without texture coordinates is refused
    for it); it takes a 3-channel bitmap of data: a grey one, or one read as sRGB colours, is refused in one line."""
    import spectrace
    from spectrace.errors import SpectraceError
    from spectrace.materials import material_textures

    direction = spectrace.bitmap(np.full((2, 2, 3), 0.5))
    assert set(material_textures(make(anisotropic=0.5, anisotropic_direction=direction))) == {"anisotropic_direction"}
    with pytest.raises(SpectraceError, match="3-channel"):
        make(anisotropic=0.5, anisotropic_direction=spectrace.bitmap(np.full((2, 2), 0.5)))
    with pytest.raises(SpectraceError, match="raw = true"):
        make(anisotropic=0.5, anisotropic_direction=spectrace.bitmap(np.full((2, 2, 3), 128, np.uint8), srgb=True))
