"""glTF's photometric units through the import and the renderer, against closed forms: KHR_lights_punctual's
candela and lux read back by spectrace's irradiance meter (683 lm/W · ∫ E ȳ dλ) as E = I / d² and E = E⊥, an
emissive material's nits by its radiance meter, and a Lambertian plane under a sun rendered as ρ E / π. Each
light has a colour: glTF's intensity times that colour's luminance Y = 0.2126 R + 0.7152 G + 0.0722 B.

The materials are imported as `diffuse` (the documented base-colour model): these tests are about units, not BSDFs."""

from __future__ import annotations

import math

import numpy as np
import pytest
from tests.interop.gltf_builder import Gltf

from spectrace.engine.meters import IrradianceMeter, RadianceMeter, measure
from spectrace.interop.gltf import load_gltf_scene

COLOUR = [1.0, 0.5, 0.25]
LUMINANCE = 0.2126 * 1.0 + 0.7152 * 0.5 + 0.0722 * 0.25
# The meter integrates ȳ by the trapezoid rule every 5 nm; the import divides by ∫ȳ on the 1 nm grid, and the
# D65-shaped RGB spectrum reproduces its colour's Y to its uplift's accuracy: 0.5 % covers both.
RELATIVE = 5e-3


def _scene(tmp_path, gltf: Gltf):
    gltf.node(camera=gltf.camera(type="perspective", perspective={"yfov": 0.5}), translation=[0, 0, 10])
    return load_gltf_scene(gltf.write(tmp_path / "lights.glb"), material_model="diffuse").with_overrides(max_depth=2)


@pytest.mark.parametrize("kind", ["point", "spot"])
def test_candela_at_distance_d_gives_intensity_over_d_squared_lux(tmp_path, device, kind):
    intensity, height = 250.0, 2.0
    gltf = Gltf()
    spot = {"spot": {"innerConeAngle": 0.2, "outerConeAngle": 0.4}} if kind == "spot" else {}
    light = gltf.light(type=kind, color=COLOUR, intensity=intensity, **spot)
    # the light's −z turned to the world's −y: a rotation of −90° about x
    half = math.sqrt(0.5)
    gltf.node(
        extensions={"KHR_lights_punctual": {"light": light}}, translation=[0, height, 0], rotation=[-half, 0, 0, half]
    )
    scene = _scene(tmp_path, gltf)
    reading = measure(
        scene, IrradianceMeter((0.0, 0.0, 0.0), (0.0, 1.0, 0.0)), streams=4, samples_per_item=4, device=device
    )
    assert reading.photometric == pytest.approx(intensity * LUMINANCE / height**2, rel=RELATIVE)
    if kind == "spot":  # outside the outer cone (0.4 rad from the axis), nothing
        aside = (height * math.tan(0.45), 0.0, 0.0)
        outside = measure(scene, IrradianceMeter(aside, (0.0, 1.0, 0.0)), streams=4, samples_per_item=4, device=device)
        assert outside.photometric == 0.0


def test_lux_of_a_directional_light_on_a_surface_facing_it(tmp_path, device):
    illuminance = 1200.0
    gltf = Gltf()
    light = gltf.light(type="directional", color=COLOUR, intensity=illuminance)
    gltf.node(extensions={"KHR_lights_punctual": {"light": light}})  # shining along −z
    scene = _scene(tmp_path, gltf)
    reading = measure(
        scene, IrradianceMeter((0.0, 0.0, 0.0), (0.0, 0.0, 1.0)), streams=4, samples_per_item=4, device=device
    )
    assert reading.photometric == pytest.approx(illuminance * LUMINANCE, rel=RELATIVE)
    tilted = measure(
        scene, IrradianceMeter((0.0, 0.0, 0.0), (0.0, 0.6, 0.8)), streams=4, samples_per_item=4, device=device
    )
    assert tilted.photometric == pytest.approx(0.8 * illuminance * LUMINANCE, rel=RELATIVE)


def test_emissive_strength_is_luminance_in_nits(tmp_path, device):
    strength = 40.0
    gltf = Gltf()
    material = gltf.material(
        emissiveFactor=COLOUR, extensions={"KHR_materials_emissive_strength": {"emissiveStrength": strength}}
    )
    gltf.node(mesh=gltf.quad(material=material))
    scene = _scene(tmp_path, gltf)
    reading = measure(
        scene, RadianceMeter((0.0, 0.0, 1.0), (0.0, 0.0, -1.0)), streams=4, samples_per_item=4, device=device
    )
    assert reading.photometric == pytest.approx(strength * LUMINANCE, rel=RELATIVE)
    behind = measure(
        scene, RadianceMeter((0.0, 0.0, -1.0), (0.0, 0.0, 1.0)), streams=4, samples_per_item=4, device=device
    )
    assert behind.photometric == 0.0, "a single-sided material emits on its front only"


def test_a_grey_plane_under_a_sun_renders_rho_e_over_pi(tmp_path, device):
    """The whole pipeline: node transforms, the orthographic camera, the PLY mesh and the light's units. Film Y
    is ∫ L ȳ dλ / ∫ ȳ dλ, so a plane of albedo ρ under E lux shows Y = ρ E / (π · 683 · ∫ȳ dλ) everywhere."""
    import spectrace
    from spectrace.spectral.colorimetry import CIE_Y_INTEGRAL

    albedo, illuminance = 0.5, 50_000.0
    gltf = Gltf()
    grey = gltf.material(pbrMetallicRoughness={"baseColorFactor": [albedo, albedo, albedo, 1.0]})
    half = math.sqrt(0.5)
    # the quad (z = 0, facing +z) laid flat, facing +y, 2 m wide; the camera and the sun straight above it
    gltf.node(mesh=gltf.quad(size=2.0, material=grey), rotation=[-half, 0, 0, half], translation=[0, -1, 0])
    gltf.node(
        extensions={"KHR_lights_punctual": {"light": gltf.light(type="directional", intensity=illuminance)}},
        rotation=[-half, 0, 0, half],
    )
    ortho = gltf.camera(type="orthographic", orthographic={"xmag": 1.0, "ymag": 1.0, "znear": 0.0, "zfar": 10.0})
    gltf.node(camera=ortho, translation=[0, 3, 0], rotation=[-half, 0, 0, half])
    scene = load_gltf_scene(gltf.write(tmp_path / "sun.gltf"), material_model="diffuse")
    image = spectrace.render(scene.with_overrides(width=16, height=16, spp=8, max_depth=2), device=device)
    expected = albedo * illuminance / (math.pi * 683.0 * CIE_Y_INTEGRAL)
    # Each pixel's wavelengths are sampled: the pixels scatter about the mean by spectral noise alone.
    values = image.xyz[..., 1].ravel()
    standard_error = values.std(ddof=1) / math.sqrt(len(values))
    assert abs(values.mean() - expected) <= 4.0 * standard_error + RELATIVE * expected


def test_an_emissive_texture_shows_upright_with_each_texel_at_its_luminance(tmp_path, device):
    """glTF's texel (0, 0) is the image's top-left corner: a 2 × 2 emissive texture on a quad seen from its front,
    +y up, shows red, green / blue, white in the image's quadrants, each at strength × Y(texel) nits (film Y is
    that over 683 lm/W · ∫ȳ dλ)."""
    import spectrace
    from spectrace.spectral.colorimetry import CIE_Y_INTEGRAL

    strength = 2.0e5
    texels = np.array([[[255, 0, 0], [0, 255, 0]], [[0, 0, 255], [255, 255, 255]]])
    gltf = Gltf()
    texture = gltf.image_texture(texels, sampler={"magFilter": 9728})
    material = gltf.material(
        emissiveTexture={"index": texture},
        emissiveFactor=[1, 1, 1],
        extensions={"KHR_materials_emissive_strength": {"emissiveStrength": strength}},
    )
    gltf.node(mesh=gltf.quad(material=material))
    ortho = gltf.camera(type="orthographic", orthographic={"xmag": 1.0, "ymag": 1.0, "znear": 0.0, "zfar": 10.0})
    gltf.node(camera=ortho, translation=[0, 0, 3])
    scene = load_gltf_scene(gltf.write(tmp_path / "sign.glb"), material_model="diffuse")
    image = spectrace.render(scene.with_overrides(width=8, height=8, spp=8, max_depth=1), device=device)
    luminance = np.array([[0.2126, 0.7152], [0.0722, 1.0]]) * strength / (683.0 * CIE_Y_INTEGRAL)
    for row in range(2):
        for column in range(2):
            values = image.xyz[4 * row : 4 * row + 4, 4 * column : 4 * column + 4, 1].ravel()
            standard_error = values.std(ddof=1) / math.sqrt(len(values))
            expected = luminance[row, column]
            assert abs(values.mean() - expected) <= 4.0 * standard_error + RELATIVE * expected, (row, column)
