"""Every material and light module maps Mitsuba 3 or says why it does not: its MITSUBA_PLUGINS (with `from_mitsuba`)
or MITSUBA_NONE, so a new module cannot silently lack a mapping. Each declared plugin imports with Mitsuba's
defaults into a scene that loads, and the importer's list of what it supports is the modules' declarations."""

import dataclasses
import re
from pathlib import Path

import numpy as np
import pytest

from plugin_mappings import assert_declares_mapping
from rgl_tensor import ggx_file
from spectrace.cameras import CAMERAS
from spectrace.errors import SpectraceError
from spectrace.integrators import INTEGRATORS
from spectrace.interop.mitsuba import load_mitsuba_scene, mitsuba_scene_data
from spectrace.lights import LIGHTS, area, projector
from spectrace.materials import MATERIALS
from spectrace.pixel_filters import PIXEL_FILTERS
from spectrace.spectral import spectrum_to_xyz
from spectrace.spectral.spectrum import Spectrum
from spectrace.textures import TEXTURES

MODULES = [*MATERIALS.values(), *LIGHTS.values(), area]
SENSOR = """<sensor type="perspective"><float name="fov" value="45"/>
    <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="6"/></film></sensor>"""


def _scene(folder: Path, body: str) -> Path:
    path = folder / "scene.xml"
    path.write_text(f'<scene version="3.0.0">\n{SENSOR}\n{body}\n</scene>\n')
    return path


def _plugins(modules) -> list[tuple[str, object]]:
    return [(plugin, module) for module in modules for plugin in module.MITSUBA_PLUGINS]


# Every plugin that maps Mitsuba's: materials, lights, textures, cameras, pixel filters and integrators.
MAPPED = [*MODULES, *TEXTURES.values(), *CAMERAS.values(), *PIXEL_FILTERS.values(), *INTEGRATORS.values()]


@pytest.mark.parametrize("module", MAPPED, ids=[f"{m.__name__.split('.')[-2]}-{m.NAME}" for m in MAPPED])
def test_every_module_declares_its_mitsuba_plugins_or_why_it_has_none(module):
    assert_declares_mapping(module, "MITSUBA_PLUGINS", "from_mitsuba", "MITSUBA_NONE")


@pytest.mark.parametrize("modules", [list(MATERIALS.values()), [*LIGHTS.values(), area]], ids=["bsdf", "emitter"])
def test_no_plugin_is_claimed_twice(modules):
    names = [plugin for plugin, _ in _plugins(modules)]
    assert len(names) == len(set(names)), names


def test_the_unsupported_message_lists_the_declared_plugins(tmp_path):
    xml = _scene(tmp_path, '<shape type="cube"><bsdf type="no-such-bsdf"/></shape>')
    with pytest.raises(SpectraceError) as caught:
        mitsuba_scene_data(xml)
    listed = dict(
        part.split(" ", 1)
        for part in re.search(r"\(spectrace imports (.*)\)$", caught.value.message).group(1).split("; ")
    )
    # Besides the materials' plugins, the adapters that wrap one bsdf (twosided and the surface-detail ones) and
    # `null`, a shape without material.
    adapters = {"twosided", "normalmap", "bumpmap", "mask", "null"}
    assert set(listed["bsdf"].split(", ")) == {p for p, _ in _plugins(MATERIALS.values())} | adapters
    assert set(listed["emitter"].split(", ")) == {p for p, _ in _plugins([*LIGHTS.values(), area])}


@pytest.mark.parametrize(
    "plugin, module", _plugins(MATERIALS.values()), ids=[p for p, _ in _plugins(MATERIALS.values())]
)
def test_each_declared_bsdf_reaches_its_module(tmp_path, plugin, module):
    """With Mitsuba's defaults the BSDF imports into a scene that loads, or is refused for a stated reason (a
    roughconductor's default material "none" is a mirror, which spectrace has only smooth), never as an unknown
    plugin."""
    properties = ""
    if plugin == "measured":  # no default file, in Mitsuba either: one written from GGX (tests/rgl_tensor.py)
        properties = f'<string name="filename" value="{ggx_file(0.3)}"/>'
    try:
        scene = load_mitsuba_scene(
            _scene(tmp_path, f'<shape type="cube"><bsdf type="{plugin}">{properties}</bsdf></shape>')
        )
    except SpectraceError as error:
        assert f"bsdf '{plugin}' with " in error.message, error.message
    else:
        assert type(scene.shapes[0].material) in {m.MODEL for m in MATERIALS.values()}


def _d65_of_unit_luminance(spectrum: Spectrum, luminance: float = 1.0) -> None:
    """Mitsuba's default emission: D65 (x, y = 0.3127, 0.3290) with luminance 1, film Y = 1 in spectrace."""
    x, y, z = spectrum_to_xyz(spectrum)
    assert y == pytest.approx(luminance, rel=1e-3)
    np.testing.assert_allclose((x / (x + y + z), y / (x + y + z)), (0.3127, 0.3290), atol=1e-3)


def _spectra(model) -> list[Spectrum]:
    return [getattr(model, f.name) for f in dataclasses.fields(model) if isinstance(getattr(model, f.name), Spectrum)]


# Mitsuba's envmap has no default image (tests/interop/test_mitsuba_scene_format.py imports one).
_EMISSIVE = _plugins(light for light in LIGHTS.values() if light.NAME != "envmap")


@pytest.mark.parametrize("plugin, module", _EMISSIVE, ids=[p for p, _ in _EMISSIVE])
def test_each_declared_emitter_imports_with_mitsubas_default_emission(tmp_path, plugin, module):
    body = f'<shape type="cube"/><emitter type="{plugin}"/>'
    (light,) = load_mitsuba_scene(_scene(tmp_path, body)).lights
    assert isinstance(light, module.MODEL)
    spectra = _spectra(light)
    assert len(spectra) == 1
    # A projector's intensity is π·scale·irradiance (the irradiance its unit-distance plane receives, Mitsuba's
    # projector.cpp), so its default irradiance of 1 is an intensity of π.
    _d65_of_unit_luminance(spectra[0], np.pi if module is projector else 1.0)


def test_the_shape_emitter_imports_on_a_shape(tmp_path):
    """The area emitter needs its radiance (Mitsuba has no default for it); RGB (1, 1, 1) emission is the same
    white of unit luminance."""
    (plugin,) = area.MITSUBA_PLUGINS
    body = f'<shape type="rectangle"><emitter type="{plugin}"><rgb name="radiance" value="1, 1, 1"/></emitter></shape>'
    (shape,) = load_mitsuba_scene(_scene(tmp_path, body)).shapes
    assert isinstance(shape.emitter, area.MODEL)
    _d65_of_unit_luminance(shape.emitter.radiance)


def test_the_commands_help_lists_every_plugin_the_importer_takes():
    """`import-mitsuba --help` is written from the importer's table (so from the registries), not by hand."""
    from typer.testing import CliRunner

    from spectrace.cli import app
    from spectrace.interop.mitsuba.plugins import SUPPORTED

    result = CliRunner().invoke(app, ["import-mitsuba", "--help"], env={"COLUMNS": "200"})
    assert result.exit_code == 0, result.output
    words = set(re.findall(r"[\w-]+", result.output))
    plugins = {plugin for plugin, _ in _plugins([*MATERIALS.values(), *LIGHTS.values(), area])}
    assert plugins <= {kind for kinds in SUPPORTED.values() for kind in kinds}
    assert {kind for kinds in SUPPORTED.values() for kind in kinds} <= words


def test_the_importer_offers_every_helper_a_plugin_mapping_calls(tmp_path):
    """A material's, light's, texture's, camera's, pixel filter's or integrator's `from_mitsuba` calls helpers on
    the importer it is given (`importer.spectrum`, `importer.roughness`, ...), which live in the kinds' modules of
    spectrace.interop.mitsuba: each name a mapping uses must be on the importer, or that plugin would fail only when
    a scene uses it."""
    import ast
    import inspect

    from spectrace.interop.mitsuba.importer import MitsubaImporter

    used: dict[str, str] = {}
    for module in {*MODULES, *TEXTURES.values(), *CAMERAS.values(), *PIXEL_FILTERS.values(), *INTEGRATORS.values()}:
        for node in ast.walk(ast.parse(inspect.getsource(module))):
            if isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name) and node.value.id == "importer":
                used.setdefault(node.attr, module.__name__)
    importer = MitsubaImporter(tmp_path / "scene.xml", tmp_path, {})
    assert {"spectrum", "roughness", "fail", "unsupported_plugin"} <= used.keys()  # the walk sees the mappings' calls
    assert {name: module for name, module in used.items() if not hasattr(importer, name)} == {}


_RFILTERS = _plugins(PIXEL_FILTERS.values())


@pytest.mark.parametrize("plugin, module", _RFILTERS, ids=[p for p, _ in _RFILTERS])
def test_each_declared_rfilter_imports_with_mitsubas_fixed_radius_as_its_module(tmp_path, plugin, module):
    """Mitsuba 3's rfilters have fixed radii (box 0.5, tent 1, gaussian 4σ with σ = 0.5, mitchell 2, B = C = 1/3)."""
    path = tmp_path / "scene.xml"
    path.write_text(
        f'<scene version="3.0.0"><sensor type="perspective"><film type="hdrfilm"><rfilter type="{plugin}"/>'
        '</film></sensor><shape type="cube"/><emitter type="constant"/></scene>'
    )
    imported = load_mitsuba_scene(path).pixel_filter
    assert imported.type == module.NAME
    assert imported.support == {"box": 0.5, "tent": 1.0, "gaussian": 2.0, "mitchell": 2.0}[plugin]
    if plugin == "mitchell":
        assert (imported.b, imported.c) == (1.0 / 3.0, 1.0 / 3.0)


_INTEGRATOR_PLUGINS = _plugins(INTEGRATORS.values())


@pytest.mark.parametrize("plugin, module", _INTEGRATOR_PLUGINS, ids=[p for p, _ in _INTEGRATOR_PLUGINS])
def test_each_declared_integrator_imports_with_mitsubas_defaults_as_its_module(tmp_path, plugin, module):
    """Each with its default max_depth (unbounded, -1, or what the integrator keeps of it) and a scene it renders:
    a diffuse cube under a constant emitter, seen by a pinhole through the film's box filter."""
    path = tmp_path / "scene.xml"
    path.write_text(
        f'<scene version="3.0.0"><integrator type="{plugin}"/><sensor type="perspective"><film type="hdrfilm">'
        '<rfilter type="box"/></film></sensor><shape type="cube"/><emitter type="constant"/></scene>'
    )
    assert load_mitsuba_scene(path).integrator == module.NAME


def test_the_integrators_that_export_are_those_with_to_mitsuba():
    """An integrator without `to_mitsuba` is refused by the export naming the ones that have it."""
    exported = [name for name, module in INTEGRATORS.items() if hasattr(module, "to_mitsuba")]
    assert exported and all(INTEGRATORS[name].MITSUBA_PLUGINS for name in exported)


_SENSORS = _plugins(CAMERAS.values())


@pytest.mark.parametrize("plugin, module", _SENSORS, ids=[p for p, _ in _SENSORS])
def test_each_declared_sensor_imports_as_its_module(tmp_path, plugin, module):
    """With Mitsuba's defaults (a thinlens needs its aperture_radius, as in Mitsuba)."""
    aperture = '<float name="aperture_radius" value="0.1"/>' if plugin == "thinlens" else ""
    path = tmp_path / "scene.xml"
    path.write_text(
        f'<scene version="3.0.0"><sensor type="{plugin}">{aperture}</sensor><shape type="cube"/>'
        '<emitter type="constant"/></scene>'
    )
    assert load_mitsuba_scene(path).camera.type == module.NAME
