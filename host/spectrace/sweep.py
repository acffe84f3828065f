"""Experiments over a grid: one computation per combination of parameter values (displays x RGB triples x
observers, a scene's light temperature or material colour over a range), here or on a Dask cluster
(spectrace.distributed), into one results table plus the images.

Each finished item is saved at once as its own small JSON file (and its images) in the output folder, named by a
digest of its parameters: a rerun skips the items already there, so an interrupted sweep resumes where it stopped.
The table, `results.json` and `results.csv` (one row per item: its parameters, then its results), is written
from those files, in grid order, at the end of every run.
"""

from __future__ import annotations

import csv
import hashlib
import io
import itertools
import json
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from spectrace.errors import SpectraceError
from spectrace.image import Image
from spectrace.io.atomic import write_atomically

ITEMS_FOLDER = "items"
IMAGES_FOLDER = "images"


def grid_items(grid: Mapping[str, Sequence[Any]]) -> list[dict[str, Any]]:
    """Every combination of the grid's values, the last key varying fastest."""
    for name, values in grid.items():
        if isinstance(values, str | bytes) or not isinstance(values, Sequence) or len(values) == 0:
            raise SpectraceError(f"a grid entry must be a non-empty list of values, got {values!r}", where=name)
    names = list(grid)
    return [dict(zip(names, combination)) for combination in itertools.product(*(grid[name] for name in names))]


def item_key(params: Mapping[str, Any]) -> str:
    """A digest of the parameters: the item's file name, the same on every run."""
    text = json.dumps(params, sort_keys=True, default=str)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


@dataclass
class SweepItem:
    """One computation: `params` (what the table shows) and the call that computes it, function(**arguments),
    which returns a dict of numbers, strings and `Image`s (written as EXR files and named in the table)."""

    params: dict[str, Any]
    function: Callable[..., dict[str, Any]]
    arguments: dict[str, Any]


def _write_text(path: Path, text: str) -> None:
    write_atomically(path, lambda temp: temp.write_text(text, encoding="utf-8"))


def _save_item(out: Path, item: SweepItem, result: Mapping[str, Any]) -> dict[str, Any]:
    if not isinstance(result, Mapping):
        raise SpectraceError(
            f"a sweep function must return a dict, got {type(result).__name__}", where=str(item.params)
        )
    key = item_key(item.params)
    row: dict[str, Any] = dict(item.params)
    for name, value in result.items():
        if isinstance(value, Image):
            relative = Path(IMAGES_FOLDER) / f"{key}-{name}.exr"
            (out / IMAGES_FOLDER).mkdir(exist_ok=True)
            value.write(out / relative)
            row[name] = relative.as_posix()
        else:
            row[name] = value
    # The item's file last: it marks the item done, so its images are complete whenever it exists.
    _write_text(out / ITEMS_FOLDER / f"{key}.json", json.dumps({"params": item.params, "row": row}, default=_plain))
    return row


def _plain(value: Any) -> Any:
    """JSON for numpy numbers and arrays in results."""
    if hasattr(value, "tolist"):
        return value.tolist()
    return str(value)


def _load_row(out: Path, params: Mapping[str, Any]) -> dict[str, Any] | None:
    path = out / ITEMS_FOLDER / f"{item_key(params)}.json"
    if not path.is_file():
        return None
    try:
        saved = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None  # damaged: computed again
    if json.dumps(saved.get("params"), sort_keys=True) != json.dumps(
        json.loads(json.dumps(params, default=_plain)), sort_keys=True
    ):
        return None
    return saved.get("row")


def write_table(out: Path, rows: list[dict[str, Any]]) -> None:
    """results.json and results.csv (columns: every key, in first-seen order; lists as JSON text)."""
    _write_text(out / "results.json", json.dumps(rows, indent=1, default=_plain))
    columns: list[str] = []
    for row in rows:
        columns += [name for name in row if name not in columns]
    text = io.StringIO()
    writer = csv.DictWriter(text, columns, lineterminator="\n")
    writer.writeheader()
    for row in rows:
        writer.writerow({k: json.dumps(v, default=_plain) if isinstance(v, list | dict) else v for k, v in row.items()})
    _write_text(out / "results.csv", text.getvalue())


def run_items(
    items: list[SweepItem],
    out_dir: str | Path,
    client: Any = None,
    progress: Callable[[int, int], None] | None = None,
    stop: Callable[[], bool] | None = None,
) -> tuple[list[dict[str, Any]], int]:
    """Compute the items not already in `out_dir` (here, or as Dask tasks on `client`), save each as it finishes,
    and write the table of every item finished so far. Returns (the rows, how many were computed now)."""
    out = Path(out_dir)
    try:
        (out / ITEMS_FOLDER).mkdir(parents=True, exist_ok=True)
    except OSError as error:
        raise SpectraceError(f"cannot create the output folder ({error.strerror or error})", where=str(out)) from None
    rows: list[dict[str, Any] | None] = [_load_row(out, item.params) for item in items]
    todo = [index for index, row in enumerate(rows) if row is None]
    should_stop = stop or (lambda: False)
    computed = 0

    def finished(index: int, result: Mapping[str, Any]) -> None:
        nonlocal computed
        rows[index] = _save_item(out, items[index], result)
        computed += 1
        if progress is not None:
            progress(len(items) - len(todo) + computed, len(items))

    try:
        if progress is not None:
            progress(len(items) - len(todo), len(items))
        if client is None:
            for index in todo:
                if should_stop():
                    break
                finished(index, items[index].function(**items[index].arguments))
        else:
            _run_on_client(client, items, todo, finished, should_stop)
    finally:
        write_table(out, [row for row in rows if row is not None])
    return [row for row in rows if row is not None], computed


def _run_on_client(client: Any, items: list[SweepItem], todo: list[int], finished, stop) -> None:
    from spectrace.distributed import require_distributed, task_failure

    distributed = require_distributed("--cluster")
    futures = {client.submit(items[i].function, **items[i].arguments, pure=False): i for i in todo}
    pending = set(futures)
    try:
        while pending:
            if stop():
                return
            try:
                done, pending = distributed.wait(pending, timeout=0.2, return_when="FIRST_COMPLETED")
            except TimeoutError:
                continue
            for future in done:
                try:
                    result = future.result()
                except Exception as error:  # the task's own exception, re-raised by Dask
                    raise task_failure(error, f"sweep item {items[futures[future]].params}") from None
                finished(futures[future], result)
    finally:
        if pending:
            client.cancel(list(pending))


def sweep(
    function: Callable[..., dict[str, Any]],
    grid: Mapping[str, Sequence[Any]],
    out_dir: str | Path,
    client: Any = None,
    progress: Callable[[int, int], None] | None = None,
) -> list[dict[str, Any]]:
    """function(**params) for every combination of the grid's values (e.g. {"display": [...], "rgb": [...],
    "observer": [...]}), here or on the Dask `client`'s workers (then `function` must be importable there: a
    module-level function). Returns the table's rows; see the module docstring for the files and the resuming."""
    items = [SweepItem(params, function, params) for params in grid_items(grid)]
    return run_items(items, out_dir, client, progress)[0]


# ---------------------------------------------------------------- the computations `spectrace sweep` offers


def display_colour_item(display: str, rgb: Sequence[float], observer: str = "cie1931_2", white_luminance=100.0):
    """The colour an RGB triple makes on a display, seen by one observer (docs/displays.md's conventions): its
    photometric XYZ (cd/m²), chromaticity and CIELAB against the viewing conditions' reference white."""
    import numpy as np

    from spectrace.displays import Observer, ViewingConditions, load_display
    from spectrace.displays.compare import display_colour

    try:
        chosen = Observer(observer)
    except ValueError:
        names = ", ".join(member.value for member in Observer)
        raise SpectraceError(f"unknown observer '{observer}' (use {names})", where="observer") from None
    viewing = ViewingConditions(float(white_luminance))
    colour = display_colour(load_display(display, where="display"), np.asarray(rgb, float), viewing)
    viewed = colour.display
    xyz = viewed.primaries_matrix(chosen) @ colour.drive
    lab = colour.lab[chosen]
    total = float(xyz.sum())
    x, y = (float(xyz[0] / total), float(xyz[1] / total)) if total > 0 else (0.0, 0.0)
    return {
        "X": float(xyz[0]),
        "Y": float(xyz[1]),
        "Z": float(xyz[2]),
        "x": x,
        "y": y,
        "L": float(lab[0]),
        "a": float(lab[1]),
        "b": float(lab[2]),
    }


def render_item(scene: Any, device: str | None = None) -> dict[str, Any]:
    """A scene's image, and its mean film XYZ (W/(m² sr)-weighted CIE XYZ of the radiance, per pixel mean)."""
    from spectrace.api import render

    image = render(scene, device=device, progress=False)
    mean = image.xyz.reshape(-1, 3).astype("float64").mean(axis=0)
    return {
        "image": image,
        "X_mean": float(mean[0]),
        "Y_mean": float(mean[1]),
        "Z_mean": float(mean[2]),
        "device": image.device,
    }
