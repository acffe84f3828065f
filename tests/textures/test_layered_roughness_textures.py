"""Roughness textures on the stochastic layered materials: the coat's `roughness` (coatedconductor, coateddiffuse)
and the metal's `conductor_roughness` (coatedconductor), in the API, the scene format and pbrt-v4's import.

- A texture whose value is the constant α everywhere renders the same bits as the number α: the walk reads the
  same float, and the row's flags (from the texture's largest α) are the number's.
- A checkerboard of two roughnesses renders each tile as the untextured material of that tile's α: the per-pixel
  differences of the two renders (the same seed, so the same paths where they agree) average to 0 within 4
  standard errors over each tile's interior.
- pbrt-v4's `"texture conductor.roughness"` and `"texture interface.roughness"` import as textures of α, remapped as
  pbrt remaps them.
"""

import numpy as np
import pytest

import spectrace
from scene_text import camera_film
from spectrace.engine.renderer import Renderer
from spectrace.errors import SpectraceError
from spectrace.interop.pbrt import pbrt_scene_data
from spectrace.scene.model import Camera, Scene
from stats_toolkit import assert_within_standard_errors, mean_and_standard_error

SIDE = 16
HALF = SIDE // 2

LAYERED = {
    "coatedconductor.conductor_roughness": lambda alpha: spectrace.coatedconductor(
        "Au", conductor_roughness=alpha, roughness=0.1, thickness=0.05
    ),
    "coatedconductor.roughness": lambda alpha: spectrace.coatedconductor(
        "Au", conductor_roughness=0.2, roughness=alpha, thickness=0.05
    ),
    "coateddiffuse.roughness": lambda alpha: spectrace.coateddiffuse((0.6, 0.4, 0.2), roughness=alpha, thickness=0.05),
}


def _scene(material, spp: int) -> Scene:
    """A unit quad filling a 30° view from z = 3 (uv across it), lit by a small sphere light off to the side and a
    dim environment, so that the highlight's shape depends on α."""
    quad = spectrace.shape("rectangle", material)
    light = spectrace.shape(
        "sphere",
        spectrace.diffuse(0.0),
        emitter=spectrace.area_emitter(20.0),
        transform=[{"scale": 0.25}, {"translate": [0.5, 0.4, 2.0]}],
    )
    return Scene(
        camera=Camera(origin=(0.0, 0.0, 3.0), target=(0.0, 0.0, 0.0), fov_degrees=30.0),
        width=SIDE,
        height=SIDE,
        shapes=[quad, light],
        lights=[spectrace.constant_environment(0.2)],
        max_depth=4,
        spp=spp,
        seed=5,
        sampler="independent",
    )


@pytest.mark.parametrize("name", list(LAYERED))
def test_a_constant_roughness_texture_renders_the_numbers_bits(device, name):
    make = LAYERED[name]
    alpha = 0.3
    number = Renderer(_scene(make(alpha), 4), device).render().xyz
    for texture in (spectrace.bitmap(np.full((2, 2), alpha), filter="nearest"), spectrace.checkerboard(alpha, alpha)):
        assert np.array_equal(Renderer(_scene(make(texture), 4), device).render().xyz, number), texture


@pytest.mark.parametrize("name", list(LAYERED))
@pytest.mark.parametrize("alphas", [(0.05, 0.5), (0.0, 0.3)], ids=["rough|rough", "smooth|rough"])
def test_checkerboard_roughness_tiles_render_as_the_untextured_material(device, name, alphas):
    """Four tiles (uv_scale 2): tile (r, c) has α = alphas[(r + c) % 2]. With α1 = 0 a tile is smooth on a surface
    whose flags say rough."""
    make = LAYERED[name]
    texture = spectrace.checkerboard(alphas[0], alphas[1], uv_scale=2.0)
    assert make(texture).is_delta is False
    textured = Renderer(_scene(make(texture), 16), device).render().xyz
    constant = {alpha: Renderer(_scene(make(alpha), 16), device).render().xyz for alpha in alphas}
    for r in range(2):
        for c in range(2):
            alpha = alphas[(r + c) % 2]
            tile = slice(r * HALF + 1, (r + 1) * HALF - 1), slice(c * HALF + 1, (c + 1) * HALF - 1)
            difference = (textured[tile] - constant[alpha][tile]).reshape(-1, 3)
            mean, error = mean_and_standard_error(difference)
            assert_within_standard_errors(mean, 0.0, error, slack=1e-6, what=(name, r, c, alpha))


def test_the_conductor_roughness_texture_is_checked():
    with pytest.raises(SpectraceError, match="channels"):
        spectrace.coatedconductor(conductor_roughness=spectrace.bitmap(np.full((2, 2, 3), 0.2)))
    with pytest.raises(SpectraceError, match="above 1"):
        spectrace.coatedconductor(conductor_roughness=spectrace.checkerboard(0.2, 1.5))


def test_a_smooth_conductor_roughness_texture_keeps_the_material_delta():
    """Smooth everywhere (all α below the smooth limit) under a smooth coat with no scattering: only delta lobes."""
    assert spectrace.coatedconductor(conductor_roughness=spectrace.checkerboard(0.0, 1e-5)).is_delta
    assert not spectrace.coatedconductor(conductor_roughness=spectrace.checkerboard(0.0, 0.2)).is_delta


def test_scene_file_roughness_textures(tmp_path):
    path = tmp_path / "scene.toml"
    path.write_text(
        camera_film(origin="[0, 0, 3]", fov="30", width="8", height="8")
        + """
[textures.tiles]
type = "checkerboard"
color0 = { value = 0.1 }
color1 = { value = 0.4 }
[materials.coated]
type = "coatedconductor"
metal = "Au"
conductor_roughness = { texture = "tiles" }
roughness = { texture = "checkerboard", color0 = { value = 0.0 }, color1 = { value = 0.2 } }
[[shapes]]
type = "rectangle"
material = "coated"
[[lights]]
type = "constant"
radiance = { value = 1.0 }
"""
    )
    material = spectrace.load_scene(path).shapes[0].material
    assert isinstance(material.conductor_roughness, type(spectrace.checkerboard()))
    assert isinstance(material.roughness, type(spectrace.checkerboard()))
    bad = path.read_text().replace("color1 = { value = 0.4 }", "color1 = { value = 1.4 }")
    path.write_text(bad)
    with pytest.raises(SpectraceError, match="conductor_roughness"):
        spectrace.load_scene(path)


PBRT_HEADER = """LookAt 0 0 5  0 0 0  0 1 0
Camera "perspective" "float fov" 20
Film "rgb" "integer xresolution" 8 "integer yresolution" 8
WorldBegin
LightSource "infinite" "rgb L" [1 1 1]
"""


def test_pbrt_coated_roughness_textures_import_as_textures(tmp_path):
    """A constant float texture is its number (remapped: α = √roughness); an imagemap becomes a one-channel image of
    α beside the TOML, remapped per texel."""
    from PIL import Image

    Image.fromarray(np.array([[0, 255], [64, 255]], np.uint8)).save(tmp_path / "rough.png")
    path = tmp_path / "scene.pbrt"
    path.write_text(
        PBRT_HEADER + 'Texture "c" "float" "constant" "float value" 0.16\n'
        'Texture "map" "float" "imagemap" "string filename" "rough.png" "string encoding" "linear"\n'
        'Material "coatedconductor" "texture conductor.roughness" "map" "texture interface.roughness" "c"\n'
        'Shape "sphere"\n'
        'Material "coateddiffuse" "texture roughness" "map"\nShape "sphere"\n'
    )
    data, importer = pbrt_scene_data(path)
    coated, diffuse = data["materials"].values()
    assert coated["roughness"] == pytest.approx(0.4)
    for table in (coated["conductor_roughness"], diffuse["roughness"]):
        assert table["texture"] == "bitmap" and table["raw"] is True
    written = [np.asarray(values) for name, values in importer.files.items() if name.endswith(".tif")]
    assert written and np.allclose(written[0].squeeze(), np.sqrt(np.array([[0, 255], [64, 255]]) / 255.0), atol=1e-6)


def test_a_number_leaves_the_rows_conductor_texture_empty():
    """A number leaves the row's conductor texture empty: the kernel reads the number as before."""
    from spectrace.core.contract import NO_TEXTURE
    from spectrace.materials import material_row
    from spectrace.spectral.table import SpectrumTable

    row = material_row(spectrace.coatedconductor(conductor_roughness=0.3), SpectrumTable())
    assert row["reflectance_texture"] == NO_TEXTURE and row["ior_coefficients_b"][2] == pytest.approx(0.3)
