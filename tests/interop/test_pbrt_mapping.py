"""Every material and light module maps pbrt-v4 or says why it does not: its PBRT_MATERIALS or PBRT_LIGHTS (with
`from_pbrt`) or PBRT_NONE, so a new module cannot silently lack a mapping. Each declared pbrt material and light
imports with pbrt-v4's defaults into a scene that loads as that module's, and the importer's list of what it takes
(its refusals, the command's help) is the modules' declarations."""

import re

import numpy as np
import pytest

from plugin_mappings import assert_declares_mapping
from rgl_tensor import ggx_file
from spectrace.cameras import CAMERAS
from spectrace.errors import SpectraceError
from spectrace.integrators import INTEGRATORS
from spectrace.interop.pbrt import load_pbrt_scene, pbrt_scene_data
from spectrace.io.exr import write_exr
from spectrace.lights import LIGHTS, area, envmap, projector
from spectrace.materials import MATERIALS
from spectrace.pixel_filters import PIXEL_FILTERS
from spectrace.resources import scenes_dir
from spectrace.textures import TEXTURES

MODULES = list(MATERIALS.values())
LIGHT_MODULES = [*LIGHTS.values(), area]
CAMERA = """LookAt 0 0 5  0 0 0  0 1 0
Camera "perspective" "float fov" 30
Film "rgb" "integer xresolution" 8 "integer yresolution" 6
WorldBegin
"""
HEADER = CAMERA + 'LightSource "infinite" "rgb L" [1 1 1]\n'
QUAD = 'Shape "trianglemesh" "point3 P" [-1 -1 0  1 -1 0  1 1 0  -1 1 0] "integer indices" [0 1 2  0 2 3]\n'
# pbrt's mix names two materials; of two different kinds, so that it stays a mix (two diffuse ones blend).
_MIX_PARTS = (
    'MakeNamedMaterial "first" "string type" "diffuse"\n'
    'MakeNamedMaterial "second" "string type" "conductor"\n'
    'Material "mix" "string materials" ["first" "second"]\n'
)


def _declared(modules, names: str = "PBRT_MATERIALS") -> list[tuple[str, object]]:
    return [(kind, module) for module in modules for kind in getattr(module, names)]


_LIGHTS = _declared(LIGHT_MODULES, "PBRT_LIGHTS")


@pytest.mark.parametrize("module", MODULES, ids=[m.NAME for m in MODULES])
def test_every_material_declares_its_pbrt_materials_or_why_it_has_none(module):
    assert_declares_mapping(module, "PBRT_MATERIALS", "from_pbrt", "PBRT_NONE")


def test_no_pbrt_material_is_claimed_twice():
    kinds = [kind for kind, _ in _declared(MODULES)]
    assert len(kinds) == len(set(kinds)), kinds


@pytest.mark.parametrize("kind, module", _declared(MODULES), ids=[k for k, _ in _declared(MODULES)])
def test_each_declared_pbrt_material_imports_with_pbrts_defaults_as_its_module(tmp_path, kind, module):
    path = tmp_path / "scene.pbrt"
    material = _MIX_PARTS if kind == "mix" else f'Material "{kind}"\n'
    if kind == "measured":  # no default file, in pbrt either: one written from GGX (tests/rgl_tensor.py)
        material = f'Material "measured" "string filename" "{ggx_file(0.3)}"\n'
    path.write_text(HEADER + material + QUAD)
    (shape,) = load_pbrt_scene(path).shapes
    assert isinstance(shape.material, module.MODEL)


def test_the_refusal_lists_the_declared_materials(tmp_path):
    """An unknown material is refused naming what the import takes: the modules' declarations, `interface`, a
    boundary without a surface, and `subsurface`, a dielectric around a medium."""
    path = tmp_path / "scene.pbrt"
    path.write_text(HEADER + 'Material "no-such-material"\n' + QUAD)
    with pytest.raises(SpectraceError) as caught:
        pbrt_scene_data(path)
    listed = re.search(r"\(spectrace imports (.*)\)$", caught.value.message).group(1).split(", ")
    assert set(listed) == {kind for kind, _ in _declared(MODULES)} | {"interface", "subsurface"}


def test_the_commands_help_lists_every_declared_material():
    from typer.testing import CliRunner

    from spectrace.cli import app

    result = CliRunner().invoke(app, ["import-pbrt", "--help"], env={"COLUMNS": "200"})
    assert result.exit_code == 0, result.output
    declared = {kind for kind, _ in [*_declared(MODULES), *_LIGHTS]}
    assert declared <= set(re.findall(r"[\w-]+", result.output))


@pytest.mark.parametrize("module", LIGHT_MODULES, ids=[m.NAME for m in LIGHT_MODULES])
def test_every_light_declares_its_pbrt_lights_or_why_it_has_none(module):
    assert_declares_mapping(module, "PBRT_LIGHTS", "from_pbrt", "PBRT_NONE")


@pytest.mark.parametrize("kind, module", _LIGHTS, ids=[f"{k}-{m.NAME}" for k, m in _LIGHTS])
def test_each_declared_pbrt_light_imports_with_pbrts_defaults_as_its_module(tmp_path, kind, module):
    """pbrt's `infinite` is two of spectrace's lights: constant without an image, envmap with one (an equal-area
    square map, as pbrt-v4 takes); an area light is on a shape."""
    path = tmp_path / "scene.pbrt"
    if module is area:
        path.write_text(CAMERA + f'AreaLightSource "{kind}"\n' + QUAD)
        (shape,) = load_pbrt_scene(path).shapes
        assert isinstance(shape.emitter, area.MODEL)
        return
    light = f'LightSource "{kind}"'
    if module is envmap or module is projector:  # pbrt-v4 requires the projection light's image too
        write_exr(tmp_path / "sky.exr", np.ones((8, 8, 3), np.float32), None, {})
        light += ' "string filename" "sky.exr"'
    path.write_text(CAMERA + light + "\n" + QUAD)
    (imported,) = load_pbrt_scene(path).lights
    assert isinstance(imported, module.MODEL)


def test_the_light_refusal_lists_the_declared_lights(tmp_path):
    path = tmp_path / "scene.pbrt"
    path.write_text(CAMERA + 'LightSource "sunsky"\n' + QUAD)
    with pytest.raises(SpectraceError) as caught:
        pbrt_scene_data(path)
    listed = re.search(r"spectrace imports (.*) and diffuse area lights$", caught.value.message).group(1).split(", ")
    assert sorted(listed) == sorted({kind for kind, module in _LIGHTS if module is not area})


_FILTERS = _declared(PIXEL_FILTERS.values(), "PBRT_FILTERS")


@pytest.mark.parametrize("kind, module", _FILTERS, ids=[k for k, _ in _FILTERS])
def test_each_declared_pbrt_filter_imports_with_pbrts_defaults_as_its_module(tmp_path, kind, module):
    """pbrt-v4's filters with their defaults (filters.cpp: box radius 0.5, triangle 2, Gaussian σ = 0.5 radius 1.5,
    Mitchell radius 2, B = C = 1/3)."""
    path = tmp_path / "scene.pbrt"
    path.write_text(f'PixelFilter "{kind}"\n' + HEADER + QUAD)
    imported = load_pbrt_scene(path).pixel_filter
    assert imported.type == module.NAME
    expected = {"box": 0.5, "triangle": 2.0, "gaussian": 1.5, "mitchell": 2.0}[kind]
    assert imported.support == expected
    if kind == "gaussian":
        assert imported.stddev == 0.5
    if kind == "mitchell":
        assert (imported.b, imported.c) == (1.0 / 3.0, 1.0 / 3.0)


# pbrt's perspective camera is two of spectrace's: thinlens for one with a lens; spherical needs mapping "equirect";
# realistic a lens file.
_CAMERA_PARAMETERS = {
    "thinlens": ' "float lensradius" 0.1',
    "equirectangular": ' "string mapping" "equirect"',
    "realistic": f' "string lensfile" "{scenes_dir() / "lenses" / "dgauss.50mm.dat"}"',
}
_CAMERAS = _declared(CAMERAS.values(), "PBRT_CAMERAS")


@pytest.mark.parametrize("kind, module", _CAMERAS, ids=[f"{k}-{m.NAME}" for k, m in _CAMERAS])
def test_each_declared_pbrt_camera_imports_as_its_module(tmp_path, kind, module):
    path = tmp_path / "scene.pbrt"
    camera = f'Camera "{kind}"{_CAMERA_PARAMETERS.get(module.NAME, "")}\n'
    path.write_text(HEADER.replace('Camera "perspective" "float fov" 30\n', camera) + QUAD)
    assert load_pbrt_scene(path).camera.type == module.NAME


def test_the_camera_refusal_lists_the_declared_cameras(tmp_path):
    path = tmp_path / "scene.pbrt"
    path.write_text(HEADER.replace('Camera "perspective"', 'Camera "no-such-camera"') + QUAD)
    with pytest.raises(SpectraceError) as caught:
        pbrt_scene_data(path)
    listed = re.search(r"spectrace imports pbrt's (.*) cameras$", caught.value.message).group(1)
    assert re.sub(r" \(.*?\)", "", listed).replace(" and ", ", ").split(", ") == list(dict(_CAMERAS))


_INTEGRATORS = _declared(INTEGRATORS.values(), "PBRT_INTEGRATORS")


@pytest.mark.parametrize("kind, module", _INTEGRATORS, ids=[k for k, _ in _INTEGRATORS])
def test_each_declared_pbrt_integrator_imports_with_pbrts_depth_as_its_module(tmp_path, kind, module):
    """pbrt-v4's maxdepth (default 5) counts bounces, spectrace's max_depth path segments: 6."""
    path = tmp_path / "scene.pbrt"
    path.write_text(f'Integrator "{kind}"\n' + HEADER + QUAD)
    scene = load_pbrt_scene(path)
    assert (scene.integrator, scene.max_depth) == (module.NAME, 6)


_TEXTURES = _declared(TEXTURES.values(), "PBRT_TEXTURES")


@pytest.mark.parametrize("kind, module", _TEXTURES, ids=[k for k, _ in _TEXTURES])
def test_each_declared_pbrt_texture_imports_as_its_module(tmp_path, kind, module):
    """A diffuse reflectance of the texture, with pbrt-v4's defaults (an imagemap needs its image); pbrt-v4's float
    noise textures (fbm, wrinkled, windy: no spectrum texture of theirs) as a mix material's amount."""
    write_exr(tmp_path / "image.exr", np.full((4, 4, 3), 0.5, np.float32), None, {})
    image = ' "string filename" "image.exr"' if kind == "imagemap" else ""
    path = tmp_path / "scene.pbrt"
    if kind in ("fbm", "wrinkled", "windy"):
        materials = 'MakeNamedMaterial "a" "string type" "diffuse"\nMakeNamedMaterial "b" "string type" "conductor"\n'
        materials += 'Material "mix" "string materials" ["a" "b"] "texture amount" "t"\n'
        path.write_text(HEADER + f'Texture "t" "float" "{kind}"\n' + materials + QUAD)
        (shape,) = load_pbrt_scene(path).shapes
        assert isinstance(shape.material.amount, module.MODEL)
        return
    path.write_text(
        HEADER + f'Texture "t" "spectrum" "{kind}"{image}\nMaterial "diffuse" "texture reflectance" "t"\n' + QUAD
    )
    (shape,) = load_pbrt_scene(path).shapes
    assert isinstance(shape.material.reflectance, module.MODEL)


# The other kinds' declarations: (module, the name of its tuple of pbrt types).
_KINDS = [
    (module, names)
    for registry, names in (
        (CAMERAS, "PBRT_CAMERAS"),
        (PIXEL_FILTERS, "PBRT_FILTERS"),
        (INTEGRATORS, "PBRT_INTEGRATORS"),
        (TEXTURES, "PBRT_TEXTURES"),
    )
    for module in registry.values()
]


@pytest.mark.parametrize("module, names", _KINDS, ids=[f"{names}-{m.NAME}" for m, names in _KINDS])
def test_every_camera_filter_integrator_and_texture_declares_its_pbrt_mapping_or_why_it_has_none(module, names):
    assert_declares_mapping(module, names, "from_pbrt", "PBRT_NONE")
