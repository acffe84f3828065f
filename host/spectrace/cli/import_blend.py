"""`spectrace import-blend SCENE.blend -o OUT.toml`: a Blender file's scene as a spectrace scene file."""

import os
from pathlib import Path
from typing import Annotated

import typer
from rich.console import Console

from spectrace.errors import SpectraceError
from spectrace.interop.blender import WARNING_PREFIX, import_blend


def import_blend_command(
    blend: Annotated[Path, typer.Argument(help="Blender file (.blend).")],
    # A string, not a Path: a Path would drop the trailing slash of "-o folder/", which names a folder.
    output: Annotated[
        str, typer.Option("--output", "-o", metavar="OUT.toml", help="spectrace scene file to write (TOML).")
    ],
    strict: Annotated[
        bool, typer.Option("--strict", help="Refuse the file when it holds what spectrace does not import.")
    ] = False,
) -> None:
    """Convert a Blender file's active scene, as Blender evaluates it (modifiers, geometry nodes and instances
    applied), to a spectrace TOML scene, its meshes (PLY) and textures (PNG) in a folder beside it: meshes,
    Principled and other common BSDF nodes with image textures, point, spot, sun and area lights in Blender's
    units, the world and the camera. Needs Blender's Python module (pip install bpy; docs/blender.md). What the
    scene holds that is not imported is a warning (--strict: an error)."""
    if output.endswith(("/", os.sep)) or not Path(output).name:
        raise SpectraceError("names a folder; give the path of the TOML file to write", where=output)
    from spectrace.interop.blender import SUFFIXES
    from spectrace.resources import resolve_scene_path

    blend = resolve_scene_path(blend, SUFFIXES)  # a bare name: NAME.blend here
    notes = import_blend(blend, Path(output), strict=strict, option="--output")
    console = Console(stderr=True, soft_wrap=True, markup=False)  # each note on one line
    for note in notes:
        console.print(note if note.startswith(WARNING_PREFIX) else f"note: {note}", highlight=False, markup=False)
    console.print(f"wrote {output}", highlight=False, markup=False)
