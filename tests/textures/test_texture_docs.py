"""Each texture's parameter table is the one docs/textures.md shows, and the Python API's helpers take its keys
with its defaults."""

import inspect
from pathlib import Path

import pytest

import spectrace
from spectrace.core.parameters import REQUIRED
from spectrace.textures import TEXTURES

DOC = (Path(__file__).resolve().parents[2] / "docs" / "textures.md").read_text(encoding="utf-8")
API = {
    "bitmap": spectrace.bitmap,
    "spectral": spectrace.spectral_texture,
    "checkerboard": spectrace.checkerboard,
    "scale": spectrace.scale_texture,
    "mix": spectrace.mix_texture,
}


def _documented_rows(name: str) -> list[tuple[str, str, str, str]]:
    section = DOC.split(f"### `{name}`\n", 1)[1].split("\n\n", 1)[0]
    rows = [line for line in section.splitlines() if line.startswith("| `")]
    return [tuple(cell.strip() for cell in row.strip("|").split(" | ")) for row in rows]


@pytest.mark.parametrize("name", list(TEXTURES))
def test_docs_table_is_the_parameter_table(name):
    expected = [(f"`{p.name}`", p.doc_type(), p.doc_default(), p.doc) for p in TEXTURES[name].PARAMETERS]
    assert _documented_rows(name) == expected


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
