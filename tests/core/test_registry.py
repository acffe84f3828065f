"""The registry every kind of plugin is listed in: a plugin's position is its device code, a name is unique, an
unknown name is refused naming the choices, and a resolved object finds the plugin whose model it is."""

from dataclasses import dataclass
from types import SimpleNamespace

import pytest

from spectrace.core.registry import Registry
from spectrace.errors import SpectraceError


@dataclass
class _Red:
    pass


@dataclass
class _Blue:
    pass


RED = SimpleNamespace(NAME="red", MODEL=_Red)
BLUE = SimpleNamespace(NAME="blue", MODEL=_Blue)


def test_a_plugins_position_is_its_code_and_its_kernel_constant():
    registry = Registry("colour", (RED, BLUE))
    assert list(registry) == ["red", "blue"] and registry["blue"] is BLUE and len(registry) == 2
    assert registry.codes == {"red": 0, "blue": 1}
    assert registry.kernel_defines("COLOUR") == {"COLOUR_RED": 0, "COLOUR_BLUE": 1, "COLOUR_TYPE_COUNT": 2}


def test_two_plugins_of_one_name_are_refused():
    with pytest.raises(ValueError, match="two colour plugins are named 'red'"):
        Registry("colour", (RED, SimpleNamespace(NAME="red")))


def test_an_unknown_name_is_one_line_naming_where_and_the_choices():
    with pytest.raises(SpectraceError) as error:
        Registry("colour", (RED, BLUE)).named("green", "scene.toml: materials.wall.type")
    assert str(error.value) == "scene.toml: materials.wall.type: unknown colour 'green' (one of red, blue)"


def test_a_model_finds_its_plugin_and_another_type_is_unsupported():
    registry = Registry("colour", (RED, BLUE))
    assert registry.for_model(_Blue()) is BLUE
    with pytest.raises(SpectraceError, match="unsupported colour int"):
        registry.for_model(3)


def test_the_package_registries_are_registries():
    """Every kind of plugin is listed through the one helper (so the device codes and the docs come from one
    shape); a kind still listed in a plain dict fails here."""
    from spectrace.cameras import CAMERAS
    from spectrace.integrators import INTEGRATORS
    from spectrace.lights import DEVICE_LIGHTS, LIGHTS
    from spectrace.materials import MATERIALS
    from spectrace.pixel_filters import PIXEL_FILTERS
    from spectrace.textures import TEXTURES

    registries = (MATERIALS, LIGHTS, DEVICE_LIGHTS, TEXTURES, CAMERAS, PIXEL_FILTERS, INTEGRATORS)
    assert all(isinstance(registry, Registry) for registry in registries)
