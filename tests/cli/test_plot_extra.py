"""Without matplotlib (the `plot` extra not installed) renders still work, and every figure asked for is one line
naming the option and the extra, before any work and with nothing written."""

import os
import subprocess
import sys

import pytest

from cli_runner import render_cornell_box

pytestmark = pytest.mark.subprocess

# An interpreter in which `import matplotlib` fails, as where it is not installed, running the command line.
_WITHOUT_MATPLOTLIB = (
    "import runpy, sys; sys.modules['matplotlib'] = None; sys.argv[0] = 'spectrace'; "
    "runpy.run_module('spectrace', run_name='__main__')"
)


def _run(*args: str) -> subprocess.CompletedProcess:
    command = [sys.executable, "-c", _WITHOUT_MATPLOTLIB, *args]
    return subprocess.run(command, capture_output=True, text=True, env=os.environ.copy(), timeout=600)


@pytest.mark.slow
def test_figures_without_matplotlib_name_the_plot_extra(tmp_path):
    figure = tmp_path / "figure.png"
    image = tmp_path / "image.png"
    cases = {
        "spectra plot": ["spectra", "plot", "cie:D65", "-o", str(figure)],
        "--plot": ["display", "compare", "--rgb", "0.5", "0.5", "0.5", "-d", "CRT-Dell", "--plot", str(figure)],
        "--false-color": [*render_cornell_box(image, 1, 8, 6), "--false-color", str(figure)],
    }
    for option, args in cases.items():
        result = _run(*args)
        lines = result.stderr.strip().splitlines()
        assert result.returncode == 2, result.stderr
        assert len(lines) == 1 and option in lines[0] and "spectrace[plot]" in lines[0], result.stderr
        assert not figure.exists() and not image.exists()


@pytest.mark.slow
def test_a_render_needs_no_matplotlib(tmp_path):
    image = tmp_path / "image.png"
    result = _run(*render_cornell_box(image, 1, 8, 6), "-q")
    assert result.returncode == 0, result.stderr
    assert image.stat().st_size > 0
