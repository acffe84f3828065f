"""Each light's parameter table agrees with the Python API's helpers (docs/scene-format.md's tables of the lights'
and the emitter's keys are written from the tables: tests/test_docs_tables.py)."""

import inspect

import pytest

import spectrace
from spectrace.core.parameters import REQUIRED
from spectrace.lights import LIGHTS, area

# Each light's Python constructor, `spectrace.<API_NAME>` (a shape's emitter: area_emitter).
API_HELPERS = {name: getattr(spectrace, m.API_NAME) for name, m in LIGHTS.items() if m.API_NAME is not None} | {
    "area": spectrace.area_emitter
}


@pytest.mark.parametrize("name", list(API_HELPERS))
def test_api_helper_takes_the_parameters_with_their_defaults(name):
    module = area if name == "area" else LIGHTS[name]
    signature = inspect.signature(API_HELPERS[name])
    for parameter in module.PARAMETERS:
        given = signature.parameters[parameter.api_name or parameter.name]
        expected = inspect.Parameter.empty if parameter.default is REQUIRED else parameter.default
        assert given.default == expected, f"{API_HELPERS[name].__name__}({given.name}=...)"
