"""Every CLI subcommand, run as a user would, in a subprocess."""

import json

import numpy as np
import pytest

from cli_runner import render_cornell_box, run_spectrace
from spectrace.io.exr import read_exr

pytestmark = pytest.mark.subprocess


def _run(*args, check=True):
    result = run_spectrace(*args)
    if check:
        assert result.returncode == 0, result.stderr
    return result


@pytest.mark.slow
def test_render_writes_exr_with_metadata(tmp_path):
    out = tmp_path / "cornell.exr"
    result = _run(
        *render_cornell_box(out, 2, 16, 12),
        "--seed",
        "7",
        "-q",
    )
    assert result.stderr == ""  # -q: nothing but warnings and errors
    channels, header = read_exr(out)
    assert channels["RGB"].shape == (12, 16, 3)
    assert {"X", "Y", "Z"} <= set(channels)
    assert header["spectrace:spp"] == "2" and header["spectrace:seed"] == "7"
    assert header["spectrace:device"] and float(header["spectrace:render_seconds"]) >= 0
    assert np.all(np.isfinite(channels["RGB"])) and channels["Y"].mean() > 0


@pytest.mark.slow
def test_render_png(tmp_path):
    from PIL import Image

    out = tmp_path / "cornell.png"
    _run(
        *render_cornell_box(out, 1, 8, 8),
        "-q",
    )
    with Image.open(out) as image:
        assert image.size == (8, 8) and image.mode == "RGB"
        assert image.text["spectrace:spp"] == "1" and image.text["spectrace:device"]
        assert float(image.text["spectrace:render_seconds"]) >= 0  # 3 decimals: a tiny render may show 0.000


@pytest.mark.slow
def test_bad_scene_is_one_line_without_traceback(tmp_path):
    scene = tmp_path / "bad.toml"
    scene.write_text("[camera]\norigin = [0, 0, 0]\ntarget = [0, 0, 1]\nfov = 40\nbogus = 1\n")
    result = _run("render", str(scene), "-o", str(tmp_path / "x.png"), check=False)
    assert result.returncode == 2
    assert result.stderr.strip().count("\n") == 0, result.stderr
    assert "bad.toml: camera.bogus: unknown key 'bogus'" in result.stderr
    assert "Traceback" not in result.stderr


def test_devices_lists_the_device_in_use():
    listing = json.loads(_run("devices", "--json").stdout)
    assert any(d["ok"] for d in listing["devices"])


@pytest.mark.slow
def test_bench_reports_throughput():
    result = _run("bench", "--size", "16", "--spp", "1", "--max-depth", "3", "--json")
    rows = json.loads(result.stdout)["render"]
    assert len(rows) == 1 and rows[0]["samples_per_second"] > 0 and rows[0]["rays_per_second"] > 0
