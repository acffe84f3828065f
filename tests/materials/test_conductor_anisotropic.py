"""The conductor's anisotropic lobe (`roughness_v`) in the scene format, the API and the pbrt-v4 import; its laws
(reciprocity, chi-square, pdf, energy) are test_bsdfs.py's, its white furnace test_furnace_integrators.py's, its
agreement with Mitsuba 3 test_mitsuba_conductor_anisotropic.py's."""

import numpy as np
import pytest

import spectrace
from scene_text import camera_film
from spectrace.engine.renderer import Renderer
from spectrace.errors import SpectraceError
from spectrace.interop.pbrt import pbrt_scene_data
from spectrace.materials import material_row
from spectrace.scene import load_scene
from spectrace.spectral.table import SpectrumTable


def _row(material) -> np.ndarray:
    return material_row(material, SpectrumTable())


def _scene(tmp_path, metal: str, textures: str = "") -> object:
    path = tmp_path / "scene.toml"
    path.write_text(
        camera_film(origin="[0, -3, 1]", width="12", height="12")
        + f"""
[[lights]]
type = "constant"
radiance = {{ value = 1.0 }}

[materials.metal]
type = "conductor"
metal = "Al"
{metal}
{textures}
[[shapes]]
type = "sphere"
material = "metal"
"""
    )
    return load_scene(path)


def test_the_scene_file_and_the_api_take_roughness_v(tmp_path):
    material = _scene(tmp_path, "roughness = 0.1\nroughness_v = 0.4").shapes[0].material
    assert material == spectrace.conductor("Al", roughness=0.1, roughness_v=0.4)
    row = _row(material)
    assert (row["tangent_frame"], row["alpha"], row["ior"]) == (1, pytest.approx(0.1), pytest.approx(0.4))
    assert not material.is_delta and spectrace.conductor("Al", roughness_v=0.0).is_delta


@pytest.mark.parametrize("value", ["1.5", "-0.1"])
def test_a_roughness_v_out_of_range_is_refused_in_one_line_naming_the_key(tmp_path, value):
    with pytest.raises(SpectraceError) as error:
        _scene(tmp_path, f"roughness = 0.1\nroughness_v = {value}")
    message = str(error.value)
    assert "materials.metal.roughness_v" in message and "\n" not in message, message
    with pytest.raises(SpectraceError, match="roughness_v"):
        spectrace.conductor("Al", roughness=0.1, roughness_v=float(value))


@pytest.mark.parametrize("distribution", ["ggx", "beckmann"])
def test_equal_widths_are_the_isotropic_row(distribution):
    """An isotropic conductor keeps its row bit for bit, so its kernels' isotropic code and its renders."""
    isotropic = spectrace.conductor("Au", roughness=0.3, distribution=distribution)
    for same in (0.3, None):
        equal = spectrace.conductor("Au", roughness=0.3, roughness_v=same, distribution=distribution)
        assert _row(equal).tobytes() == _row(isotropic).tobytes()


def test_a_textured_width_is_read_per_point(tmp_path, device):
    """Both textured slots (roughness's and roughness_v's) are read per point: a checkerboard scaled so that the
    whole sphere lies in its first square gives that square's number's image, not its largest value's (which the
    row holds for the flags)."""
    textures = """
[textures.u]
type = "checkerboard"
color0 = { value = 0.05 }
color1 = { value = 0.8 }
uv_scale = [0.5, 0.5]

[textures.v]
type = "checkerboard"
color0 = { value = 0.4 }
color1 = { value = 0.9 }
uv_scale = [0.5, 0.5]
"""
    images = []
    for metal in (
        "roughness = 0.05\nroughness_v = 0.4",
        'roughness = { texture = "u" }\nroughness_v = 0.4',
        'roughness = 0.05\nroughness_v = { texture = "v" }',
    ):
        renderer = Renderer(_scene(tmp_path, metal, textures), device)
        renderer.render(spp=16)
        images.append(renderer.image().xyz)
    assert images[0][..., 1].mean() > 0.1
    for image in images[1:]:
        np.testing.assert_allclose(image, images[0], rtol=1e-5, atol=1e-6)
    # and the widths matter: swapped, the highlight stretches the other way
    renderer = Renderer(_scene(tmp_path, "roughness = 0.4\nroughness_v = 0.05"), device)
    renderer.render(spp=16)
    assert np.abs(renderer.image().xyz - images[0]).max() > 0.05


PBRT = """LookAt 0 3 3  0 0 0  0 1 0
Camera "perspective" "float fov" 40
Film "rgb" "integer xresolution" 8 "integer yresolution" 8
WorldBegin
LightSource "point" "point3 from" [0.5 2 1] "float power" 40
Texture "r" "float" "constant" "float value" 0.09
Material "conductor" {parameters}
Shape "sphere"
"""


@pytest.mark.parametrize(
    "parameters, expected",
    [
        ('"float uroughness" 0.04 "float vroughness" 0.25', (0.2, 0.5)),  # remapped: α = √roughness
        ('"float uroughness" 0.04 "float vroughness" 0.25 "bool remaproughness" false', (0.04, 0.25)),
        ('"float roughness" 0.09 "float vroughness" 0.25', (0.3, 0.5)),  # roughness stands for a missing axis
        ('"float uroughness" 0.16 "float vroughness" 0.16', (0.4, None)),
        ('"texture uroughness" "r" "float vroughness" 0.25', (0.3, 0.5)),  # a constant float texture: 0.09
    ],
)
def test_pbrt_conductor_carries_both_roughnesses(tmp_path, parameters, expected):
    path = tmp_path / "scene.pbrt"
    path.write_text(PBRT.format(parameters=parameters))
    data, context = pbrt_scene_data(path)
    (material,) = data["materials"].values()
    assert material["roughness"] == pytest.approx(expected[0])
    assert material.get("roughness_v") == (None if expected[1] is None else pytest.approx(expected[1]))
    assert not [note for note in context.notes if "anisotropic" in note]


def test_the_mitsuba_export_keeps_both_widths(tmp_path, mitsuba_scalar_spectral):
    """Exported as Mitsuba's alpha_u (along dp/du, as spectrace's frame) and alpha_v; a textured width is refused,
    not flattened."""
    from spectrace.interop.mitsuba.export import scene_to_mitsuba_dict

    scene = _scene(tmp_path, "roughness = 0.1\nroughness_v = 0.4")
    exported = scene_to_mitsuba_dict(scene, tmp_path)
    bsdf = exported["material_0"]["bsdf"]
    assert (bsdf["type"], bsdf["alpha_u"], bsdf["alpha_v"]) == ("roughconductor", pytest.approx(0.1), 0.4)
    assert "alpha" not in bsdf
    mitsuba_scalar_spectral.load_dict(exported)  # Mitsuba takes it
    textures = '\n[textures.v]\ntype = "checkerboard"\ncolor0 = { value = 0.4 }\ncolor1 = { value = 0.2 }\n'
    textured = _scene(tmp_path, 'roughness = 0.1\nroughness_v = { texture = "v" }', textures)
    with pytest.raises(SpectraceError, match="textured roughness"):
        scene_to_mitsuba_dict(textured, tmp_path)
