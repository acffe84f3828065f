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

import tomllib
from pathlib import Path
from typing import Annotated, Any

import typer

from spectrace.cli.common import DeviceOption, console
from spectrace.errors import SpectraceError

KINDS = ("display", "render")
DISPLAY_KEYS = ("display", "rgb", "observer", "white_luminance")


def _say(text: str) -> None:
    console.print(text, highlight=False, markup=False)


def read_spec(path: Path) -> tuple[str, dict[str, Any], dict[str, list]]:
    """(kind, the [sweep] table, the [grid] table) of a sweep file, checked."""
    from spectrace.io.input_files import regular_file

    regular_file(path, what="sweep file")
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8-sig"))
    except (OSError, UnicodeDecodeError) as error:
        raise SpectraceError(f"cannot read the sweep file ({error})", where=str(path)) from None
    except tomllib.TOMLDecodeError as error:
        raise SpectraceError(f"TOML syntax error: {error}", where=str(path)) from None
    unknown = set(data) - {"sweep", "grid"}
    if unknown:
        raise SpectraceError(f"unknown table(s) {', '.join(sorted(unknown))} (use [sweep] and [grid])", where=str(path))
    settings, grid = data.get("sweep", {}), data.get("grid", {})
    kind = settings.get("kind")
    if kind not in KINDS:
        raise SpectraceError(f"kind must be one of {', '.join(KINDS)}, got {kind!r}", where=f"{path}: sweep.kind")
    if not grid:
        raise SpectraceError("the [grid] table is missing or empty", where=f"{path}: grid")
    if kind == "display":
        for name in grid:
            if name not in DISPLAY_KEYS:
                raise SpectraceError(f"unknown key (use {', '.join(DISPLAY_KEYS)})", where=f"{path}: grid.{name}")
        for name in ("display", "rgb"):
            if name not in grid:
                raise SpectraceError("a display sweep needs this key", where=f"{path}: grid.{name}")
    elif "scene" not in settings:
        raise SpectraceError("a render sweep names its scene file", where=f"{path}: sweep.scene")
    return kind, settings, grid


def sweep_items(path: Path, device: str | None) -> list:
    """The sweep's items; a render sweep's scenes are read here (any error names the file and key now, and the
    workers receive resolved scenes, no files)."""
    from spectrace import sweep as sweeping

    kind, settings, grid = read_spec(path)
    combinations = sweeping.grid_items({name: grid[name] for name in grid})
    if kind == "display":
        return [sweeping.SweepItem(params, sweeping.display_colour_item, params) for params in combinations]
    from spectrace.scene import load_scene

    scene_file = (path.parent / str(settings["scene"])).resolve()
    items = []
    for params in combinations:
        scene = load_scene(scene_file, overrides=params)
        items.append(sweeping.SweepItem(params, sweeping.render_item, {"scene": scene, "device": device}))
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
    quiet: Annotated[bool, typer.Option("--quiet", "-q", help="No progress bar.")] = False,
) -> None:
    """Run a grid of display computations or renders into one results table plus images; items already done in
    the output folder are skipped, so a rerun resumes. Ctrl-C stops after the items in flight."""
    from contextlib import nullcontext

    from spectrace import sweep as sweeping
    from spectrace.engine.stop_signals import StopOnSignals
    from spectrace.progress import progress_bar

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
                rows, computed = sweeping.run_items(items, output, None, draw, stop)
            else:
                from spectrace.distributed import connect

                with connect(cluster, workers, cluster_timeout) as client:
                    rows, computed = sweeping.run_items(items, output, client, draw, stop)
    _say(
        f"wrote {output / 'results.csv'} and results.json: {len(rows)}/{len(items)} items "
        f"({computed} computed now, {len(rows) - computed} already done)"
    )
    if len(rows) < len(items):
        raise typer.Exit(130)
