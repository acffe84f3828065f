"""`spectrace import-gltf MODEL.glb -o OUT.toml`: a glTF 2.0 file as a spectrace scene file."""

import os
from pathlib import Path
from typing import Annotated

import typer
from rich.console import Console

from spectrace.errors import SpectraceError
from spectrace.interop.gltf import MATERIAL_MODELS, WARNING_PREFIX, import_gltf


def import_gltf_command(
    model: Annotated[Path, typer.Argument(help="glTF 2.0 file (.gltf or .glb).")],
    # A string, not a Path: a Path would drop the trailing slash of "-o folder/", which names a folder.
    output: Annotated[
        str, typer.Option("--output", "-o", metavar="OUT.toml", help="spectrace scene file to write (TOML).")
    ],
    camera: Annotated[
        str | None,
        typer.Option(help="The camera to import: its index in the file's cameras, or its or its node's name."),
    ] = None,
    materials: Annotated[
        str,
        typer.Option(
            help="principled (glTF's metallic-roughness model) or diffuse (the base colour only, Lambertian: a "
            "preview, or for a renderer without the principled material)."
        ),
    ] = "principled",
    strict: Annotated[
        bool, typer.Option("--strict", help="Refuse the file when it holds what spectrace does not import.")
    ] = False,
) -> None:
    """Convert a glTF 2.0 file to a spectrace TOML scene, its meshes (PLY) and textures (PNG) in a folder beside
    it: nodes, meshes, materials, cameras, KHR_lights_punctual (candela, lux) and emissive materials. What the file
    holds that is not imported is a warning (--strict: an error). The TOML is checked by loading it before it and
    its folder replace the earlier ones; render it with `spectrace render OUT.toml` (or render the glTF file
    directly: `spectrace render MODEL.glb -o image.png`)."""
    if output.endswith(("/", os.sep)) or not Path(output).name:
        raise SpectraceError("names a folder; give the path of the TOML file to write", where=output)
    if materials not in MATERIAL_MODELS:
        raise SpectraceError(
            f"unknown material model '{materials}' (use {' or '.join(MATERIAL_MODELS)})", "--materials"
        )
    from spectrace.interop.gltf import SUFFIXES
    from spectrace.resources import resolve_scene_path

    model = resolve_scene_path(model, SUFFIXES)  # a bare name: NAME.gltf or NAME.glb here
    notes = import_gltf(model, Path(output), camera, materials, strict=strict, option="--output")
    console = Console(stderr=True, soft_wrap=True, markup=False)  # each note on one line
    for note in notes:
        console.print(note if note.startswith(WARNING_PREFIX) else f"note: {note}", highlight=False, markup=False)
    console.print(f"wrote {output}", highlight=False, markup=False)
