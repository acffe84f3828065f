"""Every pbrt-v4 scene file under the folders named, as spectrace imports it: the corpus table of "every pbrt-v4
file whose assets are present imports", for collections fetched without (all) their assets.

    python -m tests.tooling.pbrt_corpus ROOT... [--json OUT] [--missing-assets placeholder|refuse] [--timeout 120]

A scene file is a *.pbrt (recursively, in name order) with a WorldBegin; the files it includes are read through it.
Each is imported (`import_pbrt`, in this process, with a time limit per file) and its TOML loaded, with missing
meshes, images and data files stood in for (spectrace.interop.pbrt.placeholders; --missing-assets refuse: as a
user's import, refused at the first): the table says whether it imports and how many of the files it names are
absent, or the one line it is refused with. The refusals are grouped by what they name (a plugin, a parameter), and
the plugins the scene files use are counted (the files each appears in), so that what keeps files out is seen with
what they use that spectrace refuses before it gets there.

One process, one file at a time. The files are public scenes fetched apart from the project; nothing here writes
into their folders. A Python exception other than spectrace's own error is a bug: it is counted as a crash, its
last line shown, and the run exits 1."""

from __future__ import annotations

import argparse
import json
import os
import re
import sys
import tempfile
import time
import traceback
from collections import Counter
from contextlib import suppress
from dataclasses import asdict, dataclass, field
from pathlib import Path

from tests.tooling.mitsuba_corpus import FileTimeout, _cell, _first_line, time_limit

from spectrace.errors import SpectraceError

# The directives that name a plugin, and where their type is: the first argument, or a "string type" parameter.
_PLUGIN_DIRECTIVES = (
    "Shape",
    "Material",
    "LightSource",
    "AreaLightSource",
    "Camera",
    "Film",
    "Sampler",
    "Integrator",
    "PixelFilter",
)
_WORLD_BEGIN = re.compile(r"^[ \t]*WorldBegin\b", re.MULTILINE)


@dataclass
class Row:
    file: str
    imported: bool = False
    absent: list[str] = field(default_factory=list)  # the missing files stood in for, each once
    features: list[str] = field(default_factory=list)  # what the refusal names
    reason: str = ""
    plugins: list[str] = field(default_factory=list)  # "Directive type" for each plugin the file uses, once
    crashed: bool = False
    seconds: float = 0.0


def scene_files(roots: list[Path]) -> list[Path]:
    """The *.pbrt files under the roots that hold a WorldBegin (a scene, not a file for Include)."""
    found = {
        path.resolve()
        for root in roots
        for path in ([root] if root.is_file() else root.rglob("*.pbrt"))
        if path.is_file() and path.suffix == ".pbrt"
    }
    return sorted(path for path in found if _WORLD_BEGIN.search(path.read_text(errors="replace")))


def plugins_used(path: Path) -> list[str]:
    """Each plugin the scene (its present included files too) names, as "Directive type", once."""
    from spectrace.interop.pbrt.parser import parse_directives

    used: dict[str, None] = {}
    for directive in parse_directives(path, skipped=[]):
        kind = ""
        if directive.name in _PLUGIN_DIRECTIVES and directive.arguments:
            kind = str(directive.arguments[0])
        elif directive.name == "Texture" and len(directive.arguments) >= 3:
            kind = str(directive.arguments[2])
        elif directive.name in ("MakeNamedMaterial", "MakeNamedMedium"):
            kind = next((str(p.values[0]) for p in directive.parameters if p.name == "type" and p.values), "")
        if kind:
            used[f"{directive.name} {kind}"] = None
    return list(used)


def refusal_feature(reason: str) -> str:
    """What a refusal names, for grouping: its first clause after file:line, numbers blanked (quoted names kept:
    they are the plugins and parameters)."""
    text = re.sub(r"^\S+?(:\d+)?: ", "", reason)
    text = re.split(r"[:;(]", text, maxsplit=1)[0]
    text = re.sub(r"(?<![\w'])[-+]?\d[\d.e+-]*", "N", text)
    return " ".join(text.split()[:8])


def spectrace_import(path: Path, shown: dict[str, str], missing_assets: str) -> dict:
    """The row's fields from spectrace's import of the file (through a temporary TOML), loaded as a scene."""
    from spectrace.interop.pbrt import import_pbrt
    from spectrace.scene.loader import load_scene  # the import tells its own warnings

    with tempfile.TemporaryDirectory(prefix="pbrt-corpus-") as folder:
        toml_path = Path(folder) / (path.stem + ".toml")
        try:
            warnings, _ = import_pbrt(path, toml_path, missing_assets=missing_assets)
            load_scene(toml_path)
        except SpectraceError as failure:
            reason = _first_line(str(failure), shown)
            return {"reason": reason, "features": [refusal_feature(reason)]}
    absent = dict.fromkeys(
        match.group(1) for text in warnings if text.startswith("placeholder: ") for match in _missing(text)
    )
    return {"imported": True, "absent": list(absent)}


def _missing(text: str):
    return re.finditer(r"'([^']+)' is missing", text)


def survey(path: Path, shown: dict[str, str], args) -> Row:
    row = Row(shown[str(path)])
    start = time.perf_counter()
    try:
        with suppress(SpectraceError):  # the import below says why
            row.plugins = plugins_used(path)
        try:
            with time_limit(args.timeout):
                found = spectrace_import(path, shown, args.missing_assets)
        except FileTimeout as late:
            found = {"reason": f"timeout: {late}", "features": ["import time limit"]}
        for key, value in found.items():
            setattr(row, key, value)
    except Exception:
        row.crashed = True
        row.reason = "CRASH " + _first_line(traceback.format_exc().strip().splitlines()[-1], shown)
        traceback.print_exc()
    row.seconds = round(time.perf_counter() - start, 2)
    return row


def feature_groups(rows: list[Row]) -> list[tuple[str, int]]:
    """(what a refusal names, files it keeps out), the most frequent first."""
    counts = Counter(feature for row in rows if not row.imported and not row.crashed for feature in row.features)
    return sorted(counts.items(), key=lambda item: (-item[1], item[0]))


def plugin_counts(rows: list[Row]) -> list[tuple[str, int]]:
    counts = Counter(plugin for row in rows for plugin in row.plugins)
    return sorted(counts.items(), key=lambda item: (item[0].split()[0], -item[1], item[0]))


def table(rows: list[Row]) -> str:
    imported = [row for row in rows if row.imported]
    whole = [row for row in imported if not row.absent]
    lines = [
        "| scene files | import | of which with every asset present | refused |",
        "|---|---|---|---|",
        f"| {len(rows)} | {len(imported)} | {len(whole)} | {len(rows) - len(imported)} |",
        "",
        "| file | imports | assets absent | reason |",
        "|---|---|---|---|",
    ]
    for row in rows:
        absent = str(len(row.absent)) if row.imported else "-"
        lines.append(f"| {_cell(row.file)} | {'yes' if row.imported else 'NO'} | {absent} | {_cell(row.reason)} |")
    lines += ["", "What the refused files are refused for (the first thing each names):", ""]
    lines += ["| refusal | files |", "|---|---|"]
    lines += [f"| {_cell(name)} | {count} |" for name, count in feature_groups(rows)]
    lines += ["", "The plugins the scene files use (files using each):", "", "| plugin | files |", "|---|---|"]
    lines += [f"| {_cell(name)} | {count} |" for name, count in plugin_counts(rows)]
    crashed = [row for row in rows if row.crashed]
    if crashed:
        lines += ["", f"Crashes (bugs): {len(crashed)}", *(f"- {row.file}: {row.reason}" for row in crashed)]
    return "\n".join(["", *lines])


def main(argv: list[str] | None = None) -> int:
    from spectrace.interop.pbrt.placeholders import MISSING_ASSETS

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("roots", nargs="+", type=Path, help="folders (or files) holding pbrt-v4 scenes")
    parser.add_argument("--json", type=Path, help="also write the rows and the groups as JSON here")
    parser.add_argument(
        "--missing-assets", choices=MISSING_ASSETS, default="placeholder", help="as spectrace import-pbrt's"
    )
    parser.add_argument("--timeout", type=float, default=120.0, help="seconds per file")
    args = parser.parse_args(argv)
    files = scene_files(args.roots)
    # Files are named relative to the folder above the roots, so no machine's paths reach the table.
    base = Path(os.path.commonpath([root.resolve().parent for root in args.roots]))
    shown = {str(path): str(path.relative_to(base)) for path in files}
    shown |= {str(path.parent): str(path.parent.relative_to(base)) for path in files}
    shown = dict(sorted(shown.items(), key=lambda item: -len(item[0])))  # the longest first
    rows = []
    for path in files:
        row = survey(path, shown, args)
        state = f"yes ({len(row.absent)} absent)" if row.imported else "NO"
        print(f"{state:>16} {row.file}  {row.reason}", file=sys.stderr)
        rows.append(row)
    print(table(rows))
    if args.json:
        data = {
            "rows": [asdict(row) for row in rows],
            "refusals": [{"refusal": name, "files": n} for name, n in feature_groups(rows)],
            "plugins": [{"plugin": name, "files": n} for name, n in plugin_counts(rows)],
        }
        args.json.write_text(json.dumps(data, indent=1))
    return 1 if any(row.crashed for row in rows) else 0


if __name__ == "__main__":
    sys.exit(main())
