"""Kernels built for one scene's features (kernels/scene_features.h) only leave out code for the materials, lights
and media that scene lacks, so they must render exactly the image of the kernels built for every scene: same
samples, same arithmetic, the same bits. A feature left out wrongly changes or zeroes what that feature contributes,
which a bit-for-bit comparison catches in every scene below."""

import tomllib
from dataclasses import replace

import numpy as np
import pytest

import spectrace
from rgl_tensor import ggx_file
from spectrace.engine.renderer import Renderer
from spectrace.engine.scene_buffers import build_scene_buffers
from spectrace.engine.scene_features import scene_feature_defines
from spectrace.materials import MATERIALS
from spectrace.resources import scenes_dir
from spectrace.scene import load_scene
from spectrace.scene.model import EnvironmentMap

# The type codes (materials: their order in spectrace.materials.MATERIALS; lights: in
# spectrace.lights.DEVICE_LIGHTS, the shapes' emitters first), written out here so the test does not
# read them from the code under test.
MATERIAL_BITS = {
    "diffuse": 1,
    "conductor": 2,
    "mirror": 4,
    "plastic": 8,
    "dielectric": 16,
    "retroreflector": 32,
    "thindielectric": 64,
    "diffusetransmission": 128,
    "principled": 256,
    "principledthin": 512,
    "polarizer": 1024,
    "retarder": 2048,
    "pplastic": 4096,
    "hair": 8192,
    "measured": 16384,
    "coatedconductor": 32768,
    "coateddiffuse": 65536,
    "mix": 131072,
    "fluorescent": 262144,
}
LIGHT_BITS = {
    "area": 1,
    "sphere": 2,
    "shape": 4,
    "point": 8,
    "spot": 16,
    "distant": 32,
    "environment": 64,
    "environment_map": 128,
}


def _bundled(name: str) -> spectrace.Scene:
    return load_scene(scenes_dir() / f"{name}.toml")


def _material_bits_named_in(name: str) -> int:
    """The material types a bundled scene's TOML names (every material table has a `type`)."""
    text = tomllib.loads((scenes_dir() / f"{name}.toml").read_text())
    types = {material["type"] for material in text.get("materials", {}).values()}
    return sum(MATERIAL_BITS[t] for t in types)


@pytest.mark.parametrize(
    "name", ["cornell_box", "material_showcase", "subsurface", "prism", "point_light_room", "teapot"]
)
def test_defines_name_the_materials_of_the_scene_file(name):
    defines = scene_feature_defines(build_scene_buffers(_bundled(name)))
    assert defines["SCENE_MATERIAL_TYPES"] == _material_bits_named_in(name)


def test_defines_of_the_cornell_box_and_of_a_scene_with_media_and_pictures():
    cornell = scene_feature_defines(build_scene_buffers(_bundled("cornell_box")))
    assert cornell == {
        "SCENE_MATERIAL_TYPES": MATERIAL_BITS["diffuse"],
        "SCENE_LIGHT_TYPES": LIGHT_BITS["area"],
        "SCENE_HAS_MEDIA": 0,
        "SCENE_HAS_GRID_MEDIA": 0,
        "SCENE_HAS_MEDIUM_EMISSION": 0,
        "SCENE_HAS_LIGHT_IMAGES": 0,
        "SCENE_HAS_SMOOTH_ENVIRONMENT_MAP": 0,
        "SCENE_HAS_BECKMANN": 0,
        "SCENE_HAS_NONLINEAR_PLASTIC": 0,
        "SCENE_HAS_ROUGH_COAT": 0,
        "SCENE_HAS_MIX": 0,
        "SCENE_HAS_FLUORESCENCE_MATRIX": 0,
        "SCENE_HAS_TEXTURES": 0,
        "SCENE_NEEDS_FOOTPRINT": 0,
        "SCENE_HAS_PROCEDURAL_TEXTURES": 0,
        "SCENE_HAS_SOLID_TEXTURES": 0,
        "SCENE_HAS_TEXTURE_MAPPINGS": 0,
        "SCENE_HAS_MESH_ATTRIBUTES": 0,
        "SCENE_HAS_DIRECTION_MIX": 0,
        "SCENE_HAS_SURFACE_NORMALS": 0,
        "SCENE_HAS_SHAPES": 0,
        "SCENE_HAS_PARTIAL_SHAPES": 0,
        "SCENE_HAS_CURVES": 0,
        "SCENE_HAS_CURVE_RIBBONS": 0,
        "SCENE_HAS_MITSUBA_CURVE_UV": 0,
        "SCENE_HAS_INSTANCES": 0,
        "SCENE_HAS_OPACITY": 0,
        "SCENE_HAS_ONE_SIDED": 0,
        "SCENE_HAS_TANGENT_FRAMES": 0,
        "SCENE_HAS_DIRECTION_TEXTURES": 0,
        "SCENE_HAS_NORMAL_MAP_HANDEDNESS": 0,
        "SCENE_HAS_FILE_TANGENTS": 0,
        "SCENE_HIDES_AREA_EMITTERS": 0,
        "SCENE_HAS_SDF_GRIDS": 0,
    }
    subsurface = scene_feature_defines(build_scene_buffers(_bundled("subsurface")))
    assert subsurface["SCENE_HAS_MEDIA"] == 1 and subsurface["SCENE_HAS_GRID_MEDIA"] == 0
    assert scene_feature_defines(build_scene_buffers(_grid_medium_scene()))["SCENE_HAS_GRID_MEDIA"] == 1
    analytic = scene_feature_defines(build_scene_buffers(_analytic_shapes_scene()))
    assert analytic["SCENE_HAS_SHAPES"] == 1 and analytic["SCENE_HAS_PARTIAL_SHAPES"] == 0
    assert scene_feature_defines(build_scene_buffers(_partial_shapes_scene()))["SCENE_HAS_PARTIAL_SHAPES"] == 1
    assert analytic["SCENE_HAS_SDF_GRIDS"] == 0
    # The grids' samples follow the shape rows: only the rows themselves say what the scene has.
    sdf = scene_feature_defines(build_scene_buffers(_sdf_grid_scene()))
    assert sdf["SCENE_HAS_SDF_GRIDS"] == 1 and sdf["SCENE_HAS_PARTIAL_SHAPES"] == 0
    assert analytic["SCENE_HAS_CURVES"] == 0
    curves = scene_feature_defines(build_scene_buffers(_curves_scene()))
    assert curves["SCENE_HAS_CURVES"] == 1 and curves["SCENE_HAS_MITSUBA_CURVE_UV"] == 0
    assert curves["SCENE_HAS_CURVE_RIBBONS"] == 0
    assert scene_feature_defines(build_scene_buffers(_strip_curves_scene()))["SCENE_HAS_CURVE_RIBBONS"] == 1
    assert scene_feature_defines(build_scene_buffers(_curves_scene("mitsuba")))["SCENE_HAS_MITSUBA_CURVE_UV"] == 1
    assert analytic["SCENE_LIGHT_TYPES"] == LIGHT_BITS["sphere"] | LIGHT_BITS["shape"]
    lights = scene_feature_defines(build_scene_buffers(_environment_map_scene()))
    assert lights["SCENE_LIGHT_TYPES"] == LIGHT_BITS["environment_map"] and lights["SCENE_HAS_LIGHT_IMAGES"] == 1
    assert lights["SCENE_HAS_TEXTURES"] == 0
    textured = replace(
        _environment_map_scene(),
        shapes=[spectrace.shape("rectangle", spectrace.diffuse(spectrace.bitmap(np.full((2, 2), 0.5))))],
    )
    assert scene_feature_defines(build_scene_buffers(textured))["SCENE_HAS_TEXTURES"] == 1
    assert scene_feature_defines(build_scene_buffers(textured))["SCENE_HAS_PROCEDURAL_TEXTURES"] == 0
    dotted = replace(textured, shapes=[spectrace.shape("rectangle", spectrace.diffuse(spectrace.dots_texture()))])
    assert scene_feature_defines(build_scene_buffers(dotted))["SCENE_HAS_PROCEDURAL_TEXTURES"] == 1
    assert scene_feature_defines(build_scene_buffers(dotted))["SCENE_HAS_SOLID_TEXTURES"] == 0
    solid = replace(textured, shapes=[spectrace.shape("rectangle", spectrace.diffuse(spectrace.marble_texture()))])
    assert scene_feature_defines(build_scene_buffers(solid))["SCENE_HAS_SOLID_TEXTURES"] == 1
    assert scene_feature_defines(build_scene_buffers(solid))["SCENE_HAS_DIRECTION_MIX"] == 0
    assert scene_feature_defines(build_scene_buffers(_direction_mix_scene()))["SCENE_HAS_DIRECTION_MIX"] == 1
    detailed = scene_feature_defines(build_scene_buffers(_surface_detail_scene()))
    assert detailed["SCENE_HAS_SURFACE_NORMALS"] == 1 and detailed["SCENE_HAS_OPACITY"] == 1
    for material, normals, opacity in (
        (spectrace.diffuse(0.5, bump_map=spectrace.bitmap(np.full((2, 2), 0.5))), 1, 0),
        (spectrace.diffuse(0.5, opacity=spectrace.checkerboard(0.0, 1.0)), 0, 1),
        (spectrace.diffuse(0.5, opacity=1.0), 0, 0),
    ):
        scene = replace(_environment_map_scene(), shapes=[spectrace.shape("rectangle", material)])
        defines = scene_feature_defines(build_scene_buffers(scene))
        assert (defines["SCENE_HAS_SURFACE_NORMALS"], defines["SCENE_HAS_OPACITY"]) == (normals, opacity)
    # A mix: its own type bit and those of its materials (rows of their own), and SCENE_HAS_MIX.
    mixed = spectrace.mix((spectrace.diffuse(0.5), spectrace.conductor(metal="Au")), 0.3)
    scene = replace(_environment_map_scene(), shapes=[spectrace.shape("rectangle", mixed)])
    defines = scene_feature_defines(build_scene_buffers(scene))
    assert defines["SCENE_HAS_MIX"] == 1
    mixed_types = MATERIAL_BITS["mix"] | MATERIAL_BITS["diffuse"] | MATERIAL_BITS["conductor"]
    assert defines["SCENE_MATERIAL_TYPES"] == mixed_types
    for two_sided in (True, False):
        scene = replace(
            _environment_map_scene(), shapes=[spectrace.shape("rectangle", spectrace.diffuse(0.5, two_sided=two_sided))]
        )
        assert scene_feature_defines(build_scene_buffers(scene))["SCENE_HAS_ONE_SIDED"] == int(not two_sided)
    # Only an anisotropic lobe asks for the frame along dp/du: a weight above 0, or a texture of it above 0 somewhere.
    for material, tangent_frames in (
        (spectrace.principled(0.5, roughness=0.4, metallic=1.0), 0),
        (spectrace.principled(0.5, roughness=0.4, metallic=1.0, anisotropic=0.5), 1),
        (spectrace.principled(0.5, anisotropic=spectrace.bitmap(np.array([[0.0, 0.7]]))), 1),
        (spectrace.principled(0.5, anisotropic=spectrace.bitmap(np.zeros((1, 2)))), 0),
        (spectrace.principledthin(0.5, roughness=0.4, anisotropic=0.9), 1),
        (spectrace.principledthin(0.5, roughness=0.4), 0),
        (spectrace.conductor("Au", roughness=0.2, roughness_v=0.5), 1),
        (spectrace.conductor("Au", roughness=0.2, roughness_v=0.2), 0),
        (spectrace.conductor("Au", roughness=0.2), 0),
    ):
        scene = replace(_environment_map_scene(), shapes=[spectrace.shape("rectangle", material)])
        buffers = build_scene_buffers(scene)
        assert scene_feature_defines(buffers)["SCENE_HAS_TANGENT_FRAMES"] == tangent_frames, material
        principled_codes = [MATERIALS.codes[n] for n in ("principled", "principledthin", "conductor")]
        rows = buffers.materials[np.isin(buffers.materials["type"], principled_codes)]
        assert list(rows["tangent_frame"]) == [tangent_frames], material
    # A direction texture turns only an anisotropic principled lobe; it is a texture the vertices must look up.
    direction = spectrace.bitmap(np.array([[[1.0, 0.5, 1.0], [0.5, 1.0, 1.0]]]))
    for material, turned in (
        (spectrace.principled(0.5, anisotropic=0.5, anisotropic_direction=direction), 1),
        (spectrace.principled(0.5, anisotropic_direction=direction), 0),
        (spectrace.principled(0.5, anisotropic=0.5), 0),
    ):
        scene = replace(_environment_map_scene(), shapes=[spectrace.shape("rectangle", material)])
        defines = scene_feature_defines(build_scene_buffers(scene))
        assert defines["SCENE_HAS_DIRECTION_TEXTURES"] == turned, material
        assert defines["SCENE_HAS_TEXTURES"] == turned, material


def test_beckmann_lobes_and_nonlinear_plastics_are_features():
    """Only a Beckmann lobe compiles Beckmann's code in, only a nonlinear plastic the albedo's remapping, only a
    rough coat with its own transmission (not a smooth one: its transmission is the smooth interface's) the table
    lookups."""
    for material, expected in (
        (spectrace.conductor("Au", roughness=0.3), (0, 0, 0)),
        (spectrace.conductor("Au", roughness=0.3, distribution="beckmann"), (1, 0, 0)),
        (spectrace.dielectric(1.5, roughness=0.3, distribution="beckmann"), (1, 0, 0)),
        (spectrace.plastic(0.5, roughness=0.2, distribution="beckmann", nonlinear=True), (1, 1, 0)),
        (spectrace.plastic(0.5, nonlinear=True), (0, 1, 0)),
        (spectrace.plastic(0.5, roughness=0.2, coat_transmission="rough"), (0, 0, 1)),
        (spectrace.plastic(0.5, coat_transmission="rough"), (0, 0, 0)),
    ):
        scene = replace(_environment_map_scene(), shapes=[spectrace.shape("rectangle", material)])
        defines = scene_feature_defines(build_scene_buffers(scene))
        names = ("SCENE_HAS_BECKMANN", "SCENE_HAS_NONLINEAR_PLASTIC", "SCENE_HAS_ROUGH_COAT")
        assert tuple(defines[name] for name in names) == expected, material


def test_the_footprint_is_computed_only_for_the_lookups_that_read_it():
    """Trilinear filtering chooses its level by the footprint and a checkerboard bump map steps by it; nearest and
    bilinear lookups, a trilinear one on a 1 x 1 image (no pyramid), and a bitmap bump map's exact gradient (of a
    nearest or bilinear lookup) never read it."""
    image = np.full((4, 4), 0.5)
    for reflectance, bump_map, needs in (
        (spectrace.bitmap(image, filter="nearest"), None, 0),
        (spectrace.bitmap(image, filter="bilinear"), None, 0),
        (spectrace.bitmap(np.full((1, 1), 0.5), filter="trilinear"), None, 0),
        (spectrace.bitmap(image, filter="trilinear"), None, 1),
        (spectrace.checkerboard(0.2, spectrace.bitmap(image, filter="trilinear")), None, 1),
        (0.5, spectrace.bitmap(image), 0),
        (0.5, spectrace.bitmap(image, filter="nearest"), 0),
        (0.5, spectrace.bitmap(image, filter="trilinear"), 1),
        (0.5, spectrace.checkerboard(0.2, 0.7), 1),
    ):
        material = spectrace.diffuse(reflectance, bump_map=bump_map)
        scene = replace(_environment_map_scene(), shapes=[spectrace.shape("rectangle", material)])
        assert scene_feature_defines(build_scene_buffers(scene))["SCENE_NEEDS_FOOTPRINT"] == needs


def _environment_map_scene() -> spectrace.Scene:
    rgb = np.random.default_rng(5).uniform(0.0, 1.0, (8, 16, 3)).astype(np.float32)
    ground = spectrace.shape(
        "rectangle",
        spectrace.plastic((0.6, 0.5, 0.3)),
        transform=[{"rotate": {"axis": [1, 0, 0], "angle": -90}}, {"scale": 2}],
    )
    return spectrace.Scene(
        camera=spectrace.Camera(origin=(0.0, 1.0, -3.0), target=(0.0, 0.0, 0.0)),
        shapes=[ground],
        lights=[EnvironmentMap(rgb, 1.0)],
        width=16,
        height=16,
        spp=4,
    )


def _distant_and_spot_scene() -> spectrace.Scene:
    ground = spectrace.shape(
        "rectangle",
        spectrace.conductor("Au", roughness=0.3),
        transform=[{"rotate": {"axis": [1, 0, 0], "angle": -90}}, {"scale": 2}],
    )
    lights = [
        spectrace.distant_light((0.3, -1.0, 0.2), irradiance=2.0),
        spectrace.spot_light((0.0, 2.0, 0.0), (0.0, 0.0, 0.0), cutoff_angle=40.0, power_w=20.0),
    ]
    return spectrace.Scene(
        camera=spectrace.Camera(origin=(0.0, 1.0, -3.0), target=(0.0, 0.0, 0.0)),
        shapes=[ground],
        lights=lights,
        width=16,
        height=16,
        spp=4,
    )


def _surface_detail_scene(cut_out: bool = True) -> spectrace.Scene:
    """A normal-mapped plastic floor and a bump-mapped sheet, lit by an area light; the sheet a cut-out unless
    `cut_out` is False."""
    normals = np.random.default_rng(3).uniform(0.2, 0.8, (4, 4, 3))
    normals[..., 2] = 1.0
    floor = spectrace.shape("rectangle", spectrace.plastic(0.5, normal_map=spectrace.bitmap(normals)))
    bumps = spectrace.bitmap(np.random.default_rng(4).uniform(0.0, 1.0, (4, 4)))
    sheet = spectrace.shape(
        "rectangle",
        spectrace.diffuse(0.7, bump_map=bumps, bump_scale=0.05, opacity=0.4 if cut_out else 1.0),
        transform=[{"scale": 0.6}, {"translate": [0, 0, 0.5]}],
    )
    light = spectrace.shape(
        "rectangle",
        spectrace.diffuse(0.0),
        emitter=spectrace.area_emitter(5.0),
        transform=[{"scale": 0.3}, {"rotate": {"axis": [1, 0, 0], "angle": 180}}, {"translate": [0, 0, 1.5]}],
    )
    return spectrace.Scene(
        camera=spectrace.Camera(origin=(0.0, -2.0, 2.0), target=(0.0, 0.0, 0.0)),
        shapes=[floor, sheet, light],
        width=16,
        height=16,
        spp=4,
    )


def _anisotropic_scene() -> spectrace.Scene:
    """The analytic shapes' scene with its glass sphere and its floor of anisotropic principled metal."""
    base = _analytic_shapes_scene()
    metal = spectrace.principled(0.8, roughness=0.4, metallic=1.0, anisotropic=0.9)
    sphere = replace(base.shapes[1], material=metal)
    floor = spectrace.shape("rectangle", metal, transform=[{"rotate": {"axis": [0, 0, 1], "angle": 30}}, {"scale": 3}])
    return replace(base, shapes=[floor, sphere, *base.shapes[2:]])


def _anisotropic_conductor_scene() -> spectrace.Scene:
    """The anisotropic scene with conductors: a GGX sphere and a floor of Beckmann metal, each stretched along its
    dp/du."""
    base = _anisotropic_scene()
    sphere = replace(base.shapes[1], material=spectrace.conductor("Au", roughness=0.05, roughness_v=0.4))
    floor = replace(
        base.shapes[0], material=spectrace.conductor("Al", roughness=0.3, roughness_v=0.08, distribution="beckmann")
    )
    return replace(base, shapes=[floor, sphere, *base.shapes[2:]])


def _measured_scene() -> spectrace.Scene:
    """The anisotropic scene with a measured sphere and floor (a GGX measurement, tests/rgl_tensor.py)."""
    base = _anisotropic_scene()
    measured = spectrace.measured(ggx_file(0.3))
    shapes = [replace(shape, material=measured) for shape in base.shapes[:2]]
    return replace(base, shapes=[*shapes, *base.shapes[2:]])


def _textured_weights_scene() -> spectrace.Scene:
    """The anisotropic scene with principled and principledthin materials of plain base colours whose weights are
    textured: textures kept in the materials' own parameter blocks, named by no row field (Mitsuba's textured
    principled test scenes)."""
    base = _anisotropic_scene()
    rng = np.random.default_rng(11)

    def weight():
        return spectrace.bitmap(rng.uniform(0.0, 1.0, (4, 4)))

    diff_trans = spectrace.bitmap(rng.uniform(0.0, 2.0, (4, 4)))
    sheet = spectrace.principledthin((0.7, 0.1, 0.1), anisotropic=weight(), spec_trans=weight(), diff_trans=diff_trans)
    metal = spectrace.principled(0.8, roughness=weight(), metallic=weight(), anisotropic=0.5)
    sphere = replace(base.shapes[1], material=sheet)
    # Without the textured can, whose texture would keep the uvs in anyway.
    return replace(base, shapes=[replace(base.shapes[0], material=metal), sphere, *base.shapes[3:]])


def _grid_medium_scene() -> spectrace.Scene:
    """A scattering cube of a random density grid beside a homogeneous sphere, under a lamp."""
    density = np.random.default_rng(4).uniform(0.0, 3.0, (4, 5, 6))
    grid = spectrace.density_grid(density, box=((-1, -1, -1), (1, 1, 1)))
    cloud = spectrace.shape("cube", interior=spectrace.medium(sigma_a=0.2, sigma_s=(0.5, 1.0, 2.0), density=grid))
    milk = spectrace.shape(
        "sphere",
        interior=spectrace.medium(preset="wholemilk", scale=2.0),
        transform=[{"scale": 0.5}, {"translate": [1.6, 0, 0]}],
    )
    lamp = spectrace.shape(
        "rectangle",
        spectrace.diffuse(0.0),
        emitter=spectrace.area_emitter(5.0),
        transform=[{"rotate": {"axis": [1, 0, 0], "angle": 90}}, {"translate": [0, 3, 0]}],
    )
    return spectrace.Scene(
        camera=spectrace.Camera((0.5, 1.0, -5.0), (0.5, 0.0, 0.0)),
        width=16,
        height=16,
        shapes=[cloud, milk, lamp],
        lights=[spectrace.constant_environment(0.1)],
    )


def _sdf_grid_scene() -> spectrace.Scene:
    """The analytic shapes' scene with a lumpy SDF grid (kernels/shape_sdf_grid.cl) placed directly and instanced."""
    x = np.linspace(0.0, 1.0, 12)
    z, y, x = np.meshgrid(x, x, x, indexing="ij")
    values = np.sqrt((x - 0.5) ** 2 + (y - 0.5) ** 2 + (z - 0.5) ** 2) - 0.35 - 0.05 * np.sin(13 * x) * np.cos(9 * y)
    base = _analytic_shapes_scene()
    grid = spectrace.sdf_grid(values, spectrace.diffuse(0.6), transform=[{"translate": [-1.2, -0.5, 0.0]}])
    obj = spectrace.instanced_object([spectrace.sdf_grid(values, spectrace.diffuse(0.3), normals="analytic")])
    return replace(
        base, shapes=[*base.shapes, grid], instances=[spectrace.instance(obj, [{"translate": [0.4, -0.6, 0.1]}])]
    )


def _partial_shapes_scene() -> spectrace.Scene:
    """A cut sphere light over an annulus-sector floor and a cut cylinder (kernels/shape_partial.cl)."""
    floor = spectrace.shape("disk", spectrace.diffuse(0.6), transform=[{"scale": 3}], inner_radius=0.2, phi_max=300)
    can = spectrace.shape("cylinder", spectrace.diffuse(0.4), transform=[{"scale": [0.5, 0.5, 1.0]}], phi_max=200)
    bulb = spectrace.shape(
        "sphere",
        spectrace.diffuse(0.0),
        emitter=spectrace.area_emitter(20.0),
        center=(0, 0, 3),
        radius=1.0,
        z_min=-0.8,
        z_max=0.5,
        phi_max=270,
    )
    camera = spectrace.Camera(origin=(0, -5, 3), target=(0, 0, 0.5), up=(0, 0, 1))
    return spectrace.Scene(camera=camera, width=16, height=16, shapes=[floor, can, bulb])


def _curves_scene(uv_convention: str = "pbrt") -> spectrace.Scene:
    """Hair (B-spline curves of the hair BSDF) and a diffuse wire (a linear curve) over a floor, under a sphere light
    (kernels/shape_curve.cl); the curves' texture coordinates pbrt-v4's or Mitsuba 3's (h then from the geometry)."""
    rng = np.random.default_rng(5)
    roots = rng.uniform(-0.8, 0.8, (12, 2))
    strands = [
        np.array([[x + 0.1 * k * np.sin(k + x), y, 0.15 * k, 0.03 - 0.004 * k] for k in range(5)]) for x, y in roots
    ]
    hair = spectrace.curve(
        strands, spectrace.hair(eumelanin=0.8), basis="bspline", name="hair", uv_convention=uv_convention
    )
    wire_points = [[-1.5, -1.0, 0.2, 0.05], [0.0, -0.6, 0.5, 0.08], [1.5, -1.0, 0.2, 0.05]]
    wire = spectrace.curve(wire_points, spectrace.diffuse(0.7))
    floor = spectrace.shape("rectangle", spectrace.diffuse(0.5), transform=[{"scale": 3}])
    bulb = spectrace.shape("sphere", spectrace.diffuse(0.0), emitter=spectrace.area_emitter(20.0), center=(1, -1, 3))
    camera = spectrace.Camera(origin=(0, -4, 2), target=(0, 0, 0.4), up=(0, 0, 1))
    return spectrace.Scene(camera=camera, width=16, height=16, shapes=[hair, wire, floor, bulb])


def _strip_curves_scene() -> spectrace.Scene:
    """The curves scene with pbrt-v4's strips: hair as flat curves, the wire a twisting ribbon
    (kernels/curve_ribbon.cl)."""
    scene = _curves_scene()
    hair, wire, *rest = scene.shapes
    strands = [[-0.5, 0.0, 0.0, 0.03], [0.0, 0.1, 0.6, 0.03], [0.4, 0.0, 1.0, 0.03]]
    flat = spectrace.curve(strands, spectrace.hair(eumelanin=0.8), curve_type="flat", name="flat hair")
    normals = [[0.0, 1.0, 0.0], [0.0, 0.6, 0.8], [0.0, 0.0, 1.0]]
    points = [[-1.5, -1.0, 0.2, 0.15], [0.0, -0.6, 0.5, 0.2], [1.5, -1.0, 0.2, 0.15]]
    ribbon = spectrace.curve(points, spectrace.diffuse(0.7), curve_type="ribbon", curve_normals=normals)
    return replace(scene, shapes=[flat, ribbon, *rest])


def _equal_area_scene() -> spectrace.Scene:
    """A goniometric light over a floor, seen by the equal-area camera."""
    floor = spectrace.shape("rectangle", spectrace.diffuse(0.6), transform=[{"scale": 3}])
    image = np.random.default_rng(3).uniform(0.2, 2.0, (4, 4))
    lamp = spectrace.goniometric_light((0.2, 0.1, 1.0), intensity=3.0, image=image, up=(0, 0, -1), front=(1, 0, 0))
    camera = spectrace.Camera(origin=(0, 0, 0.5), target=(0, 0, 0), up=(0, 1, 0), type="equalarea")
    return spectrace.Scene(camera=camera, width=16, height=16, shapes=[floor], lights=[lamp])


def _analytic_shapes_scene() -> spectrace.Scene:
    """An analytic sphere light and a disk light over a bump-mapped disk floor, a glass sphere and a textured
    cylinder."""
    rng = np.random.default_rng(8)
    floor = spectrace.shape(
        "disk", spectrace.plastic(0.5, bump_map=spectrace.bitmap(rng.uniform(0, 1, (4, 4)))), transform=[{"scale": 3}]
    )
    glass = spectrace.shape("sphere", spectrace.dielectric(1.5), transform=[{"scale": 0.4}, {"translate": [0, 0, 0.4]}])
    can = spectrace.shape(
        "cylinder",
        spectrace.diffuse(spectrace.bitmap(rng.uniform(0, 1, (4, 4, 3)))),
        transform=[{"scale": [0.3, 0.5, 0.8]}, {"translate": [0.8, 0.2, 0]}],
    )
    bulb = spectrace.shape(
        "sphere", spectrace.diffuse(0.0), emitter=spectrace.area_emitter(20.0), transform=[{"translate": [0, 0, 8]}]
    )
    panel = spectrace.shape(
        "disk",
        spectrace.diffuse(0.0),
        emitter=spectrace.area_emitter(3.0),
        transform=[{"scale": [0.5, 0.3, 1]}, {"rotate": {"axis": [0, 1, 0], "angle": -120}}, {"translate": [2, 0, 1]}],
    )
    return spectrace.Scene(
        camera=spectrace.Camera(origin=(0.0, -3.0, 2.0), target=(0.0, 0.0, 0.3)),
        shapes=[floor, glass, can, bulb, panel],
        width=16,
        height=16,
        spp=4,
    )


def _textured_scene(filters: tuple[str, ...]) -> spectrace.Scene:
    """Rectangles textured with random colours, one per filter, in the environment map's light."""
    rng = np.random.default_rng(6)
    shapes = [
        spectrace.shape(
            "rectangle",
            spectrace.diffuse(spectrace.bitmap(rng.uniform(0.0, 1.0, (8, 8, 3)), filter=f, uv_scale=3)),
            transform=[{"rotate": {"axis": [1, 0, 0], "angle": -90}}, {"translate": [1.0 * i - 0.5, 0.1 * i, 0]}],
        )
        for i, f in enumerate(filters)
    ]
    return replace(_environment_map_scene(), shapes=shapes)


def _beckmann_scene() -> spectrace.Scene:
    """Rough Beckmann gold, glass and nonlinear plastic, a plastic with a rough coat's own transmission, beside GGX
    ones, in the environment map's light."""
    materials = [
        spectrace.conductor("Au", roughness=0.3, distribution="beckmann"),
        spectrace.dielectric(1.5, roughness=0.2, distribution="beckmann"),
        spectrace.plastic((0.6, 0.2, 0.1), roughness=0.2, distribution="beckmann", nonlinear=True),
        spectrace.plastic((0.1, 0.3, 0.6), roughness=0.3, coat_transmission="rough"),
        spectrace.conductor("Cu", roughness=0.3),
    ]
    shapes = [
        spectrace.shape("sphere", material, transform=[{"scale": 0.35}, {"translate": [0.75 * i - 1.5, 0.4, 0]}])
        for i, material in enumerate(materials)
    ]
    return replace(_environment_map_scene(), shapes=shapes)


def _with_camera(scene: spectrace.Scene, camera_type: str, filter_type: str) -> spectrace.Scene:
    """The scene through another camera type and pixel filter, framing about what its perspective camera framed."""
    camera = scene.camera
    distance = float(np.linalg.norm(np.subtract(camera.target, camera.origin)))
    changes = {
        "thinlens": {"aperture_radius": 0.05 * distance, "focus_distance": distance},
        "orthographic": {"view_width": 2.0 * distance * np.tan(np.radians(camera.fov_degrees) / 2.0)},
        "equirectangular": {},
    }[camera_type]
    camera = replace(camera, type=camera_type, **changes)
    return replace(scene, camera=camera, pixel_filter=spectrace.PixelFilter(filter_type))


def _instanced_scene() -> spectrace.Scene:
    """A textured, bump-mapped, smooth-shaded object placed three times (one mirrored) under an area light."""
    rng = np.random.default_rng(9)
    ball = spectrace.shape(
        "sphere", spectrace.plastic(0.5, bump_map=spectrace.bitmap(rng.uniform(0, 1, (4, 4)))), tessellated=True
    )
    box = spectrace.shape(
        "cube",
        spectrace.diffuse(spectrace.bitmap(rng.uniform(0, 1, (4, 4, 3)))),
        transform=[{"scale": 0.3}, {"translate": [1.0, 0, 0]}],
    )
    obj = spectrace.instanced_object([ball, box])
    placements = [
        [{"scale": 0.5}, {"translate": [-1, 0, 0.5]}],
        [{"scale": [0.6, 0.3, 0.5]}, {"rotate": {"axis": [0, 0, 1], "angle": 60}}, {"translate": [0.8, 0.3, 0.5]}],
        [{"matrix": [[-0.4, 0, 0, 0], [0, 0.4, 0, 0], [0, 0, 0.4, 0], [0, 0, 0, 1]]}, {"translate": [0, -0.8, 0.4]}],
    ]
    base = _surface_detail_scene(cut_out=False)
    return replace(
        base, shapes=[base.shapes[0], base.shapes[2]], instances=[spectrace.instance(obj, p) for p in placements]
    )


def _mesh_attribute_scene():
    """The cornell box's tall block wearing random vertex colours, blended by face weights with a rough conductor."""
    base = _bundled("cornell_box")
    block = base.shapes[-1]
    rng = np.random.default_rng(4)
    mesh = replace(
        block.mesh,
        attributes={
            "vertex_color": rng.random((len(block.mesh.vertices), 3)),
            "face_w": rng.random(len(block.mesh.faces)),
        },
    )
    material = spectrace.mix(
        [spectrace.diffuse(spectrace.mesh_attribute("vertex_color")), spectrace.conductor("Cu", roughness=0.2)],
        spectrace.mesh_attribute("face_w"),
    )
    return replace(base, shapes=[*base.shapes[:-1], replace(block, mesh=mesh, material=material)])


def _direction_mix_scene():
    """The cornell box's white surfaces in a directionmix of two reflectances (walls, floor and blocks face dir at
    different angles), and a sphere of a coated conductor whose metal's roughness is a checkerboard."""
    base = _bundled("cornell_box")
    mixed = spectrace.diffuse(spectrace.directionmix_texture((0.8, 0.3, 0.1), 0.4, dir=(1.0, 1.0, 0.5)))
    coated = spectrace.coatedconductor("Au", conductor_roughness=spectrace.checkerboard(0.05, 0.4), roughness=0.1)
    sphere = spectrace.shape("sphere", coated, transform=[{"scale": 90.0}, {"translate": [380.0, 90.0, 200.0]}])
    return replace(base, shapes=[replace(base.shapes[0], material=mixed), *base.shapes[1:], sphere])


SCENES = {
    "mesh_attributes": _mesh_attribute_scene,
    "direction_mix": _direction_mix_scene,
    "thin_lens_and_gaussian": lambda: _with_camera(_bundled("cornell_box"), "thinlens", "gaussian"),
    "orthographic_trilinear_and_mitchell": lambda: _with_camera(
        _textured_scene(("trilinear",)), "orthographic", "mitchell"
    ),
    "equirectangular_and_tent": lambda: _with_camera(_environment_map_scene(), "equirectangular", "tent"),
    "cornell_box": lambda: _bundled("cornell_box"),
    "material_showcase": lambda: _bundled("material_showcase"),
    "subsurface": lambda: _bundled("subsurface").with_overrides(max_depth=16),
    "prism": lambda: _bundled("prism"),
    "point_light_room": lambda: _bundled("point_light_room"),
    "environment_map": _environment_map_scene,
    "distant_and_spot": _distant_and_spot_scene,
    "normal_and_bump_maps": lambda: _surface_detail_scene(cut_out=False),
    "normal_and_bump_maps_and_cut_out": _surface_detail_scene,
    # The scene's kernels leave the footprint out (0), the general ones compute it: the same bits say no nearest or
    # bilinear lookup reads it.
    "nearest_and_bilinear_textures": lambda: _textured_scene(("nearest", "bilinear")),
    "trilinear_texture": lambda: _textured_scene(("trilinear",)),
    "beckmann_and_nonlinear_plastic": _beckmann_scene,
    "analytic_shapes": _analytic_shapes_scene,
    "partial_shapes": _partial_shapes_scene,
    "sdf_grids": _sdf_grid_scene,
    "curves": _curves_scene,
    "mitsuba_curves": lambda: _curves_scene("mitsuba"),
    "strip_curves": _strip_curves_scene,
    "equal_area_camera_and_goniometric_light": _equal_area_scene,
    "grid_medium": _grid_medium_scene,
    # Camera rays pass through the area light (hide_emitters): the general kernels test the flag at run time.
    "hidden_area_light": lambda: replace(_bundled("cornell_box"), hide_emitters=True),
    "instances": _instanced_scene,
    # Frames along dp/du: the anisotropic sphere's and rectangle's (an analytic shape, triangles with UVs).
    "anisotropic_principled": _anisotropic_scene,
    "anisotropic_conductor": _anisotropic_conductor_scene,
    "measured": _measured_scene,
    # Textures that only the materials' parameter blocks name (their weights'): the scene's kernels look them up.
    "textured_principled_weights": _textured_weights_scene,
}


@pytest.mark.slow
@pytest.mark.parametrize("name", SCENES)
@pytest.mark.parametrize("integrator", ["path", "direct"])
def test_scene_kernels_render_the_general_kernels_image_bit_for_bit(device, name, integrator):
    scene = SCENES[name]().with_overrides(width=16, height=16, spp=4, integrator=integrator)
    specialised = Renderer(scene, device, specialise=True).render().xyz
    general = Renderer(scene, device, specialise=False).render().xyz
    assert np.all(np.isfinite(specialised)) and specialised[..., 1].mean() > 0
    assert np.array_equal(specialised.view(np.uint32), general.view(np.uint32))


@pytest.mark.slow
@pytest.mark.parametrize(
    "name",
    [
        "cornell_box",
        "prism",
        "environment_map",
        "distant_and_spot",
        "trilinear_texture",
        "analytic_shapes",
        "partial_shapes",
        "sdf_grids",
        "curves",
        "equal_area_camera_and_goniometric_light",
        "anisotropic_principled",
        "anisotropic_conductor",
        "measured",
        "textured_principled_weights",
        "direction_mix",
    ],
)
def test_light_tracer_scene_kernels_render_the_general_kernels_image_bit_for_bit(device, name):
    """The same for the light tracer (which refuses media, so no subsurface scene)."""
    scene = SCENES[name]().with_overrides(width=16, height=16, spp=4, integrator="light")
    specialised = Renderer(scene, device, specialise=True).render().xyz
    general = Renderer(scene, device, specialise=False).render().xyz
    assert np.all(np.isfinite(specialised)) and specialised[..., 1].mean() > 0
    assert np.array_equal(specialised.view(np.uint32), general.view(np.uint32))


@pytest.mark.parametrize(("value", "specialised"), [("1", False), ("0", True), ("", True)])
def test_the_environment_picks_general_or_scene_kernels_and_an_argument_wins(device, monkeypatch, value, specialised):
    scene = _bundled("cornell_box").with_overrides(width=4, height=4, spp=1)
    monkeypatch.setenv("SPECTRACE_GENERAL_KERNELS", value)
    assert Renderer(scene, device).specialised is specialised
    assert Renderer(scene, device, specialise=not specialised).specialised is (not specialised)


@pytest.mark.subprocess
@pytest.mark.slow
def test_a_bad_general_kernels_setting_is_one_line_naming_the_variable(tmp_path, monkeypatch):
    from cli_runner import render_cornell_box, run_spectrace

    out = tmp_path / "box.png"
    out.write_bytes(b"kept")
    monkeypatch.setenv("SPECTRACE_GENERAL_KERNELS", "yes")
    result = run_spectrace(*render_cornell_box(out, spp=1, width=4, height=4))
    assert result.returncode != 0
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and "SPECTRACE_GENERAL_KERNELS" in lines[0] and "Traceback" not in result.stderr
    assert out.read_bytes() == b"kept"
