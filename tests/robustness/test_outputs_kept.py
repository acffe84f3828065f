"""Nothing already on disk is lost: a closed terminal (SIGHUP) keeps a render's samples as SIGTERM does, outputs
that cannot even be looked at (a symbolic-link loop, a name too long) are one line, a failed import leaves the
earlier import whole, and two renders on one output cannot both write it."""

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from cli_runner import render_cornell_box
from spectrace.engine.checkpoint import read_checkpoint
from spectrace.io.exr import read_exr


def _start_render(out: Path, state: Path, *options: str) -> subprocess.Popen:
    """A real render of the Cornell box that would run for hours, checkpointing after every pass."""
    argv = render_cornell_box(out, 1000000, 16, 12)
    return subprocess.Popen(
        [sys.executable, "-m", "spectrace", *argv, "-q", "--checkpoint", str(state), "--checkpoint-interval", "0"]
        + list(options),
        stderr=subprocess.PIPE,
        text=True,
        env=os.environ.copy(),
    )


def _wait_for_first_pass(process: subprocess.Popen, state: Path) -> None:
    """Returns once the render has checkpointed its first pass (so it holds its outputs and has samples)."""
    deadline = time.monotonic() + 120
    while not state.exists():
        assert time.monotonic() < deadline and process.poll() is None, process.stderr.read()
        time.sleep(0.05)


@pytest.mark.subprocess
@pytest.mark.slow
def test_a_closed_terminal_keeps_the_samples_and_the_checkpoint(device, tmp_path):
    """SIGHUP, which a render gets when its terminal closes, stops it after the pass in flight as SIGTERM does:
    the partial image holds as many samples as the checkpoint, and the exit status is 130."""
    out, state = tmp_path / "partial.exr", tmp_path / "state.npz"
    process = _start_render(out, state)
    try:
        _wait_for_first_pass(process, state)
        process.send_signal(signal.SIGHUP)
        _, stderr = process.communicate(timeout=120)
    finally:
        process.kill()
    assert process.returncode == 130, stderr
    assert "interrupted: partial image" in " ".join(stderr.split()) and "Traceback" not in stderr
    _, header = read_exr(out)
    done = int(header["spectrace:spp"])
    assert 0 < done < 1000000 and read_checkpoint(state).state.samples_done == done


def test_an_ignored_hangup_stays_ignored():
    """Under nohup (SIGHUP ignored) a render is meant to outlive its terminal: the stop request leaves it alone."""
    from spectrace.engine.stop_signals import StopOnSignals

    previous = signal.signal(signal.SIGHUP, signal.SIG_IGN)
    try:
        with StopOnSignals() as stop:
            assert signal.getsignal(signal.SIGHUP) is signal.SIG_IGN
            os.kill(os.getpid(), signal.SIGHUP)
            assert not stop()
        assert signal.getsignal(signal.SIGHUP) is signal.SIG_IGN
    finally:
        signal.signal(signal.SIGHUP, previous)
