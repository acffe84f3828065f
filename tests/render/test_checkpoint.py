"""Interrupted renders lose nothing: checkpoints continue a render bit for bit, SIGTERM writes the partial image
with its true sample count, and no kill at any moment leaves a torn output file."""

import dataclasses
import json
import os
import signal
import subprocess
import sys
import time
import zipfile

import numpy as np
import pytest

from spectrace.errors import SpectraceError
from spectrace.io.exr import read_exr
from spectrace.render import checkpoint as checkpoints
from spectrace.render.checkpoint import (
    PeriodicCheckpoints,
    read_checkpoint,
    resume_render,
    save_checkpoint,
)
from spectrace.render.renderer import Renderer
from spectrace.resources import scenes_dir
from spectrace.scene import load_scene

CORNELL = scenes_dir() / "cornell_box.toml"


def _cornell(**changes):
    settings = {"width": 20, "height": 14, "spp": 13, "seed": 5, **changes}
    return load_scene(CORNELL).with_overrides(**settings)


def _stop_after(passes: int):
    asked = []

    def should_stop() -> bool:
        asked.append(1)
        return len(asked) > passes

    return should_stop


@pytest.mark.parametrize("spectral_bins", [0, 6])
def test_interrupted_then_resumed_equals_uninterrupted(device, tmp_path, spectral_bins):
    scene = _cornell()
    path = tmp_path / "state.npz"

    interrupted = Renderer(scene, device, spectral_bins=spectral_bins)
    partial = interrupted.render(pass_spp=2, should_stop=_stop_after(3))
    assert partial.spp == interrupted.samples_done == 6  # stopped between passes, count exact
    save_checkpoint(path, interrupted)

    resumed = Renderer(scene, device, spectral_bins=spectral_bins)
    resume_render(resumed, path)
    assert resumed.samples_done == 6
    finished = resumed.render(pass_spp=5)  # other pass sizes than the first part used

    uninterrupted = Renderer(scene, device, spectral_bins=spectral_bins)
    reference = uninterrupted.render()

    film_resumed, rays_resumed = resumed.read_film()
    film_reference, rays_reference = uninterrupted.read_film()
    assert np.array_equal(film_resumed, film_reference)
    assert np.array_equal(rays_resumed, rays_reference)
    assert np.array_equal(finished.xyz, reference.xyz) and finished.spp == reference.spp == 13
    if spectral_bins:
        assert np.array_equal(resumed.read_spectral_film(), uninterrupted.read_spectral_film())
    # The equality is not vacuous: the first six samples alone give another film.
    assert not np.array_equal(interrupted.read_film()[0], film_reference)
    assert finished.render_seconds >= partial.render_seconds


def test_the_partial_image_has_its_true_sample_count(device):
    scene = _cornell()
    stopped = Renderer(scene, device).render(pass_spp=3, should_stop=_stop_after(2))
    fresh = Renderer(scene, device).render(spp=6)
    assert stopped.spp == 6 and np.array_equal(stopped.xyz, fresh.xyz)


@pytest.mark.parametrize("change, says", [
    ({"seed": 6}, "rendered with seed 5 but this render uses seed 6"),
    ({"width": 21}, "is of a 20x14 film but this render is 21x14"),
    ({"max_depth": 3}, "belongs to another scene or other settings"),
])
def test_a_checkpoint_of_another_render_is_refused(device, tmp_path, change, says):
    path = tmp_path / "state.npz"
    first = Renderer(_cornell(), device)
    first.run_pass(2)
    save_checkpoint(path, first)
    with pytest.raises(SpectraceError, match=says) as caught:
        resume_render(Renderer(_cornell(**change), device), path)
    assert str(caught.value).startswith(f"{path}: ") and "\n" not in str(caught.value)


def test_other_scene_content_or_kernels_are_refused(device, tmp_path, monkeypatch):
    path = tmp_path / "state.npz"
    first = Renderer(_cornell(), device)
    first.run_pass(1)
    save_checkpoint(path, first)
    scene = _cornell()
    moved_camera = scene.with_overrides(camera=dataclasses.replace(scene.camera, origin=(0.3, 0.27, -0.8)))
    with pytest.raises(SpectraceError, match="another scene"):
        resume_render(Renderer(moved_camera, device), path)
    monkeypatch.setattr(checkpoints, "kernels_digest", lambda folder: "edited kernels")
    with pytest.raises(SpectraceError, match="other kernel sources"):
        resume_render(Renderer(scene, device), path)


def test_damaged_checkpoints_are_refused(device, tmp_path):
    renderer = Renderer(_cornell(), device)
    renderer.run_pass(1)
    good = tmp_path / "good.npz"
    save_checkpoint(good, renderer)
    data = good.read_bytes()

    truncated = tmp_path / "truncated.npz"
    truncated.write_bytes(data[: len(data) // 2])
    with pytest.raises(SpectraceError, match="not a spectrace checkpoint"):
        read_checkpoint(truncated)

    other = tmp_path / "other.npz"
    np.savez(other, film=np.zeros(3))
    with pytest.raises(SpectraceError, match="missing or malformed 'format'"):
        read_checkpoint(other)

    wrong_shape = tmp_path / "wrong_shape.npz"
    with zipfile.ZipFile(good) as archive, zipfile.ZipFile(wrong_shape, "w") as copy:
        for item in archive.namelist():
            if item != "state_film.npy":
                copy.writestr(item, archive.read(item))
        with copy.open("state_film.npy", "w") as stream:
            np.save(stream, np.zeros((5, 4), np.float32))
    with pytest.raises(SpectraceError, match="saved film is float32 x 20"):
        resume_render(Renderer(_cornell(), device), wrong_shape)


def test_periodic_checkpoints_follow_the_interval_and_survive_a_failed_write(device, tmp_path):
    renderer = Renderer(_cornell(width=4, height=3), device)
    now = [0.0]
    warnings = []
    saver = PeriodicCheckpoints(tmp_path / "state.npz", renderer, 10.0, warn=warnings.append, clock=lambda: now[0])
    renderer.run_pass(1)
    now[0] = 9.9
    assert not saver.maybe_save() and not saver.path.exists()
    now[0] = 10.0
    assert saver.maybe_save() and read_checkpoint(saver.path).state.samples_done == 1

    blocked = tmp_path / "a-file"
    blocked.write_text("not a folder")
    failing = PeriodicCheckpoints(blocked / "state.npz", renderer, 0.0, warn=warnings.append)
    assert not failing.save()
    assert len(warnings) == 1 and "could not write checkpoint" in warnings[0] and "rendering goes on" in warnings[0]


def _spectrace(*args):
    return [sys.executable, "-m", "spectrace", *args]


@pytest.mark.subprocess
def test_sigterm_writes_the_true_partial_image_and_the_render_resumes_exactly(device, tmp_path):
    """A real `spectrace render`, stopped by SIGTERM: the image's spp is the number of samples in it, and the
    checkpoint continues the render to the same floats as an uninterrupted render."""
    partial, resumed, state = tmp_path / "partial.exr", tmp_path / "resumed.exr", tmp_path / "state.npz"
    size = ["--width", "16", "--height", "12", "--seed", "3", "-q"]
    process = subprocess.Popen(
        _spectrace("render", str(CORNELL), "-o", str(partial), "--spp", "1000000", *size, "--checkpoint", str(state),
                   "--checkpoint-interval", "0"),
        stderr=subprocess.PIPE, text=True, env=os.environ.copy())
    try:
        while not process.stderr.readline().startswith("device: "):  # the device is open, the render starts
            assert process.poll() is None
        deadline = time.monotonic() + 120
        while not state.exists():  # the first pass is done once its checkpoint is there
            assert time.monotonic() < deadline and process.poll() is None
            time.sleep(0.05)
        process.send_signal(signal.SIGTERM)
        _, stderr = process.communicate(timeout=120)
    finally:
        process.kill()
    assert process.returncode == 130, stderr
    assert "interrupted: partial image" in " ".join(stderr.split()) and "Traceback" not in stderr

    channels, header = read_exr(partial)
    done = int(header["spectrace:spp"])
    assert 0 < done < 1000000 and read_checkpoint(state).state.samples_done == done

    target = done + 5
    result = subprocess.run(_spectrace("render", str(CORNELL), "-o", str(resumed), "--spp", str(target), *size,
                                       "--resume", str(state)), capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stderr
    assert f"resumed {state}: {done} spp done" in " ".join(result.stderr.split())
    resumed_channels, resumed_header = read_exr(resumed)
    assert resumed_header["spectrace:spp"] == str(target)

    reference = Renderer(_cornell(width=16, height=12, seed=3, spp=target), device)
    at_interrupt = reference.render(spp=done)
    assert all(np.array_equal(channels[c], at_interrupt.xyz[..., i]) for i, c in enumerate("XYZ"))
    uninterrupted = reference.render(spp=target)
    assert all(np.array_equal(resumed_channels[c], uninterrupted.xyz[..., i]) for i, c in enumerate("XYZ"))


# A child that writes the old version of three files, then, in forked grandchildren killed with SIGKILL at chosen
# moments, writes a new version over and over; after each kill it copies the files aside for the test to open.
# Writing happens only in forked children, so no library state is shared across a fork after use.
_KILL_HARNESS = r"""
import json, os, random, shutil, signal, sys, time
from pathlib import Path
import numpy as np
from spectrace.io.exr import write_exr
from spectrace.io.png import write_png
from spectrace.render.checkpoint import Checkpoint, RenderIdentity, RenderState, write_checkpoint

folder, delays = Path(sys.argv[1]), json.loads(sys.argv[2])
NAMES = ("image.exr", "image.png", "state.npz")

def pixels(version):
    return np.random.default_rng(version).random((120, 160, 3), dtype=np.float32)

def write_all(version):
    rgb = pixels(version)
    write_exr(folder / "image.exr", rgb, rgb, {"version": str(version)})
    write_png(folder / "image.png", rgb, {"version": str(version)})
    state = RenderState(version, 0.0, {"film": rgb.reshape(-1, 3)})
    write_checkpoint(folder / "state.npz", Checkpoint(RenderIdentity(160, 120, version, "s", "k"), state, "d"))

def in_child(work):
    pid = os.fork()
    if pid == 0:
        work()
        os._exit(0)
    return pid

os.waitpid(in_child(lambda: write_all(0)), 0)
orphans = []
for trial, delay in enumerate(delays):
    def forever():
        while True:
            write_all(1)
    pid = in_child(forever)
    time.sleep(delay)
    os.kill(pid, signal.SIGKILL)
    os.waitpid(pid, 0)
    temps = [p for p in folder.iterdir() if p.name.startswith(".") and ".tmp" in p.name]
    orphans.append(len(temps))
    for temp in temps:
        temp.unlink()
    kept = folder / f"trial{trial}"
    kept.mkdir()
    for name in NAMES:
        shutil.copy2(folder / name, kept / name)
print(json.dumps(orphans))
"""


def _version_of(path) -> int:
    """The version a file holds, after checking that its pixels are exactly that version's."""
    from PIL import Image as PILImage

    expected = {v: np.random.default_rng(v).random((120, 160, 3), dtype=np.float32) for v in (0, 1)}
    if path.suffix == ".exr":
        channels, header = read_exr(path)
        version = int(header["spectrace:version"])
        assert np.array_equal(channels["X"], expected[version][..., 0])
    elif path.suffix == ".png":
        with PILImage.open(path) as image:
            image.load()
            version = int(image.text["spectrace:version"])
            encoded = np.asarray(image, np.float64) / 255.0
        assert np.allclose(encoded, np.clip(expected[version], 0, 1), atol=0.5 / 255 + 1e-9)
    else:
        saved = read_checkpoint(path)
        version = saved.identity.seed
        assert np.array_equal(saved.state.buffers["film"], expected[version].reshape(-1, 3))
    return version


@pytest.mark.subprocess
@pytest.mark.skipif(not hasattr(os, "fork"), reason="needs fork()")
def test_sigkill_at_any_moment_leaves_the_old_or_the_new_file(tmp_path):
    rng = np.random.default_rng(2024)
    # 0 s: killed before writing anything; 0.5 s: long after the first complete write; the rest: during writes.
    delays = [0.0, 0.0, 0.5, 0.5] + list(rng.uniform(0.0, 0.08, 26))
    harness = subprocess.run([sys.executable, "-c", _KILL_HARNESS, str(tmp_path), json.dumps(delays)],
                             capture_output=True, text=True, timeout=300)
    assert harness.returncode == 0, harness.stderr
    orphaned_temporaries = json.loads(harness.stdout)
    seen = {}
    for trial in range(len(delays)):
        for name in ("image.exr", "image.png", "state.npz"):
            seen.setdefault(name, []).append(_version_of(tmp_path / f"trial{trial}" / name))
    for name, versions in seen.items():
        assert versions[:2] == [0, 0], name  # the older file survives a kill before the new one is complete
        assert versions[2:4] == [1, 1], name
    # The kills did land inside writes (a temporary file was left behind), so the files above were at risk.
    assert sum(count > 0 for count in orphaned_temporaries) >= 5, orphaned_temporaries
