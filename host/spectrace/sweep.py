"""Experiments over a grid: one computation per combination of parameter values (displays x RGB triples x
observers, a scene's light temperature or material colour over a range), here or on a Dask cluster
(spectrace.distributed), into one results table plus the images.

Each finished item is saved at once as its own small JSON file (and its images) in the output folder, named by its key:
a digest of everything that determines its result, namely the function, its parameters, the inputs it reads
(`SweepItem.inputs`: a scene's file and every file it names, by content) and the program (the package version, the
kernel sources, the host code and the shipped spectra). A rerun skips the items whose key it finds saved, so an
interrupted sweep resumes where it stopped, while an item whose scene, asset or program changed is computed again; a
file saved without the key it should hold (damaged, or from an older spectrace) is not trusted either. The table,
`results.json` and `results.csv` (one row per item: its parameters, then its results), is written from those files, in
grid order, at the end of every run.
"""

from __future__ import annotations

import contextlib
import csv
import hashlib
import io
import itertools
import json
import os
import re
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from functools import cache
from pathlib import Path
from typing import Any

from spectrace.errors import SpectraceError
from spectrace.film.image import Image
from spectrace.io.atomic import write_atomically
from spectrace.io.input_files import is_regular_file

ITEMS_FOLDER = "items"
IMAGES_FOLDER = "images"
# Part of every key: a new layout of the item files, or a new meaning of their contents, retires the old files.
_ITEM_FORMAT = "spectrace-sweep-item-2"
# Every item is held in memory (a render sweep's scenes among them) before the first is computed.
MAX_ITEMS = 100_000


def grid_items(grid: Mapping[str, Sequence[Any]], where: str | None = None) -> list[dict[str, Any]]:
    """Every combination of the grid's values, the last key varying fastest. `where` (a file) prefixes the key
    paths that errors name."""
    prefix = f"{where}: grid." if where else ""
    count = 1
    for name, values in grid.items():
        if isinstance(values, str | bytes) or not isinstance(values, Sequence) or len(values) == 0:
            raise SpectraceError(
                f"a grid entry must be a non-empty list of values, got {value_text(values)}", where=f"{prefix}{name}"
            )
        count *= len(values)
    if count > MAX_ITEMS:
        sizes = " x ".join(str(len(values)) for values in grid.values())
        raise SpectraceError(
            f"the grid makes {count:.3g} items ({sizes}), more than the {MAX_ITEMS} one sweep may hold",
            where=f"{where}: grid" if where else None,
        )
    names = list(grid)
    return [dict(zip(names, combination)) for combination in itertools.product(*(grid[name] for name in names))]


def value_text(value: Any) -> str:
    """A value as a spec (TOML) or JSON would show it (`true`, not Python's `True`), shortened for a message."""
    try:
        text = json.dumps(value, ensure_ascii=False, default=str)
    except ValueError:  # a structure that holds itself
        text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


@cache
def program_version() -> dict[str, str]:
    """What identifies this program's results: the package version, the kernel sources' digest (the one the
    program cache and checkpoints use), and digests of the host code and the shipped spectra, since the version
    number does not change with every edit of either."""
    from pathlib import Path

    import spectrace
    from spectrace.device.program_cache import files_digest, kernels_digest
    from spectrace.resources import kernels_dir, spectra_dir

    return {
        "version": spectrace.__version__,
        "kernels": kernels_digest(kernels_dir()),
        "host": files_digest(Path(spectrace.__file__).resolve().parent, (".py",)),
        "spectra": files_digest(spectra_dir(), (".csv",)),
    }


def _canonical(value: Any) -> str:
    return json.dumps(value, sort_keys=True, default=_plain)


def item_key(
    params: Mapping[str, Any], function: Callable[..., Any] | None = None, inputs: Mapping[str, Any] | None = None
) -> str:
    """The item's key (SHA-256, hex): a digest of everything that determines its result (the module docstring)."""
    name = None if function is None else f"{function.__module__}.{function.__qualname__}"
    text = _canonical(
        {
            "format": _ITEM_FORMAT,
            "program": program_version(),
            "function": name,
            "params": params,
            "inputs": inputs or {},
        }
    )
    return hashlib.sha256(text.encode()).hexdigest()


class FileDigests:
    """SHA-256 of input files, each file read once however many items name it (a file is taken to be unchanged
    while its size, modification time and inode are)."""

    def __init__(self) -> None:
        self._known: dict[tuple, str] = {}

    def __call__(self, path: Path, where: str) -> str:
        try:
            status = os.stat(path)
            identity = (str(Path(path).resolve()), status.st_size, status.st_mtime_ns, status.st_ino)
            if identity not in self._known:
                digest = hashlib.sha256()
                with open(path, "rb") as file:
                    while block := file.read(1 << 20):
                        digest.update(block)
                self._known[identity] = digest.hexdigest()
        except OSError as error:
            raise SpectraceError(f"cannot read '{path}' ({error.strerror or error})", where=where) from None
        return self._known[identity]


@dataclass
class SweepItem:
    """One computation: `params` (what the table shows) and the call that computes it, function(**arguments),
    which returns a dict of numbers, strings and `Image`s (written as EXR files and named in the table).
    `inputs`: whatever else determines the result (digests of the files it reads), JSON-able; part of its key."""

    params: dict[str, Any]
    function: Callable[..., dict[str, Any]]
    arguments: dict[str, Any]
    inputs: dict[str, Any] = field(default_factory=dict)
    # Files each Image result is written as, by suffix; the first one's name is the row's entry, the others' are
    # under NAME_SUFFIX (image_png).
    image_formats: tuple[str, ...] = ("exr",)

    @property
    def key(self) -> str:
        formats = {} if self.image_formats == ("exr",) else {"image_formats": list(self.image_formats)}
        return item_key(self.params, self.function, {**self.inputs, **formats})


# Characters kept in an image's name; any other run of characters becomes one "-" (file systems and shells
# take these everywhere).
_UNSAFE = re.compile(r"[^A-Za-z0-9._=+-]+")
_STEM_CHARS = 120  # with the result's name and suffix, well inside a file name's 255 bytes


def _value_stem(value: Any) -> str:
    if isinstance(value, str):
        return value
    if isinstance(value, list | tuple):
        return ",".join(_value_stem(v) for v in value)
    if isinstance(value, dict):  # an inline table of a scene's key: {value = 0.2} -> value=0.2
        return ",".join(f"{k}={_value_stem(v)}" for k, v in value.items())
    return value_text(value)


def image_stems(items: Sequence[SweepItem]) -> list[str]:
    """Each item's images' name stem, from its parameters (`spp=64_roughness=0.2`): unsafe characters replaced,
    cut short, and made unique (also where case is ignored, as on macOS and Windows) by the item's key where two
    would meet."""
    stems = []
    for item in items:
        parts = (_UNSAFE.sub("-", f"{name}={_value_stem(value)}").strip("-") for name, value in item.params.items())
        stem = "_".join(parts).strip(".") or "item"
        stems.append(stem[:_STEM_CHARS])
    counts: dict[str, int] = {}
    for stem in stems:
        counts[stem.casefold()] = counts.get(stem.casefold(), 0) + 1
    return [
        stem if counts[stem.casefold()] == 1 and len(stem) < _STEM_CHARS else f"{stem}-{item.key[:12]}"
        for stem, item in zip(stems, items)
    ]


def _item_file(out: Path, key: str) -> Path:
    return out / ITEMS_FOLDER / f"{key[:16]}.json"


def _write_text(path: Path, text: str) -> None:
    write_atomically(path, lambda temp: temp.write_text(text, encoding="utf-8"))


def _save_item(out: Path, item: SweepItem, result: Mapping[str, Any], stem: str | None = None) -> dict[str, Any]:
    if not isinstance(result, Mapping):
        raise SpectraceError(
            f"a sweep function must return a dict, got {type(result).__name__}", where=str(item.params)
        )
    key = item.key
    path = _item_file(out, key)
    row: dict[str, Any] = dict(item.params)
    images = []
    try:
        for name, value in result.items():
            if isinstance(value, Image):
                (out / IMAGES_FOLDER).mkdir(exist_ok=True)
                for index, suffix in enumerate(item.image_formats):
                    relative = Path(IMAGES_FOLDER) / f"{stem or key[:16]}-{name}.{suffix}"
                    value.write(out / relative)
                    row[name if index == 0 else f"{name}_{suffix}"] = relative.as_posix()
                    images.append(relative.as_posix())
            else:
                row[name] = value
        # The item's file last: it marks the item done, so its images are complete whenever it exists.
        saved = {"key": key, "params": item.params, "row": row, "images": images}
        _write_text(path, json.dumps(saved, default=_plain))
    except OSError as error:
        raise SpectraceError(
            f"cannot save the sweep item ({error.strerror or error}); the items finished before it are saved "
            "(rerun to resume)",
            where=str(path),
        ) from None
    return row


def _plain(value: Any) -> Any:
    """JSON for numpy numbers and arrays in results."""
    if hasattr(value, "tolist"):
        return value.tolist()
    return str(value)


def _load_row(out: Path, item: SweepItem) -> dict[str, Any] | None:
    """The saved row of the item, or None when it must be computed: not saved, damaged, saved under another key
    (other inputs or program, or an older file without a key) or missing one of its images."""
    key = item.key
    path = _item_file(out, key)
    if not is_regular_file(path):
        return None
    try:
        saved = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None  # damaged: computed again
    if not isinstance(saved, dict) or saved.get("key") != key or not isinstance(saved.get("row"), dict):
        return None
    images = saved.get("images")
    if not isinstance(images, list) or not all(isinstance(n, str) and is_regular_file(out / n) for n in images):
        return None
    return saved["row"]


def write_table(out: Path, rows: list[dict[str, Any]]) -> None:
    """results.json and results.csv (columns: every key, in first-seen order; lists as JSON text), each replaced
    whole or not at all."""
    columns: list[str] = []
    for row in rows:
        columns += [name for name in row if name not in columns]
    text = io.StringIO()
    writer = csv.DictWriter(text, columns, lineterminator="\n")
    writer.writeheader()
    for row in rows:
        writer.writerow({k: json.dumps(v, default=_plain) if isinstance(v, list | dict) else v for k, v in row.items()})
    tables = {"results.json": json.dumps(rows, indent=1, default=_plain), "results.csv": text.getvalue()}
    for name, content in tables.items():
        try:
            _write_text(out / name, content)
        except OSError as error:
            raise SpectraceError(
                f"cannot write the results table ({error.strerror or error}); the finished items are saved in "
                f"{out / ITEMS_FOLDER} (rerun to write the table)",
                where=str(out / name),
            ) from None


def run_items(
    items: list[SweepItem],
    out_dir: str | Path,
    client: Any = None,
    progress: Callable[[int, int], None] | None = None,
    stop: Callable[[], bool] | None = None,
    option: str = "the output folder",
) -> tuple[list[dict[str, Any]], int]:
    """Compute the items not already in `out_dir` (here, or as Dask tasks on `client`), save each as it finishes,
    and write the table of every item finished so far. Returns (the rows, how many were computed now).

    The folder is locked meanwhile (spectrace.io.output_lock): a second sweep into it would rewrite the table
    without the first one's rows, so it is refused at once, naming this one. option: what that refusal calls
    the folder (the command line's --output)."""
    from spectrace.io.output_lock import OutputLocks

    out = Path(out_dir)
    try:
        (out / ITEMS_FOLDER).mkdir(parents=True, exist_ok=True)
    except OSError as error:
        raise SpectraceError(f"cannot create the output folder ({error.strerror or error})", where=str(out)) from None
    with OutputLocks({option: out}, command="spectrace sweep"):
        return _run_items(items, out, client, progress, stop)


def _run_items(
    items: list[SweepItem],
    out: Path,
    client: Any,
    progress: Callable[[int, int], None] | None,
    stop: Callable[[], bool] | None,
) -> tuple[list[dict[str, Any]], int]:
    rows: list[dict[str, Any] | None] = [_load_row(out, item) for item in items]
    stems = image_stems(items)
    todo = [index for index, row in enumerate(rows) if row is None]
    should_stop = stop or (lambda: False)
    computed = 0

    def finished(index: int, result: Mapping[str, Any]) -> None:
        nonlocal computed
        rows[index] = _save_item(out, items[index], result, stems[index])
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
    except BaseException:
        # The table of what is finished, if it can be written; the first failure is the one to report.
        with contextlib.suppress(SpectraceError):
            write_table(out, [row for row in rows if row is not None])
        raise
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
    inputs: Mapping[str, Any] | None = None,
) -> list[dict[str, Any]]:
    """function(**params) for every combination of the grid's values (e.g. {"display": [...], "rgb": [...],
    "observer": [...]}), here or on the Dask `client`'s workers (then `function` must be importable there: a
    module-level function). `inputs`: anything else the results depend on (the digest of a file the function
    reads, a version of its own), JSON-able: a rerun with other inputs computes every item again. Returns the
    table's rows; see the module docstring for the files and the resuming."""
    items = [SweepItem(params, function, params, dict(inputs or {})) for params in grid_items(grid)]
    return run_items(items, out_dir, client, progress)[0]


# ---------------------------------------------------------------- the computations `spectrace sweep` offers


DISPLAY_ARGUMENTS = ("display", "rgb", "observer", "white_luminance")


def _is_number(value: Any) -> bool:
    # TOML and JSON booleans are Python bools, which are ints: a `true` is no number here; nor is an integer
    # beyond any float.
    if not isinstance(value, int | float) or isinstance(value, bool):
        return False
    try:
        float(value)
    except OverflowError:
        return False
    return True


def display_argument(name: str, value: Any) -> Any:
    """One argument of `display_colour_item`, checked and converted (a Display, an RGB array, an Observer, the
    ViewingConditions); a SpectraceError names the argument, or the display file at fault."""
    import numpy as np

    from spectrace.displays import Observer, ViewingConditions, load_display
    from spectrace.spectral.display_transfer import checked_rgb

    if name == "display":
        if not isinstance(value, str):
            raise SpectraceError(f"a display is a name or a display CSV file, got {value_text(value)}", where=name)
        return load_display(value, where=name)
    if name == "rgb":
        if isinstance(value, str | bytes) or not isinstance(value, Sequence) or not all(map(_is_number, value)):
            raise SpectraceError(f"an RGB triple is a list of 3 numbers, got {value_text(value)}", where=name)
        return checked_rgb(np.asarray(value, dtype=np.float64), where=name)
    if name == "observer":
        names = [member.value for member in Observer]
        if not isinstance(value, str) or value not in names:
            raise SpectraceError(f"unknown observer {value_text(value)} (use {', '.join(names)})", where=name)
        return Observer(value)
    if name == "white_luminance":
        if not _is_number(value):
            raise SpectraceError(f"a white luminance is a number of cd/m², got {value_text(value)}", where=name)
        try:
            return ViewingConditions(float(value))
        except SpectraceError as error:
            raise SpectraceError(error.message, where=name) from None
    raise SpectraceError(f"unknown key (use {', '.join(DISPLAY_ARGUMENTS)})", where=name)


def display_inputs(display: Any, digests: FileDigests | None = None) -> dict[str, Any]:
    """The inputs of a display item besides its parameters: the display CSV's digest when `display` names a file
    (a display known by name is the program's own data)."""
    if isinstance(display, str) and is_regular_file(display.strip()):
        return {"display_file": (digests or FileDigests())(Path(display.strip()), where="display")}
    return {}


def display_colour_item(display: str, rgb: Sequence[float], observer: str = "cie1931_2", white_luminance=100.0):
    """The colour an RGB triple makes on a display, seen by one observer (docs/displays.md's conventions): its
    photometric XYZ (cd/m²), chromaticity and CIELAB against the viewing conditions' reference white."""
    from spectrace.displays.compare import display_colour

    chosen = display_argument("observer", observer)
    viewing = display_argument("white_luminance", white_luminance)
    colour = display_colour(display_argument("display", display), display_argument("rgb", rgb), viewing)
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


def scene_inputs(scene_file: Path, overrides: Mapping[str, Any], digests: FileDigests | None = None) -> dict[str, Any]:
    """The inputs of a render item besides its parameters: the scene file's digest and that of every file it
    names (meshes, textures, spectra, displays, sensor: each string of the scene, with `overrides` set, that names
    a file beside it). Spectra and displays known by name are the program's own data."""
    from spectrace.scene.loader import read_scene_spec

    digests = digests or FileDigests()
    where = str(scene_file)
    spec = read_scene_spec(scene_file, dict(overrides)).model_dump()
    named: dict[str, str] = {}
    stack: list[Any] = [spec]
    while stack:
        node = stack.pop()
        if isinstance(node, dict):
            stack.extend(node.values())
        elif isinstance(node, list | tuple):
            stack.extend(node)
        elif isinstance(node, str) and node and node not in named:
            path = scene_file.parent / node
            if is_regular_file(path):
                named[node] = digests(path, where)
    return {"scene_file": digests(scene_file, where), "files": named}
