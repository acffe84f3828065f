"""The Python API's helpers take each texture's keys with its defaults (docs/textures.md's tables are written from
the parameter tables: tests/test_docs_tables.py)."""

import inspect

import pytest

import spectrace
from spectrace.core.parameters import REQUIRED
from spectrace.textures import TEXTURES

API = {
    "bitmap": spectrace.bitmap,
    "spectral": spectrace.spectral_texture,
    "checkerboard": spectrace.checkerboard,
    "scale": spectrace.scale_texture,
    "mix": spectrace.mix_texture,
    "dots": spectrace.dots_texture,
    "fbm": spectrace.fbm_texture,
    "wrinkled": spectrace.wrinkled_texture,
    "windy": spectrace.windy_texture,
    "marble": spectrace.marble_texture,
    "mesh_attribute": spectrace.mesh_attribute,
    "directionmix": spectrace.directionmix_texture,
}


@pytest.mark.parametrize("name", list(TEXTURES))
def test_api_helper_takes_the_keys_with_their_defaults(name):
    signature = inspect.signature(API[name])
    for parameter in TEXTURES[name].PARAMETERS:
        if parameter.name == "file":
            continue  # the helpers' first argument: a path or an array
        given = signature.parameters[parameter.name]
        expected = inspect.Parameter.empty if parameter.default is REQUIRED else parameter.default
        assert given.default == expected or (
            isinstance(expected, (int, float)) and given.default in (expected, (expected, expected))
        ), f"spectrace.{API[name].__name__}({parameter.name}=...)"
