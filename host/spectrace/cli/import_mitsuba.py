"""`spectrace import-mitsuba SCENE.xml -o OUT.toml`: a Mitsuba 3 scene as a spectrace scene file."""

import os
from pathlib import Path
from typing import Annotated

import typer
from rich.console import Console

from spectrace.errors import SpectraceError
from spectrace.interop.mitsuba import WARNING_PREFIX, import_mitsuba, supported_text


def import_mitsuba_command(
    scene: Annotated[Path, typer.Argument(help="Mitsuba 3 scene (XML), or a bundled one's name (veach_mis).")],
    # A string, not a Path: a Path would drop the trailing slash of "-o folder/", which names a folder.
    output: Annotated[
        str, typer.Option("--output", "-o", metavar="OUT.toml", help="spectrace scene file to write (TOML).")
    ],
    define: Annotated[
        list[str] | None,
        typer.Option("--define", "-D", help="Set a $parameter, NAME=VALUE (repeatable), as Mitsuba's -D."),
    ] = None,
    strict: Annotated[
        bool, typer.Option("--strict", help="Refuse the scene when it has properties spectrace does not import.")
    ] = False,
) -> None:
    if output.endswith(("/", os.sep)) or not Path(output).name:
        raise SpectraceError("names a folder; give the path of the TOML file to write", where=output)
    parameters = {}
    for item in define or []:
        name, separator, value = item.partition("=")
        if not separator or not name:
            raise SpectraceError(f"expected NAME=VALUE, got '{item}'", where="--define")
        parameters[name] = value
    from spectrace.resources import resolve_scene_path

    scene = resolve_scene_path(scene, (".xml",))  # a bare name: NAME.xml here, or a bundled scene
    notes = import_mitsuba(scene, Path(output), parameters, strict=strict, option="--output")
    console = Console(stderr=True, soft_wrap=True, markup=False)  # each note on one line
    for note in notes:
        console.print(note if note.startswith(WARNING_PREFIX) else f"note: {note}", highlight=False, markup=False)
    console.print(f"wrote {output}", highlight=False, markup=False)


# The help lists the plugins from the importer's table (built from the materials' and lights' registries). This
# module is imported only when the command runs (spectrace.cli.LAZY_COMMANDS), so the importer's imports cost
# nothing elsewhere.
import_mitsuba_command.__doc__ = (
    f"Convert a Mitsuba 3 XML scene to a spectrace TOML scene ({supported_text()}). Unsupported plugins are all "
    "named in one error; choices spectrace makes differently (pixel filter, sampler) are printed as notes, and "
    "every property "
    "spectrace does not know as a warning (--strict: an error). The TOML "
    "is checked by loading it before it and the files beside it replace the earlier ones (a failed import leaves "
    "an earlier import as it was); "
    "render it with `spectrace render OUT.toml`."
)
