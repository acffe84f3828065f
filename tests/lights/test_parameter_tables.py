"""Each light's parameter table agrees with docs/scene-format.md (every key of a `[[lights]]` type, and of a
shape's `emitter`, is named in its row with its unit and default) and with the Python API's helpers."""

import inspect
from pathlib import Path

import pytest

import spectrace
from spectrace.core.parameters import REQUIRED
from spectrace.lights import LIGHTS, area

ROOT = Path(__file__).resolve().parents[2]
SCENE_FORMAT = (ROOT / "docs" / "scene-format.md").read_text(encoding="utf-8")
# Each light's Python constructor, `spectrace.<API_NAME>` (a shape's emitter: area_emitter).
API_HELPERS = {name: getattr(spectrace, m.API_NAME) for name, m in LIGHTS.items() if m.API_NAME is not None} | {
    "area": spectrace.area_emitter
}


def _row(first_cell: str) -> str:
    rows = [line for line in SCENE_FORMAT.splitlines() if line.startswith(f"| {first_cell} |")]
    assert len(rows) == 1, first_cell
    return rows[0]


MODULES = [(f'`"{name}"`', module) for name, module in LIGHTS.items()] + [("`emitter`", area)]


@pytest.mark.parametrize("first_cell, module", MODULES, ids=[m.NAME for _, m in MODULES])
def test_scene_format_row_names_every_key_with_its_unit_and_default(first_cell, module):
    row = _row(first_cell)
    for parameter in module.PARAMETERS:
        assert f"`{parameter.name}`" in row, parameter.name
        if parameter.unit.startswith("W") or parameter.unit == "degrees":
            assert parameter.unit in row, (parameter.name, parameter.unit)
        if parameter.default not in (REQUIRED, None):
            assert f"default {parameter.doc_default().strip('`')}" in row, (parameter.name, parameter.default)


def test_every_light_type_has_a_row():
    documented = {
        line.split("|")[1].strip().strip('`"')
        for line in SCENE_FORMAT.split("## `[[lights]]`", 1)[1].split("\n## ", 1)[0].splitlines()
        if line.startswith('| `"')
    }
    assert documented == set(LIGHTS)


@pytest.mark.parametrize("name", list(API_HELPERS))
def test_api_helper_takes_the_parameters_with_their_defaults(name):
    module = area if name == "area" else LIGHTS[name]
    signature = inspect.signature(API_HELPERS[name])
    for parameter in module.PARAMETERS:
        given = signature.parameters[parameter.api_name or parameter.name]
        expected = inspect.Parameter.empty if parameter.default is REQUIRED else parameter.default
        assert given.default == expected, f"{API_HELPERS[name].__name__}({given.name}=...)"
