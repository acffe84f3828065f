"""A small TOML writer for scene data: tables, tables of tables, arrays of tables, inline tables and arrays of
strings, numbers and booleans, which is all a spectrace scene uses (the standard library reads TOML only)."""

import json
import math
import re
from collections.abc import Callable, Mapping
from pathlib import Path, PurePosixPath

import numpy as np

from spectrace.errors import SpectraceError

_BARE_KEY = re.compile(r"[A-Za-z0-9_-]+")
_FLOAT32_MAX = float(np.finfo(np.float32).max)


def _key(key: str) -> str:
    return key if _BARE_KEY.fullmatch(key) else json.dumps(key, ensure_ascii=False)


def _value(value) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if not math.isfinite(value):
            raise ValueError(f"TOML scene values must be finite, got {value}")
        return float_text(value)
    if isinstance(value, str):
        # JSON's string escapes (\", \\, \n, \uXXXX) are valid in TOML basic strings; TOML also wants DEL escaped.
        return json.dumps(value, ensure_ascii=False).replace("\x7f", "\\u007f")
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_value(item) for item in value) + "]"
    if isinstance(value, dict):
        return "{ " + ", ".join(f"{_key(k)} = {_value(v)}" for k, v in value.items()) + " }" if value else "{}"
    raise TypeError(f"cannot write {type(value).__name__} to TOML")


def non_finite_key(data: object, path: str = "") -> str | None:
    """The key path (`lights[0].direction[1]`) of the first NaN or infinite number in scene data, or None: what an
    importer's arithmetic made of degenerate input, to be reported at its source instead of failing to write."""
    stack: list[tuple[object, str]] = [(data, path)]
    while stack:
        value, where = stack.pop()
        if isinstance(value, float) and not math.isfinite(value):
            return where
        if isinstance(value, dict):
            stack.extend((item, f"{where}.{key}" if where else str(key)) for key, item in reversed(value.items()))
        elif isinstance(value, (list, tuple)):
            stack.extend((item, f"{where}[{index}]") for index, item in reversed(list(enumerate(value))))
    return None


def float_text(value: float) -> str:
    """The shortest text that reads back as `value` at the precision it carries. A value that is exactly a float32
    (as every number written by a single-precision program is: Mitsuba's 3.9 is 3.9000000953674316) is written as
    the shortest text of that float32 ("3.9"), which reads back as the same float32; any other value as Python's
    shortest repr, which reads back as exactly the same double."""
    if abs(value) <= _FLOAT32_MAX:
        single = np.float32(value)
        if float(single) == value:
            text = repr(float(str(single)))
            if np.float32(float(text)) == single:
                return text
    # float(): numpy's float64 is a float whose repr is "np.float64(...)", which TOML cannot read.
    return repr(float(value))


def _table_body(table: dict) -> list[str]:
    return [f"{_key(key)} = {_value(value)}" for key, value in table.items()]


def dumps(data: dict, header: str = "") -> str:
    """TOML text for `data`: scalar and inline values at the top; each dict of plain values as a [table]; each dict
    of dicts as [name.key] tables; each list of dicts as [[name]] arrays of tables. `header` becomes # comments."""
    lines = [f"# {line}".rstrip() for line in header.splitlines()]
    if lines:
        lines.append("")
    plain = {k: v for k, v in data.items() if not _is_section(v)}
    lines += _table_body(plain)
    for name, value in data.items():
        if not _is_section(value):
            continue
        if isinstance(value, list):
            for table in value:
                lines += ["", f"[[{_key(name)}]]", *_table_body(table)]
        elif value and all(isinstance(v, dict) for v in value.values()):
            for sub_name, table in value.items():
                lines += ["", f"[{_key(name)}.{_key(sub_name)}]", *_table_body(table)]
        else:
            lines += ["", f"[{_key(name)}]", *_table_body(value)]
    text = "\n".join(lines).lstrip("\n")
    while "\n\n\n" in text:
        text = text.replace("\n\n\n", "\n\n")
    return text + "\n"


def _is_section(value) -> bool:
    return (isinstance(value, dict) and value != {}) or (
        isinstance(value, list) and bool(value) and all(isinstance(item, dict) for item in value)
    )


def _with_strings_replaced(value, replacements: Mapping[str, str]):
    if isinstance(value, str):
        return replacements.get(value, value)
    if isinstance(value, dict):
        return {key: _with_strings_replaced(item, replacements) for key, item in value.items()}
    if isinstance(value, (list, tuple)):
        return [_with_strings_replaced(item, replacements) for item in value]
    return value


def write_scene(
    toml_path: Path,
    data: dict,
    header: str,
    files: Mapping[str, Callable[[Path], object]],
    check: Callable[[Path], object],
    option: str = "the TOML file",
    command: str = "spectrace import",
) -> None:
    """Write an imported scene all or nothing (spectrace.io.atomic.write_with_files): the TOML of `data` and the
    files it refers to, `files` (name relative to the TOML's folder, as `data` spells it -> writer). check(temp)
    loads the TOML first, written where it will be with those names leading to the files not yet in place, and
    raises to leave the earlier import, TOML and files, as it was.

    The TOML's own lock is the caller's (lock_import, taken before the import's work); the entries beside it
    that are swapped in (a folder of meshes, a side file) are locked here, since only now are their names known,
    so that a second import sharing them (`-o out` and `-o out.toml` share `out_assets`) is refused, naming its
    holder, instead of both swapping them."""
    from spectrace.io.atomic import write_with_files
    from spectrace.io.output_lock import OutputLocks

    def write_and_check(temp: Path, staged: Mapping[str, str]) -> None:
        temp.write_text(dumps(_with_strings_replaced(data, staged), header=header), encoding="utf-8")
        check(temp)
        temp.write_text(dumps(data, header=header), encoding="utf-8")

    folder = toml_path.parent
    entries = dict.fromkeys(PurePosixPath(name).parts[0] for name in files)
    with OutputLocks({f"{top} beside {option}": folder / top for top in entries}, command=command):
        write_with_files(toml_path, files, write_and_check)


def write_imported_scene(
    toml_path: Path,
    data: dict,
    header: str,
    files: Mapping[str, Callable[[Path], object]],
    told_at: Callable[[SpectraceError, Path], SpectraceError],
    option: str,
    command: str,
) -> list[str]:
    """An importer's last step, the same for every format: refuse a number that overflowed on the way, write the
    TOML and its files all or nothing (write_scene), loading the TOML first; told_at(error, path) turns the loader's
    complaint about the TOML at `path` into one at the place in the imported file the value came from. Returns the
    loaded scene's warnings (spectrace.scene.scene_warnings), for the importer to tell with its own."""
    from spectrace.scene.loader import load_scene
    from spectrace.scene.scene_warnings import scene_warnings

    if (key := non_finite_key(data)) is not None:
        failure = SpectraceError(
            "is NaN or infinite: a number of the file overflows or divides by zero", f"{toml_path}: {key}"
        )
        raise told_at(failure, toml_path)

    found: list[str] = []

    def check(temp: Path) -> None:
        try:
            scene = load_scene(temp)  # from the output's folder, where its relative file paths lead
        except SpectraceError as error:
            raise told_at(error, temp) from None
        found[:] = scene_warnings(scene)

    try:
        write_scene(toml_path, data, header, files, check, option, command)
    except OSError as error:
        raise SpectraceError(
            f"cannot write the TOML or its files ({error.strerror or error})", where=str(toml_path)
        ) from None
    return found


def check_import_output(toml_path: Path, source: Path | None, source_kind: str, option: str) -> None:
    """Refuse, before any work, an import's output that could not be written (spectrace.io.output_files) or that
    is the file being imported, `source` (the `source_kind`, "the pbrt scene", ...), which writing would destroy."""
    from spectrace.io.output_files import check_output_file

    check_output_file(toml_path, option, create_folders=True)
    if source is not None and toml_path.exists() and source.exists() and toml_path.samefile(source):
        raise SpectraceError(
            f"is {source_kind} being imported; writing it would destroy the input", where=str(toml_path)
        )


def lock_import(toml_path: Path, option: str, command: str):
    """The lock of an import's TOML (spectrace.io.output_lock.OutputLocks), to hold from before the import's work
    until it ends: a second command writing the same file is refused at once, naming this one. The TOML's folder
    is made first (an import makes missing folders anyway), since the lock file lies there."""
    from spectrace.io.output_lock import OutputLocks

    try:
        toml_path.parent.mkdir(parents=True, exist_ok=True)
    except OSError as error:
        raise SpectraceError(
            f"cannot create the folder of {option} ({error.strerror or error})", where=str(toml_path)
        ) from None
    return OutputLocks({option: toml_path}, command=command)
