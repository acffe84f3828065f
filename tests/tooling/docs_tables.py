"""The docs' tables of every plugin's keys and the README's table of names, written from the registries.

    python -m tests.tooling.docs_tables            # rewrite every generated block in place
    python -m tests.tooling.docs_tables --check    # exit 1 naming each block that differs (tests/test_docs_tables.py)

A block lies between `<!-- generated: NAME -->` and `<!-- end generated -->` in a page of docs/ or the README; the
prose around it is written by hand. Each kind of plugin is read in one place below (`_kinds`), through its
registry's Mapping interface (name -> a module with NAME and PARAMETERS), so a registry that moves is one line here.

It lives with the tests' tooling, not in the package: the pages it writes are not shipped with the package, and
the package's layers stay free of a module that reads every registry at once.
"""

from __future__ import annotations

import argparse
import re
import sys
from collections.abc import Callable, Iterable, Mapping
from pathlib import Path
from typing import Any

REPOSITORY = Path(__file__).resolve().parents[2]
COMMAND = "python -m tests.tooling.docs_tables"
END = "<!-- end generated -->"
_BLOCK = re.compile(r"(<!-- generated: (?P<name>[^>]+?) -->\n)(?P<body>.*?)(?=" + re.escape(END) + ")", re.S)


def _kinds() -> dict[str, Mapping[str, Any]]:
    """Each kind's registry: plugin name -> a module (or namespace) with NAME and PARAMETERS, in registry order."""
    from spectrace.cameras import CAMERAS
    from spectrace.integrators import INTEGRATORS
    from spectrace.lights import LIGHTS
    from spectrace.materials import MATERIALS
    from spectrace.pixel_filters import PIXEL_FILTERS
    from spectrace.textures import TEXTURES

    return {
        "materials": MATERIALS,
        "lights": LIGHTS,
        "textures": TEXTURES,
        "cameras": CAMERAS,
        "pixel filters": PIXEL_FILTERS,
        "integrators": INTEGRATORS,
    }


def _shared_parameters() -> dict[str, tuple]:
    """Keys that every plugin of a kind takes beside its own, and the area emitter's (a shape's `emitter` table)."""
    from spectrace.cameras import shared
    from spectrace.lights import area
    from spectrace.materials import surface

    return {"cameras": shared.PARAMETERS, "materials": surface.PARAMETERS, "emitter": area.PARAMETERS}


def _cell(text: str) -> str:
    return text.replace("|", "\\|")


def _row(cells: Iterable[str]) -> str:
    return "|" + "|".join(f" {_cell(cell)} " if cell else " " for cell in cells) + "|"


def _key_row(parameter) -> list[str]:
    return [f"`{parameter.name}`", parameter.doc_type(), parameter.doc_default(), parameter.doc]


def key_table(parameters: Iterable) -> str:
    """One plugin's (or one shared set of) keys: key, type and unit, default, meaning."""
    rows = [_row(["key", "type, unit", "default", "meaning"]), "|---|---|---|---|"]
    return "\n".join(rows + [_row(_key_row(p)) for p in parameters])


def type_table(registry: Mapping[str, Any], shared: Iterable = ()) -> str:
    """Every plugin of a kind with its keys, one row a key; `shared` keys (every type's) come first."""
    rows = [_row(["`type`", "key", "type, unit", "default", "meaning"]), "|---|---|---|---|---|"]
    for index, parameter in enumerate(shared):
        rows.append(_row(["every type" if index == 0 else "", *_key_row(parameter)]))
    for name, plugin in registry.items():
        parameters = list(plugin.PARAMETERS)
        if not parameters:
            rows.append(_row([f'`"{name}"`', "—", "", "", "no keys of its own"]))
        for index, parameter in enumerate(parameters):
            rows.append(_row([f'`"{name}"`' if index == 0 else "", *_key_row(parameter)]))
    return "\n".join(rows)


def shared_key_table(registry: Mapping[str, Any]) -> str:
    """Keys that several plugins of a kind take, once each, with the plugins that take it (each key's first
    plugin's entry: a key means the same wherever it is taken)."""
    taken: dict[str, list[str]] = {}
    first: dict[str, Any] = {}
    for name, plugin in registry.items():
        for parameter in plugin.PARAMETERS:
            first.setdefault(parameter.name, parameter)
            taken.setdefault(parameter.name, []).append(name)
    rows = [_row(["key", "type, unit", "default", "meaning", "taken by"]), "|---|---|---|---|---|"]
    for key, parameter in first.items():
        users = "every type" if len(taken[key]) == len(registry) else ", ".join(f"`{n}`" for n in taken[key])
        rows.append(_row([*_key_row(parameter), users]))
    return "\n".join(rows)


def sections(registry: Mapping[str, Any]) -> str:
    """A `### name` heading and key table per plugin."""
    return "\n\n".join(f"### `{name}`\n{key_table(plugin.PARAMETERS)}" for name, plugin in registry.items())


def names(registry: Mapping[str, Any]) -> str:
    """The plugins' names as a scene file writes them: `"a"`, `"b"` or `"c"`."""
    quoted = [f'`"{name}"`' for name in registry]
    return quoted[0] if len(quoted) == 1 else ", ".join(quoted[:-1]) + " or " + quoted[-1]


# The README's rows: kind, the row's first cell.
README_ROWS = {
    "materials": "materials (`[materials.NAME]`)",
    "lights": "lights (`[[lights]]`; area lights are shapes' emitters)",
    "integrators": "integrators (`[integrator]`)",
    "cameras": "cameras (`[camera]`)",
    "pixel filters": "pixel filters (`[film] filter`)",
    "textures": "textures (`[textures.NAME]`)",
}


def readme_names(kinds: Mapping[str, Mapping[str, Any]]) -> str:
    rows = [_row(["kind", "names"]), "|---|---|"]
    for kind, label in README_ROWS.items():
        rows.append(_row([label, ", ".join(f"`{name}`" for name in kinds[kind])]))
    return "\n".join(rows)


def blocks() -> dict[str, Callable[[], str]]:
    """Every generated block by its marker's name."""
    kinds = _kinds()
    shared = _shared_parameters()
    return {
        "materials parameters": lambda: type_table(kinds["materials"]),
        "material surface parameters": lambda: key_table(shared["materials"]),
        "lights parameters": lambda: type_table(kinds["lights"]),
        "emitter parameters": lambda: key_table(shared["emitter"]),
        "textures parameters": lambda: sections(kinds["textures"]),
        "cameras parameters": lambda: type_table(kinds["cameras"], shared["cameras"]),
        "camera types": lambda: f"`type` is {names(kinds['cameras'])}.",
        "pixel filters parameters": lambda: type_table(kinds["pixel filters"]),
        "integrator types": lambda: f"`type` is {names(kinds['integrators'])}.",
        "integrator parameters": lambda: shared_key_table(kinds["integrators"]),
        "readme names": lambda: readme_names(kinds),
    }


def pages() -> list[Path]:
    return [REPOSITORY / "README.md", *sorted((REPOSITORY / "docs").glob("*.md"))]


def regenerate(text: str, generated: Mapping[str, Callable[[], str]], where: str = "") -> str:
    """`text` with each block's body replaced by its generated text; an unknown block name is an error."""

    def body(match: re.Match) -> str:
        name = match["name"]
        if name not in generated:
            raise ValueError(f"{where}: unknown generated block {name!r} (one of {', '.join(generated)})")
        return match[1] + generated[name]() + "\n"

    return _BLOCK.sub(body, text)


def block_names(text: str) -> list[str]:
    return [match["name"] for match in _BLOCK.finditer(text)]


def stale() -> list[str]:
    """'<page>: <block>' for each block whose text differs from what the registries give, and each block that no
    page holds (a block deleted by hand, or a marker's name mistyped)."""
    generated = blocks()
    problems, seen = [], set()
    for page in pages():
        text = page.read_text(encoding="utf-8")
        if text.count("<!-- generated: ") != text.count(END):
            problems.append(f"{page.relative_to(REPOSITORY)}: a generated block without its end marker")
            continue
        fresh = regenerate(text, generated, str(page.relative_to(REPOSITORY)))
        old, new = dict(_bodies(text)), dict(_bodies(fresh))
        problems += [f"{page.relative_to(REPOSITORY)}: {name}" for name in old if old[name] != new[name]]
        seen.update(old)
    problems += [f"no page holds the block {name!r}" for name in generated if name not in seen]
    return problems


def _bodies(text: str) -> list[tuple[str, str]]:
    counts: dict[str, int] = {}
    found = []
    for match in _BLOCK.finditer(text):
        counts[match["name"]] = counts.get(match["name"], 0) + 1
        found.append((f"{match['name']} #{counts[match['name']]}", match["body"]))
    return [(name.removesuffix(" #1"), body) for name, body in found]


def write() -> list[Path]:
    """Rewrite every page whose blocks differ; the pages changed."""
    generated = blocks()
    changed = []
    for page in pages():
        text = page.read_text(encoding="utf-8")
        fresh = regenerate(text, generated, str(page.relative_to(REPOSITORY)))
        if fresh != text:
            page.write_text(fresh, encoding="utf-8")
            changed.append(page)
    return changed


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog=COMMAND, description=__doc__.split("\n\n")[0])
    parser.add_argument("--check", action="store_true", help="only report the blocks that differ; exit 1 if any")
    args = parser.parse_args(argv)
    if args.check:
        problems = stale()
        for problem in problems:
            print(f"stale: {problem}", file=sys.stderr)
        return 1 if problems else 0
    for page in write():
        print(f"wrote {page.relative_to(REPOSITORY)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
