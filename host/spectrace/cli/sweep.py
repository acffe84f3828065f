"""`spectrace sweep SPEC.toml -o FOLDER`: a grid of display computations or renders (spectrace.sweep), here or on
a Dask cluster (--workers, --cluster), resumable. The spec file:

    [sweep]
    kind = "display"                     # display colours: grid keys display, rgb, observer, white_luminance
    [grid]
    display = ["LCD-Apple_WLED", "OLED-SonyPVM2541"]
    rgb = [[1.0, 0.0, 0.0], [0.5, 0.5, 0.5]]
    observer = ["cie1931_2", "cie1964_10"]

or kind = "render" with `scene = "room.toml"` (relative to the spec) and grid keys that are the scene file's dotted
key paths ("film.width", "materials.red.reflectance"), each set before the scene is read.
"""

from __future__ import annotations

import json
import tomllib
from pathlib import Path
from typing import Annotated, Any

import typer

from spectrace.cli.common import DeviceOption, console
from spectrace.cli.scene_settings import override_at_fault
from spectrace.errors import SpectraceError

KINDS = ("display", "render")
SWEEP_KEYS = {"display": ("kind",), "render": ("kind", "scene", "formats")}
# Image files a render sweep may write for each item (`formats = ["exr", "png"]`; EXR alone by default).
SWEEP_FORMATS = ("exr", "png", "tif", "jpg", "pfm")


def _say(text: str) -> None:
    console.say(text)


def _key_path(table: str, name: str) -> str:
    """A key of the table as a key path; a key that is no bare name (a scene's dotted key path) quoted."""
    return f"{table}.{name}" if name.isidentifier() else f"{table}.{json.dumps(name, ensure_ascii=False)}"


def read_spec(path: Path) -> tuple[str, dict[str, Any], dict[str, list]]:
    """(kind, the [sweep] table, the [grid] table) of a sweep file, checked: a spec of the wrong shape is one
    SpectraceError naming the file and the key path."""
    from spectrace.io.input_files import regular_file
    from spectrace.sweep import value_text

    regular_file(path, what="sweep file")
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8-sig"))
    except (OSError, UnicodeDecodeError) as error:
        raise SpectraceError(f"cannot read the sweep file ({error})", where=str(path)) from None
    except tomllib.TOMLDecodeError as error:
        raise SpectraceError(f"TOML syntax error: {error}", where=str(path)) from None
    except RecursionError:  # tomllib parses arrays and inline tables recursively
        raise SpectraceError("arrays or inline tables nested too deep to parse", where=str(path)) from None
    unknown = set(data) - {"sweep", "grid"}
    if unknown:
        raise SpectraceError(f"unknown table(s) {', '.join(sorted(unknown))} (use [sweep] and [grid])", where=str(path))
    for table in ("sweep", "grid"):
        if not isinstance(data.get(table, {}), dict):
            value = data[table]
            got = type(value).__name__
            if isinstance(value, list):
                got = f"an array of tables ([[{table}]])" if all(isinstance(v, dict) for v in value) else "an array"
            raise SpectraceError(f"expected a table ([{table}]), got {got}", where=f"{path}: {table}")
    settings, grid = data.get("sweep", {}), data.get("grid", {})
    kind = settings.get("kind")
    if not isinstance(kind, str) or kind not in KINDS:
        raise SpectraceError(
            f"kind must be one of {', '.join(KINDS)}, got {value_text(kind)}", where=f"{path}: sweep.kind"
        )
    for name in settings:
        if name not in SWEEP_KEYS[kind]:
            allowed = ", ".join(SWEEP_KEYS[kind])
            where = f"{path}: {_key_path('sweep', name)}"
            raise SpectraceError(f"unknown key in a {kind} sweep (use {allowed})", where=where)
    if not grid:
        raise SpectraceError("the [grid] table is missing or empty", where=f"{path}: grid")
    for name, values in grid.items():
        where = f"{path}: {_key_path('grid', name)}"
        if isinstance(values, dict):
            hint = ' (quote a dotted key path: "film.width" = [...])' if kind == "render" else ""
            raise SpectraceError(f"a grid entry must be a list of values, got a table{hint}", where=where)
        if not isinstance(values, list) or not values:
            raise SpectraceError(
                f"a grid entry must be a non-empty list of values, got {value_text(values)}", where=where
            )
    if kind == "display":
        _check_display_grid(path, grid)
    _check_no_repeats(path, grid)
    if kind == "render":
        if "scene" not in settings:
            raise SpectraceError("a render sweep names its scene file", where=f"{path}: sweep.scene")
        if not isinstance(settings["scene"], str) or not settings["scene"]:
            raise SpectraceError(
                f"the scene is a file name, got {value_text(settings['scene'])}", where=f"{path}: sweep.scene"
            )
    formats = settings.get("formats", ["exr"])
    if (
        not isinstance(formats, list)
        or not formats
        or any(f not in SWEEP_FORMATS for f in formats)
        or len(set(formats)) < len(formats)
    ):
        raise SpectraceError(
            f"formats must be a list of distinct image formats among {', '.join(SWEEP_FORMATS)}, "
            f"got {value_text(formats)}",
            where=f"{path}: sweep.formats",
        )
    return kind, settings, grid


def _check_no_repeats(path: Path, grid: dict[str, list]) -> None:
    """A value twice in one grid entry would make two items of the same key, one row twice in the table."""
    for name, values in grid.items():
        seen: dict[str, int] = {}
        for index, value in enumerate(values):
            text = json.dumps(value, sort_keys=True, default=str)
            if text in seen:
                raise SpectraceError(
                    f"repeats the value at [{seen[text]}]", where=f"{path}: {_key_path('grid', name)}[{index}]"
                )
            seen[text] = index


def _check_display_grid(path: Path, grid: dict[str, list]) -> None:
    from spectrace.sweep import DISPLAY_ARGUMENTS, display_argument

    for name in grid:
        if name not in DISPLAY_ARGUMENTS:
            raise SpectraceError(
                f"unknown key (use {', '.join(DISPLAY_ARGUMENTS)})", where=f"{path}: {_key_path('grid', name)}"
            )
    for name in ("display", "rgb"):
        if name not in grid:
            raise SpectraceError("a display sweep needs this key", where=f"{path}: grid.{name}")
    for name, values in grid.items():
        for index, value in enumerate(values):
            try:
                display_argument(name, value)
            except SpectraceError as error:
                # The argument's own complaint, or a display file's (which names that file and line).
                message = error.message if error.where == name else str(error)
                raise SpectraceError(message, where=f"{path}: {_key_path('grid', name)}[{index}]") from None


def sweep_items(path: Path, device: str | None) -> list:
    """The sweep's items; a render sweep's scenes are read here (any error names the file and key now, and the
    workers receive resolved scenes, no files). Each item's key covers what determines it: its parameters, the
    files it reads (by content) and the program."""
    from spectrace import sweep as sweeping

    kind, settings, grid = read_spec(path)
    combinations = sweeping.grid_items({name: grid[name] for name in grid}, where=str(path))
    digests = sweeping.FileDigests()
    if kind == "display":
        return [
            sweeping.SweepItem(
                params, sweeping.display_colour_item, params, sweeping.display_inputs(params["display"], digests)
            )
            for params in combinations
        ]
    from spectrace.io.input_files import regular_file
    from spectrace.resources import resolve_scene_path
    from spectrace.scene import load_scene

    try:  # beside the spec, or a bundled scene's name
        named = resolve_scene_path(settings["scene"], folder=path.parent)
    except SpectraceError as error:
        raise SpectraceError(error.message, where=f"{path}: sweep.scene") from None
    scene_file = regular_file(named, where=f"{path}: sweep.scene", what="scene file")
    scene_file = scene_file.resolve()
    items = []
    for params in combinations:
        try:
            scene = load_scene(scene_file, overrides=params)
            inputs = sweeping.scene_inputs(scene_file, params, digests)
        except SpectraceError as error:
            name = override_at_fault(error, scene_file, params)
            if name is None:  # the scene's own fault, named with its key path
                raise SpectraceError(str(error), where=f"{path}: sweep.scene") from None
            index = grid[name].index(params[name])
            raise SpectraceError(
                f"{error.message} (in {scene_file.name})",
                where=f"{path}: {_key_path('grid', name)}[{index}]",
            ) from None
        inputs["device"] = device
        arguments = {"scene": scene, "device": device}
        formats = tuple(settings.get("formats", ["exr"]))
        items.append(sweeping.SweepItem(params, sweeping.render_item, arguments, inputs, image_formats=formats))
    return items


def sweep_command(
    spec: Annotated[Path, typer.Argument(help="Sweep file (TOML): [sweep] kind, [grid] of values.")],
    output: Annotated[Path, typer.Option("--output", "-o", help="Folder for results.json, results.csv, images.")],
    device: DeviceOption = None,
    cluster: Annotated[str | None, typer.Option(help="Run the items on the Dask scheduler at this address.")] = None,
    workers: Annotated[
        int | None, typer.Option(help="Run the items on a Dask LocalCluster of N worker processes.", min=1)
    ] = None,
    cluster_timeout: Annotated[
        float, typer.Option(help="Seconds to wait for the --cluster scheduler to answer.", min=0.1)
    ] = 30.0,
    quiet: Annotated[
        bool, typer.Option("--quiet", "-q", help="No progress bar and no messages but warnings and errors.")
    ] = False,
) -> None:
    """Run a grid of display computations or renders into one results table plus images; items already done in
    the output folder are skipped, so a rerun resumes. Ctrl-C stops after the items in flight."""
    from contextlib import nullcontext

    from spectrace import sweep as sweeping
    from spectrace.engine.stop_signals import StopOnSignals
    from spectrace.progress import progress_bar

    console.quiet = quiet
    if cluster is not None and workers is not None:
        raise SpectraceError("give --cluster or --workers, not both", where="--workers")
    if cluster is not None or workers is not None:
        from spectrace.distributed import require_distributed

        require_distributed("--cluster" if cluster is not None else "--workers")
    items = sweep_items(spec, device)
    with StopOnSignals() as stop:
        bar = nullcontext(None) if quiet else progress_bar(len(items), 0, console.rich(), unit="items")
        with bar as draw:
            if cluster is None and workers is None:
                rows, computed = sweeping.run_items(items, output, None, draw, stop, "--output")
            else:
                from spectrace.distributed import connect

                with connect(cluster, workers, cluster_timeout) as client:
                    rows, computed = sweeping.run_items(items, output, client, draw, stop, "--output")
    _say(
        f"wrote {output / 'results.csv'} and results.json: {len(rows)}/{len(items)} items "
        f"({computed} computed now, {len(rows) - computed} already done)"
    )
    if len(rows) < len(items):
        raise typer.Exit(130)
