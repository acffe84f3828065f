"""The README's table of the names a scene file uses is each registry's list, in its order: a plugin added,
renamed or removed without the README following fails here."""

import re
from pathlib import Path

import pytest

from spectrace.cameras import CAMERAS
from spectrace.integrators import INTEGRATORS
from spectrace.lights import LIGHTS
from spectrace.materials import MATERIALS
from spectrace.pixel_filters import PIXEL_FILTERS
from spectrace.textures import TEXTURES

README = Path(__file__).resolve().parents[1] / "README.md"

REGISTRIES = {
    "materials": list(MATERIALS),
    "lights": list(LIGHTS),
    "integrators": list(INTEGRATORS),
    "cameras": list(CAMERAS),
    "pixel filters": list(PIXEL_FILTERS),
    "textures": list(TEXTURES),
}


def readme_lists(text: str) -> dict[str, list[str]]:
    """kind -> the names in its row of the table under "The names a scene file uses" (the row's first word(s)
    before any parenthesis name the kind; the names are the second cell's code spans)."""
    section = text.split("### The names a scene file uses", 1)[1].split("\n#", 1)[0]
    rows = {}
    for line in section.splitlines():
        cells = [cell.strip() for cell in line.strip().strip("|").split("|")]
        if len(cells) == 2 and cells[1].startswith("`"):
            rows[cells[0].split("(")[0].strip()] = re.findall(r"`([^`]+)`", cells[1])
    return rows


def test_the_reader_reads_a_row_and_sees_a_missing_name():
    text = (
        "### The names a scene file uses\n| kind | names |\n|---|---|\n"
        "| integrators (`[integrator]`) | `path`, `light` |\n## Next\n| other | `x` |\n"
    )
    assert readme_lists(text) == {"integrators": ["path", "light"]}
    assert readme_lists(text)["integrators"] != REGISTRIES["integrators"]


@pytest.mark.parametrize("kind", sorted(REGISTRIES))
def test_the_readme_lists_each_registry_in_its_order(kind):
    rows = readme_lists(README.read_text(encoding="utf-8"))
    assert kind in rows, f"README.md has no row for {kind}"
    assert rows[kind] == REGISTRIES[kind]


def test_the_readme_table_has_no_row_for_an_unknown_kind():
    assert set(readme_lists(README.read_text(encoding="utf-8"))) == set(REGISTRIES)
