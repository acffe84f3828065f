"""Import and render every glTF file under the folders named, and print a table of what happened to each.

    python -m tests.tooling.gltf_samples FOLDER... [--size 64] [--spp 4] [--device intel-cpu] [--no-render]

For each .gltf/.glb found (recursively, in name order): whether `spectrace import-gltf` imports it, whether the
imported scene renders, its triangles (each mesh once, however many nodes place it), materials, lights (punctual
lights and emitting shapes) and cameras, and for each failure the one line spectrace gives (a traceback here is a
bug: the script prints it and counts it). The files are public sample models fetched apart from the project;
nothing here writes into their folders."""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
import traceback
from dataclasses import dataclass
from pathlib import Path

from spectrace.errors import SpectraceError


@dataclass
class Row:
    file: str
    imported: bool = False
    rendered: bool | None = None
    triangles: int = 0
    materials: int = 0
    lights: int = 0
    cameras: int = 0
    warnings: int = 0
    reason: str = ""
    crashed: bool = False


def _counts(path: Path) -> tuple[int, int]:
    """(materials, cameras) the file declares, read from its JSON (0 where the JSON does not read)."""
    try:
        from spectrace.interop.gltf.document import GltfDocument

        doc = GltfDocument(path)
        return len(doc.array("materials")), len(doc.array("cameras"))
    except Exception:
        return 0, 0


def _lights(data: dict) -> int:
    emitting = sum(1 for shape in data.get("shapes", []) if "emitter" in shape)
    return emitting + sum(1 for light in data.get("lights", []) if light.get("type") != "constant")


def sample(path: Path, size: int, spp: int, device: str | None, render: bool) -> Row:
    from spectrace.api import render as render_scene
    from spectrace.interop.gltf import gltf_scene_data, import_gltf
    from spectrace.scene import load_scene

    row = Row(str(path))
    row.materials, row.cameras = _counts(path)
    with tempfile.TemporaryDirectory(prefix="gltf-sample-") as folder:
        toml_path = Path(folder) / "scene.toml"
        try:
            data, ctx = gltf_scene_data(path, toml_path)
            notes = import_gltf(path, toml_path)
        except SpectraceError as failure:
            row.reason = str(failure)
            return row
        except Exception:
            row.crashed = True
            row.reason = "CRASH " + traceback.format_exc().strip().splitlines()[-1]
            traceback.print_exc()
            return row
        row.imported = True
        row.warnings = sum(1 for note in notes if note.startswith("warning: "))
        row.triangles = sum(len(mesh.faces) for mesh in ctx.meshes.values())
        row.lights = _lights(data)
        if not render:
            return row
        try:
            scene = load_scene(toml_path)
            aspect = scene.height / scene.width
            scene = scene.with_overrides(width=size, height=max(1, round(size * aspect)), spp=spp)
            render_scene(scene, device=device, progress=False)
            row.rendered = True
        except SpectraceError as failure:
            row.rendered = False
            row.reason = str(failure)
        except Exception:
            row.rendered = False
            row.crashed = True
            row.reason = "CRASH " + traceback.format_exc().strip().splitlines()[-1]
            traceback.print_exc()
    return row


def _mark(value: bool | None) -> str:
    return "-" if value is None else ("yes" if value else "NO")


def table(rows: list[Row], root: Path | None) -> str:
    def shown(file: str) -> str:
        return str(Path(file).relative_to(root)) if root is not None else file

    lines = [
        "| file | imported | rendered | triangles | materials | lights | cameras | warnings |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for row in rows:
        lines.append(
            f"| {shown(row.file)} | {_mark(row.imported)} | {_mark(row.rendered)} | {row.triangles} | "
            f"{row.materials} | {row.lights} | {row.cameras} | {row.warnings} |"
        )
    failures = [row for row in rows if row.reason]
    if failures:
        lines += ["", "Failures:"]
        lines += [f"- {shown(row.file)}: {row.reason.replace(row.file, Path(row.file).name)}" for row in failures]
    imported = sum(row.imported for row in rows)
    rendered = sum(bool(row.rendered) for row in rows)
    crashed = sum(row.crashed for row in rows)
    lines += ["", f"{len(rows)} files: {imported} imported, {rendered} rendered, {crashed} crashed"]
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("folders", nargs="+", type=Path)
    parser.add_argument("--size", type=int, default=64, help="image width in pixels")
    parser.add_argument("--spp", type=int, default=4)
    parser.add_argument("--device", default=None)
    parser.add_argument("--no-render", action="store_true", help="import only")
    parser.add_argument("--json", type=Path, help="also write the rows as JSON here")
    args = parser.parse_args(argv)
    files = sorted(
        {
            path
            for folder in args.folders
            for path in ([folder] if folder.is_file() else folder.rglob("*"))
            if path.suffix.lower() in (".gltf", ".glb") and path.is_file()
        }
    )
    rows = []
    for path in files:
        row = sample(path, args.size, args.spp, args.device, not args.no_render)
        print(f"{_mark(row.imported):>3} {_mark(row.rendered):>3} {path}  {row.reason}", file=sys.stderr, flush=True)
        rows.append(row)
    root = Path(os.path.commonpath([path.parent for path in files])) if files else None
    print(table(rows, root))
    if args.json:
        args.json.write_text(json.dumps([row.__dict__ for row in rows], indent=1))
    return 1 if any(row.crashed for row in rows) else 0


if __name__ == "__main__":
    sys.exit(main())
