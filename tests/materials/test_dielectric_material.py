"""The dielectric material end to end: scene keys (every ior form, errors with key paths), the API helper, the
Material row the kernels read, and renders that check physics: a lossless glass sphere in a uniform environment
(a white furnace) renders as the environment, also when the glass is dispersive, which tests that terminating the
secondary wavelengths at a dispersive event is unbiased."""

import numpy as np
import pytest

import spectrace
from scene_text import camera_film
from spectrace.core.contract import IOR_CAUCHY, IOR_CONSTANT, IOR_SELLMEIER
from spectrace.engine.renderer import Renderer
from spectrace.errors import SpectraceError
from spectrace.materials import MATERIAL_CODES, material_row
from spectrace.scene import load_scene
from spectrace.scene.model import Camera, ConstantEnvironment, Scene
from spectrace.spectral.glasses import glass
from spectrace.spectral.spectrum import Spectrum
from spectrace.spectral.table import SpectrumTable
from stats_toolkit import assert_furnace

SCENE = (
    camera_film(origin="[0, 0, -4]", fov="30", width="4", height="4")
    + """[materials.glass]
type = "dielectric"
{material}
[[shapes]]
type = "sphere"
material = "glass"
[[lights]]
type = "constant"
radiance = {{ value = 1 }}
"""
)


def _load(tmp_path, material_lines: str):
    path = tmp_path / "scene.toml"
    path.write_text(SCENE.format(material=material_lines), encoding="utf-8")
    return load_scene(path)


@pytest.mark.parametrize(
    "lines, model, n_at_d",
    [
        ("", IOR_CONSTANT, 1.5),
        ("ior = 1.33", IOR_CONSTANT, 1.33),
        ('ior = "BK7"', IOR_SELLMEIER, 1.5168),
        ('ior = "SF11"\nroughness = 0.2', IOR_SELLMEIER, 1.78472),
        (
            "ior = { sellmeier = [1.03961212, 0.231792344, 1.01046945, 0.00600069867, 0.0200179144, 103.560653] }",
            IOR_SELLMEIER,
            1.5168,
        ),
        ("ior = { cauchy = [1.5046, 0.00420] }", IOR_CAUCHY, 1.5046 + 0.00420 / 0.5875618**2),
    ],
)
def test_ior_forms_load_into_material_rows(tmp_path, lines, model, n_at_d):
    material = _load(tmp_path, lines).shapes[0].material
    assert material.ior.at(587.5618) == pytest.approx(n_at_d, abs=5e-5)
    row = material_row(material, SpectrumTable())
    assert row["type"] == MATERIAL_CODES["dielectric"] and row["ior_model"] == model
    assert row["alpha"] == pytest.approx(material.roughness)
    if model == IOR_SELLMEIER:
        assert row["ior_coefficients_b"][:3] == pytest.approx(material.ior.coefficients[:3])
        assert row["ior_coefficients_c"][:3] == pytest.approx(material.ior.coefficients[3:])


@pytest.mark.parametrize(
    "lines, message",
    [
        ('ior = "BK8"', "materials.glass.ior: unknown glass 'BK8'"),
        ("ior = 0.2", "materials.glass.ior: the index of refraction must lie in"),
        ("ior = 1.0\nroughness = 0.2", "materials.glass.ior: a rough dielectric's index must differ from 1"),
        ("ior = { cauchy = [1.5] }", "materials.glass.ior"),
        ("ior = { sellmeier = [1, 1, 1, 0.2, 0.1, 0.3] }", "materials.glass.ior: the index of refraction must lie in"),
        ("roughness = 2", "materials.glass.roughness"),
        ("colour = 1", "unknown key 'colour'"),
    ],
)
def test_bad_dielectrics_name_the_key(tmp_path, lines, message):
    with pytest.raises(SpectraceError) as error:
        _load(tmp_path, lines)
    assert message in str(error.value) and "\n" not in str(error.value)


def test_api_helper():
    material = spectrace.dielectric("SF11", roughness=0.1, specular_tint=0.9)
    assert material.ior.name == "SF11" and material.ior.dispersive
    assert material.ior.at(587.5618) == pytest.approx(glass("SF11").nd_catalog, abs=5e-5)
    assert spectrace.dielectric({"cauchy": [1.5, 0.004]}).ior.model == "cauchy"
    with pytest.raises(SpectraceError, match="roughness"):
        spectrace.dielectric(1.5, roughness=-1)
    # Below 1 (the rarer medium inside) and index-matched smooth interfaces are valid; a rough matched one is not.
    assert spectrace.dielectric(1 / 1.33).ior.at(500.0) == pytest.approx(1 / 1.33)
    assert spectrace.dielectric(1.0).is_delta
    with pytest.raises(SpectraceError, match="differ from 1"):
        spectrace.dielectric(1.0, roughness=0.1)


FURNACE_SIDE, FURNACE_SPP = 12, 96


@pytest.mark.parametrize("ior", [1.5, "SF11"])
def test_glass_sphere_in_a_furnace_renders_as_the_environment(device, ior):
    """Smooth glass absorbs nothing and L/n² is conserved along refracted rays, so every pixel's expected Y is the
    environment's radiance k exactly, for a constant and for a dispersive index (where only the hero wavelength
    continues through the glass, weighted by 4).

    Russian roulette is off (rr_depth beyond the longest path): rays trapped by total internal reflection bounce
    dozens of times, and roulette's 1/0.95 per bounce would give those rare paths weights far above the rest, a
    heavy tail that the image's standard error cannot see. Without it every path through clear glass carries
    exactly k, and the only noise left is the wavelengths' (and, with dispersion, the hero's weight of 4)."""
    k = 0.8
    scene = Scene(
        camera=Camera(origin=(0.0, 0.0, -4.0), target=(0.0, 0.0, 0.0), fov_degrees=30.0),
        width=FURNACE_SIDE,
        height=FURNACE_SIDE,
        spp=FURNACE_SPP,
        max_depth=-1,
        seed=3,
        shapes=[spectrace.shape("sphere", spectrace.dielectric(ior))],
        lights=[ConstantEnvironment(Spectrum.constant(k))],
    ).with_overrides(rr_depth=2000)
    y = Renderer(scene, device).render().xyz[..., 1].ravel()
    _, standard_error = assert_furnace(y, k, slack=1e-4 * k, what=ior)
    if ior == 1.5:
        assert standard_error < 0.002 * k  # no dispersion: the four wavelengths move together, little noise


@pytest.mark.parametrize("name", ["cube", "sphere", "prism"])
def test_built_in_closed_shapes_face_outward(name):
    """A dielectric takes its exterior from the winding, so the closed built-ins must be wound outward: every face's
    (v1 − v0) × (v2 − v0) points away from the (convex) shape's centre. The prism also has the stated size."""
    mesh = spectrace.geometry.primitives.BUILTIN_SHAPES[name]()
    v0, v1, v2 = mesh.triangles()
    normals = np.cross(v1 - v0, v2 - v0)
    centroids = (v0 + v1 + v2) / 3 - mesh.vertices.mean(axis=0)
    assert np.all(np.einsum("ij,ij->i", normals, centroids) > 0)
    if name == "prism":
        assert mesh.area() == pytest.approx(2 * np.sqrt(3) + 3 * 4)  # two caps of side 2, three 2 x 2 sides
