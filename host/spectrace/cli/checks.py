"""Checks of command-line values that no scene file sees: the overrides (--seed, --max-depth, --exposure) and the
files a command will write. Commands run them before opening a device, so that a typo or an unwritable output
fails at once instead of after a long render, and nothing already on disk is replaced by mistake."""

from __future__ import annotations

import math
import os
import stat
import tempfile
from collections.abc import Mapping
from pathlib import Path

from spectrace.errors import SpectraceError
from spectrace.scene import limits


def check_seed(seed: int | None, option: str = "--seed") -> None:
    if seed is not None and (problem := limits.seed_problem(seed)):
        raise SpectraceError(problem, where=option)


def check_max_depth(depth: int | None, option: str = "--max-depth") -> None:
    if depth is not None and (problem := limits.max_depth_problem(depth)):
        raise SpectraceError(problem, where=option)


def check_exposure(stops: float | None, option: str = "--exposure") -> None:
    if stops is not None and (problem := limits.exposure_problem(stops)):
        raise SpectraceError(problem, where=option)


def check_finite(value: float | None, option: str) -> None:
    """Click's ranges let NaN and infinity through (no comparison with them is true)."""
    if value is not None and not math.isfinite(value):
        raise SpectraceError(f"must be a finite number, got {value}", where=option)


def _read_only(path: Path) -> bool:
    # Without any write permission bit, the file is meant to be kept even where the process could replace it (the
    # superuser, or an atomic rename in a writable folder, which ignores the file's own permissions).
    return not os.access(path, os.W_OK) or stat.S_IMODE(path.stat().st_mode) & 0o222 == 0


def check_output_file(path: Path, option: str, create_folders: bool = False) -> None:
    """Refuse an output file that could not be written at the end: a folder or other non-file, a read-only file,
    a missing folder (unless `create_folders`: then the nearest existing one is checked), or a folder where no
    file can be created (tried, since permission bits do not tell the superuser's rights or a read-only mount's)."""
    where = str(path)
    if path.is_dir():
        raise SpectraceError(f"{option} names a folder; name a file in it", where=where)
    if path.exists() or path.is_symlink():
        if not path.is_file():
            raise SpectraceError(
                f"{option} names something that is not a regular file (it would be replaced)", where=where
            )
        if _read_only(path):
            raise SpectraceError(
                f"{option} names a read-only file; make it writable or choose another name", where=where
            )
    folder = path.parent if str(path.parent) else Path(".")
    while create_folders and not folder.exists() and folder.parent != folder:
        folder = folder.parent
    if not folder.exists():
        raise SpectraceError(f"the folder {folder} for {option} does not exist", where=where)
    if not folder.is_dir():
        raise SpectraceError(f"{folder} is not a folder, so {option} cannot be written there", where=where)
    try:  # the same kind of file the atomic writer makes: a hidden temporary one next to the output
        fd, probe = tempfile.mkstemp(prefix=f".{path.stem}.", suffix=".probe", dir=folder)
        os.close(fd)
        os.unlink(probe)
    except OSError as error:
        raise SpectraceError(
            f"cannot create files in the folder {folder} for {option} ({error.strerror or error})", where=where
        ) from None


def same_file(first: Path, second: Path) -> bool:
    """Different spellings of one file: relative and absolute, '..', symbolic links, hard links."""
    if first.resolve() == second.resolve():
        return True
    try:
        return os.path.samefile(first, second)
    except OSError:  # one of them does not exist yet
        return False


def check_distinct_files(outputs: Mapping[str, Path | None], inputs: Mapping[str, Path | None] | None = None) -> None:
    """Refuse two outputs naming the same file (the later would silently replace the earlier) and an output naming
    an input. Keys are the options (or descriptions of the inputs) shown in the message."""
    named = [(option, path) for option, path in outputs.items() if path is not None]
    for index, (option, path) in enumerate(named):
        for other_option, other in named[index + 1 :]:
            if same_file(path, other):
                raise SpectraceError(
                    f"{option} and {other_option} name the same file; give each its own", where=str(path)
                )
        for what, source in (inputs or {}).items():
            if source is not None and same_file(path, source):
                raise SpectraceError(f"{option} names {what}, which it would overwrite", where=str(path))
