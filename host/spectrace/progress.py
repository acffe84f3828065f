"""The progress bar of a render, one for the Python API and the command line: rich's on the terminal (on stderr;
a file or a pipe gets its last state as one line), tqdm's widget in Jupyter when tqdm and ipywidgets are installed
(`pip install "spectrace[notebook]"`), and a plain text bar in Jupyter without them, where tqdm's and rich's
notebook bars print a warning and an empty widget."""

from __future__ import annotations

import sys
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from rich.console import Console

ProgressCallback = Callable[[int, int], None]


def in_notebook() -> bool:
    shell = sys.modules.get("IPython")
    ipython = shell.get_ipython() if shell is not None and hasattr(shell, "get_ipython") else None
    return ipython is not None and "IPKernelApp" in getattr(ipython, "config", {})


def _installed(name: str) -> bool:
    import importlib.util

    return importlib.util.find_spec(name) is not None


def has_ipywidgets() -> bool:
    return _installed("ipywidgets")


@contextmanager
def text_bar(
    total_spp: int, done_spp: int, stream=None, unit: str = "spp", label: str = "rendering"
) -> Iterator[ProgressCallback]:
    """A one-line text bar redrawn with a carriage return."""
    stream = stream or sys.stderr
    width = 30

    def draw(done: int, total: int) -> None:
        filled = width * min(done, total) // max(total, 1)
        stream.write(f"\r{label} |{'#' * filled}{'.' * (width - filled)}| {done}/{total} {unit}")
        stream.flush()

    draw(done_spp, total_spp)
    try:
        yield draw
    finally:
        stream.write("\n")
        stream.flush()


@contextmanager
def progress_bar(
    total_spp: int, done_spp: int, console: Console | None = None, unit: str = "spp", label: str = "rendering"
) -> Iterator[ProgressCallback]:
    """A progress callback, progress(samples_done, samples_total), drawing the bar for where the render runs.
    `console`: the rich console to draw on outside Jupyter (default: a new one on stderr), so that messages the
    caller prints on it during the render stay above the bar. `unit`: what is counted (a tiled render counts
    tiles, one bar over all its workers); `label`: what the work is (validating, measuring)."""
    if in_notebook():
        if not (has_ipywidgets() and _installed("tqdm")):
            with text_bar(total_spp, done_spp, unit=unit, label=label) as draw:
                yield draw
            return
        from tqdm.auto import tqdm

        bar = tqdm(total=total_spp, initial=done_spp, unit=unit, desc=label)
        try:
            yield lambda done, total: bar.update(done - bar.n)
        finally:
            bar.close()
        return
    from rich.console import Console
    from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn, TimeRemainingColumn

    with Progress(
        TextColumn(label),
        BarColumn(),
        TextColumn("{task.completed}/{task.total} " + unit),
        TimeElapsedColumn(),
        TimeRemainingColumn(),
        console=console or Console(stderr=True, soft_wrap=True, markup=False),
    ) as progress:
        task = progress.add_task("render", total=total_spp, completed=done_spp)
        yield lambda done, total: progress.update(task, completed=done, total=total)
