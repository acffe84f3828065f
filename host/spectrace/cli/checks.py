"""Checks of command-line values that no scene file sees: the overrides (--seed, --max-depth, --exposure) and the
files a command will write. Commands run them before opening a device, so that a typo or an unwritable output
fails at once instead of after a long render, and nothing already on disk is replaced by mistake."""

from __future__ import annotations

import math
import os
from collections.abc import Mapping
from pathlib import Path

from spectrace.core import limits
from spectrace.errors import SpectraceError
from spectrace.io.output_files import check_output_file  # noqa: F401 (the commands' check of their outputs)


def check_max_depth(depth: int | None, option: str = "--max-depth") -> None:
    if depth is not None and (problem := limits.max_depth_problem(depth)):
        raise SpectraceError(problem, where=option)


def check_finite(value: float | None, option: str) -> None:
    """Click's ranges let NaN and infinity through (no comparison with them is true)."""
    if value is not None and not math.isfinite(value):
        raise SpectraceError(f"must be a finite number, got {value}", where=option)


def same_file(first: Path, second: Path) -> bool:
    """Different spellings of one file: relative and absolute, '..', symbolic links, hard links."""
    try:
        if first.resolve() == second.resolve():
            return True
    except (OSError, RuntimeError):  # a loop of symbolic links (RuntimeError before Python 3.13), too long a name
        return os.path.abspath(first) == os.path.abspath(second)
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
