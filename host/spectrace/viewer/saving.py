"""What the viewer saves, into the one folder it was given: the image (through Image.write, atomic) and the scene
with the page's edits as TOML (the scene file's own table with each edited key path set, written by the importers'
TOML writer and loaded back before it replaces anything). A name from the page is a plain file name: no folder,
no hidden file, one of the suffixes below; it never names a file outside the folder."""

from __future__ import annotations

import os
import re
import tomllib
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from spectrace.errors import SpectraceError

IMAGE_SUFFIXES = (".exr", ".png")
SCENE_SUFFIXES = (".toml",)
_NAME = re.compile(r"[A-Za-z0-9][A-Za-z0-9 ._()+-]{0,119}")


def checked_name(name: object, suffixes: tuple[str, ...]) -> str:
    """`name` if it is a plain file name with one of `suffixes`, else a SpectraceError naming it."""
    if not isinstance(name, str) or not _NAME.fullmatch(name) or ".." in name:
        raise SpectraceError(
            "must be a plain file name: letters, digits, spaces and ._()+- (no folder, not hidden), at most 120 "
            "characters",
            where="name",
        )
    if Path(name).suffix.lower() not in suffixes:
        raise SpectraceError(f"must end in {' or '.join(suffixes)}, got {name!r}", where="name")
    return name


def save_image(image: Any, folder: Path, name: object, include_xyz: bool = True) -> Path:
    from spectrace.io.output_files import check_output_file

    path = folder / checked_name(name, IMAGE_SUFFIXES)
    check_output_file(path, "name")
    try:
        image.write(path, include_xyz=include_xyz)
    except OSError as error:
        raise SpectraceError(f"cannot write the image ({error.strerror or error})", where=str(path)) from None
    return path


def _split(table: Any, parts: list[str]) -> tuple[Any, str] | None:
    """The table holding key path `parts` and its last key: names may hold dots ("white 9.5 (.05 D)"), so each
    step takes the longest run of parts that is a key of a table or the `name` of a table in an array; the last part
    is the key set (added to its table when the file left it to its default)."""
    for count in range(len(parts) - 1, 0, -1):
        head, rest = ".".join(parts[:count]), parts[count:]
        if isinstance(table, dict):
            inner = [table[head]] if head in table else []
        elif isinstance(table, list):  # an entry by its name, or by its index where names repeat
            inner = [item for item in table if isinstance(item, dict) and item.get("name") == head]
            if not inner and head.isdigit() and int(head) < len(table):
                inner = [table[int(head)]]
        else:
            inner = []
        for item in inner:
            if (found := _split(item, rest)) is not None:
                return found
    if isinstance(table, dict) and (".".join(parts) in table or len(parts) == 1):
        return table, ".".join(parts)
    return None


def _set(document: dict, key: str, value: object) -> None:
    found = _split(document, key.split("."))
    if found is None:
        raise SpectraceError("has no place in the scene file to be written to", where=key)
    table, last = found
    table[last] = value


def _relocated(value: Any, source_folder: Path, folder: Path) -> Any:
    """The document with each string that names a file beside the scene rewritten relative to `folder`, so that
    the saved scene finds the same files from where it lies."""
    if isinstance(value, dict):
        return {k: _relocated(v, source_folder, folder) for k, v in value.items()}
    if isinstance(value, list):
        return [_relocated(v, source_folder, folder) for v in value]
    if isinstance(value, str) and value and not Path(value).is_absolute():
        candidate = source_folder / value
        if candidate.is_file() and source_folder.resolve() != folder.resolve():
            return Path(os.path.relpath(candidate.resolve(), folder.resolve())).as_posix()
    return value


def save_scene(source: Path | None, edits: Mapping[str, object], folder: Path, name: object) -> Path:
    """Write the scene file `source` with `edits` (key path -> value) as `folder/name`, atomically, after loading it
    back from its temporary name there."""
    from spectrace.interop.toml_writer import dumps
    from spectrace.io.atomic import write_atomically
    from spectrace.io.output_files import check_output_file
    from spectrace.scene import load_scene

    path = folder / checked_name(name, SCENE_SUFFIXES)
    if source is None or source.suffix.lower() != ".toml":
        raise SpectraceError("the scene was not read from a TOML file, so there is none to save with the edits")
    check_output_file(path, "name")
    if path.exists() and path.resolve() == source.resolve():
        raise SpectraceError("is the scene being viewed; choose another name", where="name")
    with open(source, "rb") as handle:
        document = _relocated(tomllib.load(handle), source.parent, folder)
    for section in {key.split(".")[0] for key in edits} & {"film", "sampler", "camera"}:
        document.setdefault(section, {})  # a table the file left out, all its keys at their defaults
    for key, value in edits.items():
        _set(document, key, value)
    header = f"{source.name} with the edits made in spectrace view"

    def write(temp: Path) -> None:
        temp.write_text(dumps(document, header=header), encoding="utf-8")
        try:
            load_scene(temp)
        except SpectraceError as error:  # named as the file it would have been
            raise SpectraceError(str(error).replace(str(temp), str(path))) from None

    try:
        write_atomically(path, write)
    except OSError as error:
        raise SpectraceError(f"cannot write the scene ({error.strerror or error})", where=str(path)) from None
    return path


def save_built_scene(scene: Any, folder: Path, name: object) -> Path:
    """Write a scene built in Python, with the edits made to it, as `folder/name` (spectrace.save_scene: its meshes
    beside it, all or nothing)."""
    from spectrace.io.output_files import check_output_file
    from spectrace.session.scene_toml import save_scene as save_python_scene

    path = folder / checked_name(name, SCENE_SUFFIXES)
    check_output_file(path, "name")
    return save_python_scene(scene, path, header="A scene built in Python, with the edits made in spectrace view")
