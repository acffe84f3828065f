"""KHR_materials_specular, _dispersion, _anisotropy and _iridescence read into the principled material: each mapped
value checked against the extension's own definition (Fresnel reflectance at normal incidence, the Abbe number,
the ratio of the lobe's two roughnesses), the imported TOML loaded, and the anisotropy's rotation rendered against
the texture layout it stands for."""

from __future__ import annotations

import math
import tomllib

import numpy as np
import pytest
from tests.interop.gltf_builder import Gltf

from spectrace.interop.gltf import gltf_scene_data


def _material(tmp_path, extensions: dict, **pbr) -> tuple[dict, list[str]]:
    gltf = Gltf()
    gltf.json["extensionsUsed"] = sorted(extensions)
    material = gltf.material(
        pbrMetallicRoughness={"metallicFactor": 0.0, **pbr}, extensions=extensions, doubleSided=True
    )
    gltf.node(mesh=gltf.quad(1.0, material))
    path = gltf.write(tmp_path / "model.glb")
    data, ctx = gltf_scene_data(path, tmp_path / "out.toml")
    (table,) = data["materials"].values()
    return table, ctx.warnings


def _loads(tmp_path, extensions: dict, **pbr) -> None:
    """The import's TOML loads: every mapped value is one the principled material takes."""
    from spectrace.interop.gltf import import_gltf
    from spectrace.scene import load_scene

    gltf = Gltf()
    gltf.json["extensionsUsed"] = sorted(extensions)
    material = gltf.material(pbrMetallicRoughness={"metallicFactor": 0.0, **pbr}, extensions=extensions)
    gltf.node(mesh=gltf.quad(1.0, material))
    import_gltf(gltf.write(tmp_path / "loads.glb"), tmp_path / "loads.toml")
    load_scene(tmp_path / "loads.toml")


def _r0(eta: float) -> float:
    return ((eta - 1.0) / (eta + 1.0)) ** 2


@pytest.mark.parametrize("ior, factor", [(1.5, 0.5), (1.7, 0.25), (1.5, 0.0)])
def test_specular_factor_scales_the_normal_incidence_reflectance(tmp_path, ior, factor):
    extensions = {"KHR_materials_ior": {"ior": ior}, "KHR_materials_specular": {"specularFactor": factor}}
    table, warnings = _material(tmp_path, extensions)
    assert _r0(table["eta"]) == pytest.approx(factor * _r0(ior), rel=1e-9, abs=1e-8)
    assert any("KHR_materials_specular is approximated" in w for w in warnings) == (0.0 < factor < 1.0)
    _loads(tmp_path, extensions)


def test_a_grey_specular_colour_scales_the_reflectance_and_a_coloured_one_is_named(tmp_path):
    grey, warnings = _material(tmp_path, {"KHR_materials_specular": {"specularColorFactor": [2.0, 2.0, 2.0]}})
    assert _r0(grey["eta"]) == pytest.approx(2.0 * _r0(1.5))
    assert not warnings
    coloured, warnings = _material(tmp_path, {"KHR_materials_specular": {"specularColorFactor": [1.0, 0.0, 0.0]}})
    assert _r0(coloured["eta"]) == pytest.approx(0.2126 * _r0(1.5))
    assert any("coloured F0" in w for w in warnings)


def test_specular_on_a_transmitting_material_keeps_its_index(tmp_path):
    extensions = {
        "KHR_materials_transmission": {"transmissionFactor": 1.0},
        "KHR_materials_ior": {"ior": 1.4},
        "KHR_materials_specular": {"specularFactor": 0.5},
    }
    table, warnings = _material(tmp_path, extensions)
    assert table["eta"] == 1.4
    assert any("transmitting material is not imported" in w for w in warnings)


@pytest.mark.parametrize("ior, dispersion", [(1.5, 0.4), (1.7, 1.0), (1.33, 0.2)])
def test_dispersion_is_the_abbe_number_of_the_index(tmp_path, ior, dispersion):
    """V_d = (n_d − 1)/(n_F − n_C) at the Fraunhofer d, F and C lines (587.56, 486.13, 656.27 nm), and n(λ_d) = the
    extension's ior, with V_d = 20 / dispersion (KHR_materials_dispersion)."""
    from spectrace.spectral.glasses import index_of_refraction

    extensions = {
        "KHR_materials_transmission": {"transmissionFactor": 1.0},
        "KHR_materials_ior": {"ior": ior},
        "KHR_materials_dispersion": {"dispersion": dispersion},
    }
    table, _ = _material(tmp_path, extensions)
    n = index_of_refraction(table["eta"])
    n_d, n_f, n_c = n.at(np.array([587.56, 486.13, 656.27]))
    assert n_d == pytest.approx(ior, abs=2e-5)
    assert (n_d - 1.0) / (n_f - n_c) == pytest.approx(20.0 / dispersion, rel=1e-3)
    _loads(tmp_path, extensions)


def test_dispersion_without_transmission_leaves_the_index_a_number(tmp_path):
    table, _ = _material(tmp_path, {"KHR_materials_dispersion": {"dispersion": 0.5}})
    assert "eta" not in table or isinstance(table["eta"], float)


@pytest.mark.parametrize("strength, roughness", [(0.5, 0.5), (0.8, 0.3), (0.2, 0.7)])
def test_anisotropy_keeps_the_ratio_of_glTFs_two_roughnesses(tmp_path, strength, roughness):
    """glTF: α_t = mix(α, 1, s²), α_b = α, α = r². spectrace's principled (docs/materials.md): αx = α/√(1 − 0.9a),
    αy = α √(1 − 0.9a), so αx/αy = 1/(1 − 0.9a)."""
    extensions = {"KHR_materials_anisotropy": {"anisotropyStrength": strength, "anisotropyRotation": 0.5}}
    table, warnings = _material(tmp_path, extensions, roughnessFactor=roughness)
    alpha = roughness**2
    expected = (alpha + strength**2 * (1.0 - alpha)) / alpha
    assert 1.0 / (1.0 - 0.9 * table["anisotropic"]) == pytest.approx(expected, rel=1e-9)
    assert table["anisotropic_rotation"] == pytest.approx(math.degrees(0.5))
    assert any("KHR_materials_anisotropy is approximated" in w for w in warnings)
    _loads(tmp_path, extensions, roughnessFactor=roughness)


def test_iridescence_is_named_once(tmp_path):
    gltf = Gltf()
    gltf.json["extensionsUsed"] = ["KHR_materials_iridescence"]
    for _ in range(3):
        material = gltf.material(extensions={"KHR_materials_iridescence": {"iridescenceFactor": 1.0}})
        gltf.node(mesh=gltf.quad(1.0, material))
    _, ctx = gltf_scene_data(gltf.write(tmp_path / "model.glb"), tmp_path / "out.toml")
    named = [w for w in ctx.warnings if "KHR_materials_iridescence" in w]
    assert len(named) == 1 and "thin-film" in named[0]


def _anisotropic_plane(path, uvs, rotation: float):
    gltf = Gltf()
    gltf.json["extensionsUsed"] = ["KHR_materials_anisotropy"]
    material = gltf.material(
        pbrMetallicRoughness={"baseColorFactor": [0.9, 0.9, 0.9, 1.0], "metallicFactor": 1.0, "roughnessFactor": 0.5},
        extensions={"KHR_materials_anisotropy": {"anisotropyStrength": 0.9, "anisotropyRotation": rotation}},
        doubleSided=True,
    )
    corners = [[-2, -2, 0], [2, -2, 0], [2, 2, 0], [-2, 2, 0]]
    gltf.node(mesh=gltf.mesh(corners, [0, 1, 2, 0, 2, 3], [[0, 0, 1]] * 4, uvs, material))
    light = gltf.light(type="point", intensity=2000.0)
    gltf.node(extensions={"KHR_lights_punctual": {"light": light}}, translation=[0.6, 0.3, 1.0])
    camera = gltf.camera(type="perspective", perspective={"yfov": 1.2, "aspectRatio": 1.0, "znear": 0.01})
    gltf.node(camera=camera, translation=[0.0, 0.0, 1.5])
    return gltf.write(path)


def _render(path, tmp_path) -> np.ndarray:
    from spectrace.api import render
    from spectrace.interop.gltf import import_gltf
    from spectrace.scene import load_scene

    toml = tmp_path / f"{path.stem}.toml"
    import_gltf(path, toml)
    scene = load_scene(toml).with_overrides(width=16, height=16, spp=16, seed=5)
    return render(scene, progress=False).xyz[..., 1]


def test_a_rotated_anisotropy_renders_as_the_texture_layout_turned_the_other_way(tmp_path):
    """anisotropyRotation π/2 on a layout whose u runs along +x stretches the lobe along +y, as no rotation on a
    layout whose u runs along +y does (the same directions, so the same random numbers give the same paths: the
    two agree to float rounding); the unrotated first layout, stretched along x, renders another image."""
    upright = [[0, 1], [1, 1], [1, 0], [0, 0]]  # u along +x
    turned = [[0, 0], [0, 1], [1, 1], [1, 0]]  # u along +y
    rotated = _render(_anisotropic_plane(tmp_path / "rotated.glb", upright, math.pi / 2), tmp_path)
    along_y = _render(_anisotropic_plane(tmp_path / "along_y.glb", turned, 0.0), tmp_path)
    along_x = _render(_anisotropic_plane(tmp_path / "along_x.glb", upright, 0.0), tmp_path)
    np.testing.assert_allclose(rotated, along_y, rtol=1e-3, atol=1e-6 * along_y.max())
    assert np.abs(along_x - along_y).max() > 0.1 * along_y.max()


def _specular_panels(path):
    """Two near-black panels, KHR_materials_specular's factor 1 and 0.25, turned 55° from the camera under the
    uniform white environment a file without lights gets: what they show is mostly their specular reflection."""
    gltf = Gltf()
    gltf.json["extensionsUsed"] = ["KHR_materials_specular"]
    for x, factor in ((-0.8, 1.0), (0.8, 0.25)):
        material = gltf.material(
            pbrMetallicRoughness={
                "baseColorFactor": [0.02, 0.02, 0.02, 1.0],
                "metallicFactor": 0.0,
                "roughnessFactor": 0.4,
            },
            extensions={"KHR_materials_specular": {"specularFactor": factor}},
            doubleSided=True,
        )
        # −55° about x: the panel's normal tilts up, away from the camera
        gltf.node(mesh=gltf.quad(0.75, material), translation=[x, 0.0, 0.0], rotation=[-0.4617486, 0, 0, 0.8870108])
    camera = gltf.camera(type="perspective", perspective={"yfov": 0.7, "aspectRatio": 2.0, "znear": 0.01})
    gltf.node(camera=camera, translation=[0.0, 0.0, 1.8])
    return gltf.write(path)


@pytest.mark.subprocess
@pytest.mark.slow
def test_specular_factor_renders_as_cycles_renders_it(tmp_path):
    """Blender's importer turns specularFactor into the Principled BSDF's Specular IOR Level, which Cycles applies by
    scaling F0 (grazing reflectance staying 1), as the index spectrace imports does. 64×32 at 64 spp, against Cycles
    with the sample assets' allowance (tests/interop/test_gltf_cycles.py: 7 % a block besides 4 σ, 2 % the mean).
    Measured: the blocks within 6 %, but the bottom row's (8–18 % brighter in Cycles on both panels alike, the two
    principled models' difference where the noise is largest; inside 4 σ), the means within 0.5 %. Without the
    mapping the right panel's blocks are 0.51–0.86 of Cycles' and eleven of them fail."""
    pytest.importorskip("bpy", reason="bpy (Blender as a Python module, installed apart: pip install bpy) is absent")
    from tests.interop.test_gltf_cycles import _check, compare

    _check(compare(_specular_panels(tmp_path / "panels.glb"), tmp_path, width=64, spp=64), 0.07, 0.02)


def _textured_anisotropy(tmp_path, blues: list[int], strength: float, roughness: float):
    """A quad whose anisotropyTexture is a row of texels with these B values (RG the tangent's own direction)."""
    gltf = Gltf()
    gltf.json["extensionsUsed"] = ["KHR_materials_anisotropy"]
    pixels = np.array([[[255, 128, b] for b in blues]])
    index = gltf.image_texture(pixels, sampler={"magFilter": 9728, "minFilter": 9728})
    extension = {"anisotropyStrength": strength, "anisotropyTexture": {"index": index}}
    material = gltf.material(
        pbrMetallicRoughness={"metallicFactor": 0.0, "roughnessFactor": roughness},
        extensions={"KHR_materials_anisotropy": extension},
    )
    gltf.node(mesh=gltf.quad(1.0, material))
    return gltf.write(tmp_path / "textured.glb")


def test_the_anisotropy_textures_strength_keeps_glTFs_ratio_texel_by_texel(tmp_path):
    """Each texel's strength s = anisotropyStrength × B gives the ratio α_t/α_b = (α + s²(1 − α))/α of glTF's
    definition as principled's 1/(1 − 0.9 a), within the 8-bit PNG's step; the direction (RG) is named."""
    from PIL import Image

    blues = [0, 64, 128, 200, 255]
    strength, roughness = 0.8, 0.5
    data, ctx = gltf_scene_data(_textured_anisotropy(tmp_path, blues, strength, roughness), tmp_path / "out.toml")
    (table,) = data["materials"].values()
    bitmap = table["anisotropic"]
    assert bitmap["texture"] == "bitmap" and bitmap["raw"] is True
    ctx.files[bitmap["file"]](tmp_path / "weights.png")
    weights = np.asarray(Image.open(tmp_path / "weights.png"), dtype=np.float64)[0] / 255.0
    alpha = roughness**2
    s = strength * np.array(blues) / 255.0
    expected = (alpha + s**2 * (1.0 - alpha)) / alpha
    np.testing.assert_allclose(weights, (1.0 - 1.0 / expected) / 0.9, atol=0.5 / 255.0 + 1e-12)
    # RG, the direction per texel: the texture's own RGB, raw (the kernel reads 2 (r, g) − 1)
    direction = table["anisotropic_direction"]
    assert direction["texture"] == "bitmap" and direction["raw"] is True
    ctx.files[direction["file"]](tmp_path / "direction.png")
    rgb = np.asarray(Image.open(tmp_path / "direction.png"))[0]
    assert rgb[:, :2].tolist() == [[255, 128]] * len(blues)
    assert not any("texture (a direction and strength per texel) is not imported" in w for w in ctx.warnings)


# The texel (255, 128) glTF writes for "along the tangent": d = 2 (r, g) − 1 = (1, 1/255), turned 0.22° from it
ALONG_TANGENT = math.atan2(1.0 / 255.0, 1.0)


def _anisotropy_plane_two_halves(path, blues: list[int] | None, strength: float, rotation=0.0, texels=None):
    """The lit metal plane of _anisotropic_plane with anisotropyTexture's B `blues` (RG 255, 128) or RGB `texels`
    over its halves (u < ½, u > ½), or no texture, turned by anisotropyRotation `rotation`; roughness 0.3
    (α = 0.09), where strength 1 gives principled's largest weight, a = 1, exactly."""
    gltf = Gltf()
    gltf.json["extensionsUsed"] = ["KHR_materials_anisotropy"]
    extension: dict = {"anisotropyStrength": strength, "anisotropyRotation": rotation}
    if blues is not None or texels is not None:
        pixels = np.array([texels if texels is not None else [[255, 128, b] for b in blues]])
        extension["anisotropyTexture"] = {"index": gltf.image_texture(pixels, sampler={"magFilter": 9728})}
    material = gltf.material(
        pbrMetallicRoughness={"baseColorFactor": [0.9, 0.9, 0.9, 1.0], "metallicFactor": 1.0, "roughnessFactor": 0.3},
        extensions={"KHR_materials_anisotropy": extension},
        doubleSided=True,
    )
    corners = [[-2, -2, 0], [2, -2, 0], [2, 2, 0], [-2, 2, 0]]
    uvs = [[0, 1], [1, 1], [1, 0], [0, 0]]  # u along +x: the texture's left texel on the left half
    gltf.node(mesh=gltf.mesh(corners, [0, 1, 2, 0, 2, 3], [[0, 0, 1]] * 4, uvs, material))
    light = gltf.light(type="point", intensity=2000.0)
    gltf.node(extensions={"KHR_lights_punctual": {"light": light}}, translation=[0.3, 0.3, 1.0])
    camera = gltf.camera(type="perspective", perspective={"yfov": 1.2, "aspectRatio": 1.0, "znear": 0.01})
    gltf.node(camera=camera, translation=[0.0, 0.0, 1.5])
    return gltf.write(path)


def test_a_two_valued_anisotropy_texture_renders_each_half_as_its_untextured_strength(tmp_path):
    """B = 255 on the left half, 0 on the right: the left renders as anisotropyStrength 1 without a texture (turned
    by the texels' direction, ALONG_TANGENT), the right as an isotropic lobe (strength 0), to float rounding (the
    same paths; the texels hold a = 1 and 0 exactly); columns beside the seam, where a pixel's samples fall on both
    texels, are left out. The two untextured images differ on each side, so each half shows which weight it got."""
    textured = _render(_anisotropy_plane_two_halves(tmp_path / "halves.glb", [255, 0], 1.0), tmp_path)
    stretched = _render(_anisotropy_plane_two_halves(tmp_path / "stretched.glb", None, 1.0, ALONG_TANGENT), tmp_path)
    round_lobe = _render(_anisotropy_plane_two_halves(tmp_path / "round.glb", None, 0.0), tmp_path)
    left, right = slice(0, 7), slice(9, 16)
    scale = stretched.max()
    np.testing.assert_allclose(textured[:, left], stretched[:, left], rtol=1e-3, atol=1e-6 * scale)
    np.testing.assert_allclose(textured[:, right], round_lobe[:, right], rtol=1e-3, atol=1e-6 * scale)
    for half in (left, right):
        assert np.abs(stretched[:, half] - round_lobe[:, half]).max() > 0.05 * scale


def test_a_two_valued_anisotropy_direction_renders_each_half_as_its_untextured_rotation(tmp_path):
    """anisotropyTexture's RG: (255, 128) on the left half, (128, 255) on the right, d = (1, 1/255) and (1/255, 1),
    with anisotropyRotation 30°: the left renders as the untextured rotation 30° + atan2(1, 255), the right as
    30° + atan2(255, 1) (the lobe across the tangent), to float rounding (the same paths); columns beside the seam
    are left out. The two untextured images differ on each side, so each half shows which direction it got."""
    turn = math.pi / 6
    texels = [[255, 128, 255], [128, 255, 255]]
    textured = _render(_anisotropy_plane_two_halves(tmp_path / "dir.glb", None, 1.0, turn, texels=texels), tmp_path)
    along = _render(_anisotropy_plane_two_halves(tmp_path / "along.glb", None, 1.0, turn + ALONG_TANGENT), tmp_path)
    across = math.atan2(1.0, 1.0 / 255.0)
    turned = _render(_anisotropy_plane_two_halves(tmp_path / "across.glb", None, 1.0, turn + across), tmp_path)
    left, right = slice(0, 7), slice(9, 16)
    scale = along.max()
    np.testing.assert_allclose(textured[:, left], along[:, left], rtol=1e-3, atol=1e-6 * scale)
    np.testing.assert_allclose(textured[:, right], turned[:, right], rtol=1e-3, atol=1e-6 * scale)
    for half in (left, right):
        assert np.abs(along[:, half] - turned[:, half]).max() > 0.05 * scale


def _anisotropic_plane_with_tangents(path, uvs, tangent):
    """_anisotropic_plane turned 30° by anisotropyRotation, with TANGENT `tangent` (xyz, w) at every corner, the
    light and camera on the plane x = 0, so the scene but the anisotropic frame is its own mirror image in x."""
    gltf = Gltf()
    gltf.json["extensionsUsed"] = ["KHR_materials_anisotropy"]
    material = gltf.material(
        pbrMetallicRoughness={"baseColorFactor": [0.9, 0.9, 0.9, 1.0], "metallicFactor": 1.0, "roughnessFactor": 0.5},
        extensions={"KHR_materials_anisotropy": {"anisotropyStrength": 0.9, "anisotropyRotation": math.pi / 6}},
        doubleSided=True,
    )
    corners = [[-2, -2, 0], [2, -2, 0], [2, 2, 0], [-2, 2, 0]]
    mesh = gltf.mesh(corners, [0, 1, 2, 0, 2, 3], [[0, 0, 1]] * 4, uvs, material)
    gltf.json["meshes"][mesh]["primitives"][0]["attributes"]["TANGENT"] = gltf.accessor([tangent] * 4)
    gltf.node(mesh=mesh)
    light = gltf.light(type="point", intensity=2000.0)
    gltf.node(extensions={"KHR_lights_punctual": {"light": light}}, translation=[0.0, 0.4, 1.0])
    camera = gltf.camera(type="perspective", perspective={"yfov": 1.2, "aspectRatio": 1.0, "znear": 0.01})
    gltf.node(camera=camera, translation=[0.0, 0.0, 1.5])
    return gltf.write(path)


def test_the_anisotropy_rotation_turns_toward_the_signed_bitangent_on_a_mirrored_layout(tmp_path):
    """glTF turns the anisotropy direction from the tangent t toward the bitangent b = (n × t) w. A layout whose u
    runs along −x with w = −1 (the mirror image in x of one whose u runs along +x with w = 1: b = +y on both) must
    render the mirror image of the other's highlight (to the noise of 16 × 16 pixels at 16 spp); turning toward n × t
    instead renders the unmirrored image."""
    upright = [[0, 1], [1, 1], [1, 0], [0, 0]]  # u along +x
    mirrored = [[1, 1], [0, 1], [0, 0], [1, 0]]  # u along −x
    plain = _render(_anisotropic_plane_with_tangents(tmp_path / "plain.glb", upright, [1, 0, 0, 1]), tmp_path)
    mirror = _render(_anisotropic_plane_with_tangents(tmp_path / "mirror.glb", mirrored, [-1, 0, 0, -1]), tmp_path)
    flipped = plain[:, ::-1]
    wrong = np.abs(plain - flipped).mean()  # the highlight's asymmetry: 1.2 × the image's mean
    assert wrong > 0.5 * plain.mean()
    # measured: 0.007 × that asymmetry (the two renders' noise); 1.0, the unmirrored image bit for bit, without w
    assert np.abs(mirror - flipped).mean() < 0.05 * wrong


def _specular_plane_two_halves(path, alphas: list[int] | None, factor: float, colours=None, colour_factor=None):
    """A near-black dielectric plane (index 1.5, roughness 0.3) lit by a point light, with KHR_materials_specular's
    factor `factor` and specularTexture's A `alphas` over its halves (u < ½, u > ½), or no texture: what it shows
    is mostly its specular reflection."""
    gltf = Gltf()
    gltf.json["extensionsUsed"] = ["KHR_materials_specular"]
    extension: dict = {"specularFactor": factor}
    if alphas is not None:
        pixels = np.array([[[255, 255, 255, a] for a in alphas]])
        extension["specularTexture"] = {"index": gltf.image_texture(pixels, sampler={"magFilter": 9728})}
    if colours is not None:
        pixels = np.array([[[c, c, c, 255] for c in colours]])
        extension["specularColorTexture"] = {"index": gltf.image_texture(pixels, sampler={"magFilter": 9728})}
    if colour_factor is not None:
        extension["specularColorFactor"] = [colour_factor] * 3
    material = gltf.material(
        pbrMetallicRoughness={
            "baseColorFactor": [0.02, 0.02, 0.02, 1.0],
            "metallicFactor": 0.0,
            "roughnessFactor": 0.3,
        },
        extensions={"KHR_materials_specular": extension},
        doubleSided=True,
    )
    corners = [[-2, -2, 0], [2, -2, 0], [2, 2, 0], [-2, 2, 0]]
    uvs = [[0, 1], [1, 1], [1, 0], [0, 0]]  # u along +x: the texture's left texel on the left half
    gltf.node(mesh=gltf.mesh(corners, [0, 1, 2, 0, 2, 3], [[0, 0, 1]] * 4, uvs, material))
    light = gltf.light(type="point", intensity=2000.0)
    gltf.node(extensions={"KHR_lights_punctual": {"light": light}}, translation=[0.0, 0.3, 1.0])
    camera = gltf.camera(type="perspective", perspective={"yfov": 1.2, "aspectRatio": 1.0, "znear": 0.01})
    gltf.node(camera=camera, translation=[0.0, 0.0, 1.5])
    return gltf.write(path)


def test_a_two_valued_specular_texture_renders_each_half_as_its_untextured_factor(tmp_path):
    """specularTexture's A = 204 on the left half and 102 on the right scale F0 = 0.04 (index 1.5) by 0.8 and 0.4:
    principled's specular levels 0.4 and 0.2, which the 8-bit texels hold exactly (102/255, 51/255). Each half
    renders as the untextured specularFactor 0.8 or 0.4, whose index the host computes, to float rounding (the same
    paths); columns beside the seam are left out. The two untextured images differ on each side (F0 twice as
    large), so each half shows which level it got."""
    textured = _render(_specular_plane_two_halves(tmp_path / "halves.glb", [204, 102], 1.0), tmp_path)
    strong = _render(_specular_plane_two_halves(tmp_path / "strong.glb", None, 0.8), tmp_path)
    weak = _render(_specular_plane_two_halves(tmp_path / "weak.glb", None, 0.4), tmp_path)
    left, right = slice(0, 7), slice(9, 16)
    scale = strong.max()
    np.testing.assert_allclose(textured[:, left], strong[:, left], rtol=1e-3, atol=1e-6 * scale)
    np.testing.assert_allclose(textured[:, right], weak[:, right], rtol=1e-3, atol=1e-6 * scale)
    for half in (left, right):
        assert np.abs(strong[:, half] - weak[:, half]).max() > 0.05 * scale


def test_the_specular_textures_become_a_grey_specular_level_their_product(tmp_path):
    """specularTexture (A) and specularColorTexture together become principled's textured `specular` in place of the
    index: a scale texture of the colour texture's level (the luminance of F0 = specularFactor · R0 · texel, over
    0.08) times A; the TOML loads."""
    from PIL import Image

    gltf = Gltf()
    gltf.json["extensionsUsed"] = ["KHR_materials_specular"]
    index = gltf.image_texture(np.array([[[255, 255, 255, 255], [255, 255, 255, 0]]]))
    extension = {"specularFactor": 0.5, "specularTexture": {"index": index}, "specularColorTexture": {"index": index}}
    material = gltf.material(
        pbrMetallicRoughness={"metallicFactor": 0.0}, extensions={"KHR_materials_specular": extension}
    )
    gltf.node(mesh=gltf.quad(1.0, material))
    from spectrace.interop.gltf import import_gltf
    from spectrace.scene import load_scene

    path = gltf.write(tmp_path / "model.glb")
    data, ctx = gltf_scene_data(path, tmp_path / "out.toml")
    (table,) = data["materials"].values()
    specular = table["specular"]
    assert specular["texture"] == "scale" and "eta" not in table
    assert not any("Texture is not imported" in w for w in ctx.warnings)
    import_gltf(path, tmp_path / "loads.toml")
    (written,) = tomllib.loads((tmp_path / "loads.toml").read_text(encoding="utf-8"))["materials"].values()
    with Image.open(tmp_path / written["specular"]["tex"]["file"]) as image:  # white texels: 0.5 · 0.04 / 0.08
        assert np.asarray(image).ravel().tolist() == [64, 64]  # 0.25 to the 8-bit texel
    (loaded,) = {shape.material for shape in load_scene(tmp_path / "loads.toml").shapes}
    # the row's index is the largest texel's: F0 = 0.5 · 0.04 (within the 8-bit texel's rounding)
    assert loaded.specular_texture is not None and _r0(loaded.eta.at(550.0)) == pytest.approx(0.02, rel=0.01)


def test_a_two_valued_specular_colour_texture_renders_each_half_as_its_untextured_colour_factor(tmp_path):
    """specularColorTexture's grey texels, sRGB codes 255 and 170 (linear 1 and 0.40198), with specularFactor 0.8
    give F0 = 0.8 · 0.04 · texel: principled's specular levels 0.4 and 0.16079, which the 8-bit texels hold to
    4e-5 (102/255, 41/255). Each half renders as the untextured specularColorFactor of its texel's linear value to
    float rounding and that texel's rounding; the two untextured images differ on each side."""
    texel = ((170 / 255 + 0.055) / 1.055) ** 2.4
    textured = _render(_specular_plane_two_halves(tmp_path / "halves.glb", None, 0.8, colours=[255, 170]), tmp_path)
    strong = _render(_specular_plane_two_halves(tmp_path / "strong.glb", None, 0.8, colour_factor=1.0), tmp_path)
    weak = _render(_specular_plane_two_halves(tmp_path / "weak.glb", None, 0.8, colour_factor=texel), tmp_path)
    left, right = slice(0, 7), slice(9, 16)
    scale = strong.max()
    np.testing.assert_allclose(textured[:, left], strong[:, left], rtol=1e-3, atol=1e-6 * scale)
    np.testing.assert_allclose(textured[:, right], weak[:, right], rtol=1e-3, atol=1e-6 * scale)
    for half in (left, right):
        assert np.abs(strong[:, half] - weak[:, half]).max() > 0.05 * scale
