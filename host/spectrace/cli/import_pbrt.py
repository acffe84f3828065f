"""`spectrace import-pbrt SCENE.pbrt -o OUT.toml`: a pbrt-v4 scene as a spectrace scene file (docs/pbrt.md)."""

import os
from pathlib import Path
from typing import Annotated

import typer
from rich.console import Console

from spectrace.errors import SpectraceError
from spectrace.interop.pbrt import import_pbrt
from spectrace.interop.pbrt.lights import AREA_LIGHTS, LIGHTS
from spectrace.interop.pbrt.materials import IMPORTED_MATERIALS
from spectrace.interop.pbrt.placeholders import MISSING_ASSETS
from spectrace.interop.pbrt.shapes import SHAPES
from spectrace.interop.pbrt.textures import TEXTURES


def import_pbrt_command(
    scene: Annotated[Path, typer.Argument(help="pbrt-v4 scene (.pbrt).")],
    # A string, not a Path: a Path would drop the trailing slash of "-o folder/", which names a folder.
    output: Annotated[
        str, typer.Option("--output", "-o", metavar="OUT.toml", help="spectrace scene file to write (TOML).")
    ],
    strict: Annotated[
        bool, typer.Option("--strict", help="Fail if anything in the file is not imported (default: warn).")
    ] = False,
    missing_assets: Annotated[
        str,
        typer.Option(
            "--missing-assets",
            metavar="refuse|placeholder",
            help="A missing mesh, image or data file: refuse the scene (default), or import a placeholder for it, "
            "each one a warning (for surveys of scene collections without their assets).",
        ),
    ] = "refuse",
) -> None:
    if missing_assets not in MISSING_ASSETS:
        raise SpectraceError(f"'{missing_assets}': give one of {', '.join(MISSING_ASSETS)}", where="--missing-assets")
    if output.endswith(("/", os.sep)) or not Path(output).name:
        raise SpectraceError("names a folder; give the path of the TOML file to write", where=output)
    from spectrace.resources import resolve_scene_path

    scene = resolve_scene_path(scene, (".pbrt",))  # a bare name: NAME.pbrt here
    warnings, notes = import_pbrt(scene, Path(output), strict=strict, option="--output", missing_assets=missing_assets)
    console = Console(stderr=True, soft_wrap=True, markup=False)  # each line on one line
    for warning in warnings:
        console.print(f"warning: {warning}", highlight=False, markup=False)
    for note in notes:
        console.print(f"note: {note}", highlight=False, markup=False)
    console.print(f"wrote {output}", highlight=False, markup=False)


import_pbrt_command.__doc__ = (
    f"Convert a pbrt-v4 scene to a spectrace TOML scene (shapes {', '.join(SHAPES)}; materials "
    f"{', '.join(IMPORTED_MATERIALS)}; textures {', '.join(TEXTURES)}; lights {', '.join(LIGHTS)}, area "
    f"{', '.join(AREA_LIGHTS)}). Meshes and environment maps go to a folder OUT_assets beside OUT.toml. "
    "Parameters and directives not imported are listed as warnings (--strict: an error); entities spectrace "
    "cannot represent are an error naming file:line. The TOML is checked by loading it before it and OUT_assets "
    "replace the earlier ones: a failed import leaves an earlier import as it was."
)
