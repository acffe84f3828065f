"""pbrt-v4's `subsurface` material imported as a dielectric boundary around a random-walk medium:

- each of pbrt's forms gives the interior the coefficients pbrt would use: the named media reproduce the published
  tables (Jensen et al. 2001: reduced σs' and σa; Narasimhan et al. 2006: σs and σa, in 1/mm; numbers typed from
  the papers' tables here), sigma_a/sigma_s and the defaults as given, and `reflectance` an albedo whose photon beam
  diffusion effective albedo, integrated here by adaptive quadrature from the published profile (Habel et al.
  2013, as pbrt-v4 tabulates it), is the reflectance asked for;
- a pbrt subsurface sphere renders the same bits as the same scene written in the scene format;
- an unknown name is refused in one line naming the file, the line and the key."""

import math
from pathlib import Path

import numpy as np
import pytest
from tests.cli_runner import run_spectrace

from spectrace.engine.renderer import Renderer
from spectrace.errors import SpectraceError
from spectrace.interop.pbrt import load_pbrt_scene, pbrt_scene_data
from spectrace.scene import load_scene
from spectrace.spectral.colorimetry import reflectance_to_xyz, xyz_to_linear_srgb
from spectrace.spectral.illuminants import d65_normalised

HEADER = """Scale -1 1 1
LookAt 0 0 5  0 0 0  0 1 0
Camera "perspective" "float fov" 30
Film "rgb" "integer xresolution" 12 "integer yresolution" 12
Sampler "independent" "integer pixelsamples" 4
Integrator "volpath" "integer maxdepth" 12
WorldBegin
LightSource "infinite" "rgb L" [1 1 1]
"""


def _write(tmp_path: Path, material: str) -> Path:
    path = tmp_path / "subsurface.pbrt"
    path.write_text(HEADER + material + '\nShape "sphere" "float radius" 1\n')
    return path


def _imported(tmp_path: Path, material: str) -> tuple[dict, dict]:
    data, _ = pbrt_scene_data(_write(tmp_path, material))
    shape = data["shapes"][0]
    return data["materials"][shape["material"]], shape["interior"]


def _srgb(spectrum) -> np.ndarray:
    """The linear sRGB of a coefficient spectrum (its values as a reflectance under D65, as the uplift made it)."""
    return xyz_to_linear_srgb(reflectance_to_xyz(spectrum.values, d65_normalised()))


# (pbrt name, scale, σs (reduced for Jensen et al.), σa), 1/mm, from the papers' tables.
PUBLISHED = [
    ("Marble", 2.0, (2.19, 2.62, 3.00), (0.0021, 0.0041, 0.0071)),  # Jensen et al. 2001
    ("Ketchup", 1.0, (0.18, 0.07, 0.03), (0.061, 0.97, 1.45)),
    ("Skin1", 3.0, (0.74, 0.88, 1.01), (0.032, 0.17, 0.48)),
    ("Espresso", 1.0, (0.72378, 0.84557, 1.0247), (4.7984, 6.5751, 8.8493)),  # Narasimhan et al. 2006
    ("Regular Milk", 0.5, (4.5513, 5.8294, 7.136), (0.0015333, 0.0046, 0.019933)),
    ("Head & Shoulders Shampoo", 1.0, (0.023805, 0.028804, 0.034306), (0.084621, 0.15688, 0.20365)),
]


@pytest.mark.parametrize(("name", "scale", "sigma_s", "sigma_a"), PUBLISHED)
def test_a_named_medium_has_the_published_coefficients(tmp_path, name, scale, sigma_s, sigma_a):
    path = _write(tmp_path, f'Material "subsurface" "string name" "{name}" "float scale" {scale} "float eta" 1.4')
    medium = load_pbrt_scene(path).shapes[0].interior
    assert medium.g == 0.0  # pbrt-v4 uses the named media isotropically
    assert _srgb(medium.sigma_s) == pytest.approx(np.array(sigma_s) * scale, rel=2e-3, abs=1e-6)
    assert _srgb(medium.sigma_a) == pytest.approx(np.array(sigma_a) * scale, rel=2e-3, abs=1e-6)


def test_the_boundary_is_a_dielectric_of_eta_rough_where_asked(tmp_path):
    material, _ = _imported(tmp_path, 'Material "subsurface" "string name" "Apple"')
    assert material == {"type": "dielectric", "ior": 1.33}  # pbrt-v4's default eta
    material, _ = _imported(tmp_path, 'Material "subsurface" "float eta" 1.5 "float roughness" 0.04')
    assert material == {"type": "dielectric", "ior": 1.5, "roughness": pytest.approx(0.2)}  # α = √roughness


def test_a_named_medium_ignores_g_with_a_warning(tmp_path):
    data, result = pbrt_scene_data(_write(tmp_path, 'Material "subsurface" "string name" "Cream" "float g" 0.5'))
    assert data["shapes"][0]["interior"] == {"preset": "cream"}
    assert any('"g" ignored' in warning for warning in result.warnings)


def test_coefficients_scale_and_g_are_taken_as_given(tmp_path):
    _, interior = _imported(
        tmp_path,
        'Material "subsurface" "rgb sigma_a" [0.1 0.2 0.3] "rgb sigma_s" [4 5 6] "float scale" 3 "float g" 0.3',
    )
    assert interior == {"sigma_a": {"rgb": [0.1, 0.2, 0.3]}, "sigma_s": {"rgb": [4, 5, 6]}, "scale": 3, "g": 0.3}
    medium = load_pbrt_scene(_write(tmp_path, 'Material "subsurface" "float g" -0.2')).shapes[0].interior
    # pbrt-v4's default medium: σa (.0011, .0024, .014), σs (2.55, 3.21, 3.77) per scene unit, with the given g.
    assert _srgb(medium.sigma_a) == pytest.approx([0.0011, 0.0024, 0.014], rel=2e-3)
    assert _srgb(medium.sigma_s) == pytest.approx([2.55, 3.21, 3.77], rel=2e-3)
    assert medium.g == -0.2


def _fresnel(cos_i: float, eta: float) -> float:
    sin2_t = (1.0 - cos_i * cos_i) / (eta * eta)
    if sin2_t >= 1.0:
        return 1.0
    cos_t = math.sqrt(1.0 - sin2_t)
    rp = (eta * cos_i - cos_t) / (eta * cos_i + cos_t)
    rs = (cos_i - eta * cos_t) / (cos_i + eta * cos_t)
    return 0.5 * (rp * rp + rs * rs)


def _effective_albedo(albedo: float, g: float, eta: float) -> float:
    """ρ_eff = ∫ 2πr (S_ss + S_ms) dr of the photon beam diffusion profile (σt = 1), each depth integral and the
    radial one by adaptive quadrature. The boundary's Fresnel moments are those of light inside meeting air."""
    from scipy.integrate import quad

    m1 = quad(lambda mu: _fresnel(mu, 1.0 / eta) * mu, 0.0, 1.0, limit=200)[0]
    m2 = quad(lambda mu: _fresnel(mu, 1.0 / eta) * mu * mu, 0.0, 1.0, limit=200)[0]
    sa, ss = 1.0 - albedo, albedo
    ssr = ss * (1 - g)
    str_ = sa + ssr
    d = (2 * sa + ssr) / (3 * str_ * str_)
    tr = math.sqrt(sa / d)
    ze = -2 * d * (1 + 3 * m2) / (1 - 2 * m1)

    def multiple(r: float) -> float:
        def at(z: float) -> float:
            zv = 2 * ze - z
            dr, dv = math.hypot(r, z), math.hypot(r, zv)
            phi = (math.exp(-tr * dr) / dr - math.exp(-tr * dv) / dv) / (4 * math.pi * d)
            e = (z * (1 + tr * dr) * math.exp(-tr * dr) / dr**3 - zv * (1 + tr * dv) * math.exp(-tr * dv) / dv**3) / (
                4 * math.pi
            )
            kappa = 1 - math.exp(-2 * str_ * (dr + z))
            exitance = 0.25 * (1 - 2 * m1) * phi + 0.5 * (1 - 3 * m2) * e
            return str_ * math.exp(-str_ * z) * kappa * (ssr / str_) ** 2 * exitance

        return quad(at, 0.0, math.inf, limit=200)[0]

    def single(r: float) -> float:
        t_crit = r * math.sqrt(eta * eta - 1)

        def at(s: float) -> float:
            t = t_crit + s
            dist = math.hypot(r, t)
            cos_o = t / dist
            phase = (1 - g * g) / (4 * math.pi * (1 + g * g + 2 * g * cos_o) ** 1.5)
            leaving = (1 - _fresnel(cos_o, 1 / eta)) * cos_o
            return math.exp(-s) * albedo * math.exp(-(dist + t_crit)) / dist**2 * phase * leaving

        return quad(at, 0.0, math.inf, limit=200)[0]

    total = 0.0
    for low, high in ((0.0, 0.01), (0.01, 1.0), (1.0, 20.0), (20.0, math.inf)):
        total += quad(lambda r: 2 * math.pi * r * (single(r) + multiple(r)), low, high, limit=100, epsrel=1e-6)[0]
    return total


def test_a_reflectance_gives_the_albedo_whose_diffusion_albedo_it_is(tmp_path):
    """pbrt-v4's SubsurfaceFromDiffuse: σt = 1/mfp, and the albedo whose effective albedo is the reflectance."""
    reflectance, mfp, g, eta = (0.2, 0.5, 0.8), (0.5, 1.0, 2.0), 0.2, 1.4
    _, interior = _imported(
        tmp_path,
        'Material "subsurface" "rgb reflectance" [{} {} {}] "rgb mfp" [{} {} {}] "float g" {} "float eta" {}'.format(
            *reflectance, *mfp, g, eta
        ),
    )
    assert interior["g"] == g
    sigma_a, sigma_s = np.array(interior["sigma_a"]["rgb"]), np.array(interior["sigma_s"]["rgb"])
    np.testing.assert_allclose(sigma_a + sigma_s, 1.0 / np.array(mfp), rtol=1e-12)
    albedo = sigma_s / (sigma_a + sigma_s)
    assert np.all(np.diff(albedo) > 0)
    for a, r in zip(albedo, reflectance, strict=True):
        assert _effective_albedo(float(a), g, eta) == pytest.approx(r, rel=2e-3)


def test_a_subsurface_sphere_renders_as_the_same_scene_written_in_toml(tmp_path, device):
    path = _write(tmp_path, 'Material "subsurface" "string name" "Skin1" "float scale" 4 "float eta" 1.4')
    toml = tmp_path / "twin.toml"
    toml.write_text(
        """[camera]
origin = [0.0, 0.0, 5.0]
target = [0.0, 0.0, 4.0]
up = [0.0, 1.0, 0.0]
fov = 30.0
fov_axis = "x"

[film]
width = 12
height = 12
filter = { type = "gaussian", stddev = 0.5, radius = 1.5 }

[integrator]
type = "path"
max_depth = 13

[sampler]
type = "independent"
spp = 4

[materials.skin]
type = "dielectric"
ior = 1.4

[[shapes]]
type = "sphere"
material = "skin"
interior = { preset = "skin1", scale = 4.0 }

[[lights]]
type = "constant"
radiance = { rgb = [1.0, 1.0, 1.0] }
"""
    )
    imported = Renderer(load_pbrt_scene(path), device).render().xyz
    written = Renderer(load_scene(toml), device).render().xyz
    assert np.mean(written[..., 1]) > 0.05
    np.testing.assert_array_equal(imported, written)


@pytest.mark.subprocess
def test_an_unknown_name_is_refused_in_one_line(tmp_path):
    path = _write(tmp_path, 'Material "subsurface"\n  "string name" "Marmite"')
    out = tmp_path / "out" / "scene.toml"
    result = run_spectrace("import-pbrt", str(path), "-o", str(out), timeout=120)
    assert result.returncode != 0
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1, result.stderr
    assert f"{path}:10" in lines[0] and '"string name"' in lines[0] and "Marmite" in lines[0]
    assert "Traceback" not in result.stderr and not out.exists()


def test_one_form_at_a_time(tmp_path):
    with pytest.raises(SpectraceError, match='"sigma_a" given without "sigma_s"'):
        pbrt_scene_data(_write(tmp_path, 'Material "subsurface" "rgb sigma_a" [1 1 1]'))


def test_a_named_medium_preset_of_either_table_imports(tmp_path):
    path = tmp_path / "medium.pbrt"
    path.write_text(
        HEADER
        + 'MakeNamedMedium "milk" "string type" "homogeneous" "string preset" "Lowfat Milk" "float scale" 2\n'
        + 'AttributeBegin\nMediumInterface "milk" ""\nMaterial "interface"\nShape "sphere" "float radius" 1\n'
        + "AttributeEnd\n"
    )
    medium = load_pbrt_scene(path).shapes[0].interior
    assert _srgb(medium.sigma_s) == pytest.approx(np.array([0.89187, 1.5136, 2.532]) * 2, rel=2e-3)
    assert _srgb(medium.sigma_a) == pytest.approx(np.array([0.002875, 0.00575, 0.0115]) * 2, rel=2e-3)


def test_a_reflectance_image_imports_as_its_mean_colour_with_a_warning(tmp_path):
    """pbrt-v4's head scene gives its skin's reflectance as an image: spectrace's medium is uniform, so the image's
    mean linear colour (sRGB decoded here by the standard's formula) is inverted instead."""
    from PIL import Image

    codes = np.array([[[200, 120, 90], [180, 100, 60]], [[220, 150, 120], [160, 90, 70]]], np.uint8)
    Image.fromarray(codes).save(tmp_path / "albedo.png")
    c = codes / 255.0
    linear = np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4).reshape(-1, 3).mean(axis=0)
    material = '"float mfp" 0.5 "float eta" 1.33'
    textured = 'Texture "albedo" "spectrum" "imagemap" "string filename" "albedo.png"\n'
    textured += f'Material "subsurface" "texture reflectance" "albedo" {material}'
    data, result = pbrt_scene_data(_write(tmp_path, textured))
    plain = 'Material "subsurface" "rgb reflectance" [{} {} {}] {}'.format(*linear, material)
    _, expected = _imported(tmp_path, plain)
    interior = data["shapes"][0]["interior"]
    for key in ("sigma_a", "sigma_s"):
        np.testing.assert_allclose(interior[key]["rgb"], expected[key]["rgb"], rtol=1e-3)
    assert any("mean colour" in warning for warning in result.warnings)
