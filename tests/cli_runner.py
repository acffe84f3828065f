"""Running the command line from tests: as a real process where exit status and stderr matter, or through its
entry point in this process where only the status and the message are checked (fast)."""

import contextlib
import io
import os
import subprocess
import sys

import pytest

from spectrace.resources import scenes_dir


def run_spectrace(*args: str, timeout: float = 600) -> subprocess.CompletedProcess:
    """`python -m spectrace ARGS` as a user would run it; the result, whatever its exit status."""
    return subprocess.run(
        [sys.executable, "-m", "spectrace", *args],
        capture_output=True,
        text=True,
        env=os.environ.copy(),
        timeout=timeout,
    )


def run_here(*args: str) -> subprocess.CompletedProcess:
    """`spectrace ARGS` through its entry point in this process, answered as run_spectrace answers (status, stdout,
    stderr): for tests about what a command writes rather than how a real process exits, which save the interpreter
    and the imports a process pays (a display command's is about 2 CPU-s, colour-science's import the most)."""
    from spectrace import cli

    out, err = io.StringIO(), io.StringIO()
    argv, sys.argv = sys.argv, ["spectrace", *args]
    try:
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            try:
                cli.main()
                status = 0
            except SystemExit as exit_info:
                status = exit_info.code if isinstance(exit_info.code, int) else int(exit_info.code is not None)
    finally:
        sys.argv = argv
    return subprocess.CompletedProcess(["spectrace", *args], status, out.getvalue(), err.getvalue())


def render_cornell_box(out, spp: int, width: int, height: int) -> list[str]:
    """`render` arguments for the bundled Cornell box at a small size, written to `out`; options follow them."""
    spp, width, height = str(spp), str(width), str(height)
    return [
        "render",
        str(scenes_dir() / "cornell_box.toml"),
        "-o",
        str(out),
        "--spp",
        spp,
        "--width",
        width,
        "--height",
        height,
    ]


def run_in_process(monkeypatch, capsys, argv: list[str]) -> tuple[int, str]:
    """The CLI's exit status and stderr for `spectrace ARGV`, run through its entry point in this process."""
    from spectrace import cli

    monkeypatch.setattr(sys, "argv", ["spectrace", *argv])
    with pytest.raises(SystemExit) as exit_info:
        cli.main()
    return exit_info.value.code, capsys.readouterr().err
