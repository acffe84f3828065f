"""`spectrace view` as a user runs it: the address it prints, Ctrl-C keeping the image, bad options in one line."""

import os
import re
import signal
import subprocess
import sys

import numpy as np
import pytest
from tests.viewer.viewer_client import Client

from cli_runner import run_spectrace
from spectrace.resources import scenes_dir

pytestmark = pytest.mark.subprocess


def _start(tmp_path, *options: str) -> tuple[subprocess.Popen, Client]:
    process = subprocess.Popen(
        [sys.executable, "-m", "spectrace", "view", str(scenes_dir() / "cornell_box.toml"), "--no-browser", *options],
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        env=os.environ.copy(),
        cwd=tmp_path,
    )
    assert process.stdout is not None
    line = process.stdout.readline()
    found = re.search(r"http://127\.0\.0\.1:\d+/\?token=[\w-]+", line)
    if found is None:
        process.kill()
        pytest.fail(f"no address printed: {line + process.stdout.read()}")
    return process, Client(found.group(0))


@pytest.mark.slow
def test_ctrl_c_writes_the_samples_done(tmp_path):
    from spectrace.io.exr import read_exr

    process, client = _start(tmp_path, "--width", "24", "--height", "16", "--spp", "100000")
    try:
        shown = client.wait_for(lambda s: s["spp"] >= 3)["spp"]
        process.send_signal(signal.SIGINT)
        output, _ = process.communicate(timeout=120)
    finally:
        process.kill()
    assert process.returncode == 130, output
    assert "Traceback" not in output and "wrote cornell_box.exr" in output
    channels, header = read_exr(tmp_path / "cornell_box.exr")
    spp = int(header["spectrace:spp"])
    assert shown <= spp < 100000 and f"{spp} spp" in output
    assert np.isfinite(channels["Y"]).all() and channels["Y"].mean() > 0


@pytest.mark.parametrize(
    "options, where",
    [
        (["--port", "70000"], "--port"),
        (["--folder", "no such folder"], "--folder"),
        (["-o", "out.bmp"], "out.bmp"),
        (["--spp", "0"], "--spp"),
    ],
)
def test_a_bad_option_is_one_line(tmp_path, options, where):
    result = run_spectrace("view", str(scenes_dir() / "cornell_box.toml"), "--no-browser", *options, timeout=120)
    assert result.returncode != 0
    lines = (result.stdout + result.stderr).strip().splitlines()
    assert len(lines) == 1 and where in lines[0] and "Traceback" not in lines[0]
