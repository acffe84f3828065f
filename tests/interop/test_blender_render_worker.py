"""The render behind the Blender add-on (spectrace.interop.blender.render_worker), without Blender: the progress it
reports after each pass, the image it leaves, its stop after the pass in flight when the add-on passes on Esc
(SIGINT), and a scene it cannot load as one line."""

from __future__ import annotations

import signal
import subprocess
import sys

import numpy as np
import pytest

SCENE = """
[camera]
origin = [0.0, 0.0, -4.0]
target = [0.0, 0.0, 0.0]
fov = 40

[film]
width = 24
height = 16

[materials.clay]
type = "diffuse"
reflectance = { rgb = [0.7, 0.35, 0.2] }

[[shapes]]
type = "sphere"
material = "clay"

[[lights]]
type = "constant"
radiance = { rgb = [1.0, 1.0, 1.0] }
"""


def _worker(tmp_path, spp: int) -> subprocess.Popen:
    (tmp_path / "scene.toml").write_text(SCENE, encoding="utf-8")
    command = [sys.executable, "-m", "spectrace.interop.blender.render_worker", "scene.toml", "image.npy", str(spp)]
    return subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=tmp_path)


@pytest.mark.subprocess
@pytest.mark.slow
def test_progress_after_each_pass_and_the_image_as_linear_rgb(tmp_path):
    worker = _worker(tmp_path, 16)
    out, err = worker.communicate(timeout=300)
    assert worker.returncode == 0, err
    lines = [line.split() for line in out.splitlines()]
    progress = [(int(words[1]), int(words[2])) for words in lines[:-1] if words[0] == "progress"]
    partial = [int(words[1]) for words in lines[:-1] if words[0] == "partial"]
    assert len(progress) + len(partial) == len(lines) - 1 and len(progress) >= 2 and progress[-1] == (16, 16), out
    # the first pass's image, and never one after the last pass (the final image is the one to show then)
    assert partial and partial[0] == progress[0][0] and max(partial) < 16, out
    assert np.load(tmp_path / "image.partial.npy").shape == (16, 24, 3)
    assert all(b[0] > a[0] for a, b in zip(progress, progress[1:], strict=False)), out
    assert lines[-1][:2] == ["done", "16"], out
    image = np.load(tmp_path / "image.npy")
    assert image.shape == (16, 24, 3) and image.dtype == np.float32
    # a white sky of radiance 1 renders as RGB 1 where the camera sees it (the three columns each side of the
    # sphere, whose silhouette spans the middle 18); 1 % for the wavelengths' noise over 96 pixels at 16 spp
    sky = np.concatenate([image[:, :3], image[:, -3:]], axis=1).reshape(-1, 3).mean(axis=0)
    assert sky == pytest.approx([1.0, 1.0, 1.0], abs=0.01)


@pytest.mark.subprocess
@pytest.mark.slow
def test_sigint_stops_after_the_pass_in_flight_with_the_image_of_the_samples_done(tmp_path):
    worker = _worker(tmp_path, 1_000_000)
    assert worker.stdout is not None
    first = worker.stdout.readline().split()
    assert first[0] == "progress", first
    worker.send_signal(signal.SIGINT)
    out, err = worker.communicate(timeout=300)
    assert worker.returncode == 0, err
    done = out.splitlines()[-1].split()
    assert done[0] == "done" and int(first[1]) <= int(done[1]) < 1_000_000, out
    image = np.load(tmp_path / "image.npy")
    assert image.shape == (16, 24, 3) and np.all(np.isfinite(image)) and image.mean() > 0.1


@pytest.mark.subprocess
@pytest.mark.slow
def test_a_scene_it_cannot_load_is_one_line_naming_the_file(tmp_path):
    (tmp_path / "scene.toml").write_text("[camera\n", encoding="utf-8")
    command = [sys.executable, "-m", "spectrace.interop.blender.render_worker", "scene.toml", "image.npy", "4"]
    done = subprocess.run(command, capture_output=True, text=True, cwd=tmp_path, timeout=300)
    assert done.returncode != 0
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and "scene.toml" in lines[0] and "Traceback" not in done.stderr, done.stderr
    assert not (tmp_path / "image.npy").exists()
