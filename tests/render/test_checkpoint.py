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

from cli_runner import run_in_process
from spectrace.engine import checkpoint as checkpoints
from spectrace.engine.checkpoint import (
    PeriodicCheckpoints,
    read_checkpoint,
    resume_render,
    save_checkpoint,
)
from spectrace.engine.renderer import Renderer
from spectrace.errors import SpectraceError
from spectrace.io.exr import read_exr
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


# 5 bands: the Cornell box program with bands that tests/cluster and tests/robustness build too, not one of its own.
@pytest.mark.parametrize("spectral_bins", [0, 5])
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


@pytest.mark.parametrize(
    "change, says",
    [
        ({"seed": 6}, "rendered with seed 5 but this render uses seed 6"),
        ({"width": 21}, "is of a 20x14 film but this render is 21x14"),
        ({"max_depth": 3}, "belongs to another scene or other settings"),
    ],
)
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


def test_bdpt_with_other_pixels_per_light_subpath_is_refused(device, tmp_path):
    """Another grouping of pixels draws other samples: resuming with it would not give the uninterrupted render."""
    path = tmp_path / "state.npz"
    scene = _cornell().with_overrides(integrator="bdpt")
    first = Renderer(scene, device)
    first.run_pass(1)
    save_checkpoint(path, first)
    with pytest.raises(SpectraceError, match="another scene or other settings"):
        resume_render(Renderer(scene.with_overrides(pixels_per_light_path=2), device), path)
    resume_render(Renderer(scene.with_overrides(pixels_per_light_path=4), device), path)  # the Cornell box's own


def _rewrite(source, target, replaced=None, dropped=()):
    """A copy of the checkpoint archive `source` with some entries replaced or dropped, and the rest untouched."""
    replaced = replaced or {}
    with zipfile.ZipFile(source) as archive, zipfile.ZipFile(target, "w") as copy:
        for item in archive.namelist():
            name = item.removesuffix(".npy")
            if name in dropped:
                continue
            if name in replaced:
                with copy.open(item, "w") as stream:
                    np.save(stream, replaced[name])
            else:
                copy.writestr(item, archive.read(item))
    return target


def test_damaged_checkpoints_are_refused(device, tmp_path):
    renderer = Renderer(_cornell(), device)
    renderer.run_pass(1)
    good = tmp_path / "good.npz"
    saved = save_checkpoint(good, renderer)
    data = good.read_bytes()

    truncated = tmp_path / "truncated.npz"
    truncated.write_bytes(data[: len(data) // 2])
    with pytest.raises(SpectraceError, match="not a spectrace checkpoint"):
        read_checkpoint(truncated)

    other = tmp_path / "other.npz"
    np.savez(other, film=np.zeros(3))
    with pytest.raises(SpectraceError, match="missing or malformed 'format'"):
        read_checkpoint(other)

    def refused(path, says):
        with pytest.raises(SpectraceError) as caught:
            read_checkpoint(path)
        assert str(caught.value).startswith(f"{path}: ") and says in str(caught.value), str(caught.value)
        assert "\n" not in str(caught.value)

    # One float of the film turned into NaN (a bit flipped on disk, an edit): the checksum no longer holds.
    film = saved.state.buffers["film"].copy()
    film[7, 1] = np.nan
    refused(_rewrite(good, tmp_path / "nan.npz", {"state_film": film}), "checksum does not match its contents")
    wrong_shape = np.zeros((5, 4), np.float32)
    refused(_rewrite(good, tmp_path / "shape.npz", {"state_film": wrong_shape}), "checksum does not match")
    refused(_rewrite(good, tmp_path / "no_sum.npz", dropped={"checksum"}), "missing or malformed 'checksum'")
    refused(
        _rewrite(good, tmp_path / "future.npz", {"format": np.array("spectrace-checkpoint-9")}),
        "written by another version of spectrace",
    )

    # Consistent files (the checksum matches) whose numbers cannot be a render's state.
    def written(name, **state_changes):
        state = dataclasses.replace(saved.state, **state_changes)
        path = tmp_path / name
        checkpoints.write_checkpoint(path, dataclasses.replace(saved, state=state))
        return path

    refused(
        written("nan_sums.npz", buffers={**saved.state.buffers, "film": film}),
        "damaged checkpoint: the film buffer holds 1 NaN or infinite values",
    )
    refused(
        written("wrong_shape.npz", buffers={**saved.state.buffers, "film": wrong_shape}),
        "the film buffer is float32 of shape (5, 4); a 20x14 film needs float32 of shape (280, 4)",
    )
    refused(
        written("wrong_type.npz", buffers={**saved.state.buffers, "ray_counts": np.zeros(280, np.float64)}),
        "the ray_counts buffer is float64 of shape (280,)",
    )
    refused(written("no_rays.npz", buffers={"film": saved.state.buffers["film"]}), "the ray_counts buffer is missing")
    refused(written("count.npz", samples_done=-3), "sample count -3 is outside 0..1048576")
    refused(written("time.npz", render_seconds=float("inf")), "render time inf s is not a finite")


def test_checkpoints_of_the_first_format_still_resume(device, tmp_path):
    """Format 1 had no checksum: such files are read with the explicit checks only, and continue exactly."""
    renderer = Renderer(_cornell(), device)
    renderer.run_pass(2)
    save_checkpoint(tmp_path / "new.npz", renderer)
    old = _rewrite(
        tmp_path / "new.npz", tmp_path / "old.npz", {"format": np.array("spectrace-checkpoint-1")}, dropped={"checksum"}
    )
    resumed = Renderer(_cornell(), device)
    resume_render(resumed, old)
    assert resumed.samples_done == 2
    assert np.array_equal(resumed.read_film()[0], renderer.read_film()[0])
    film = renderer.read_film()[0]
    film[0, 0] = np.inf
    damaged = _rewrite(old, tmp_path / "old_damaged.npz", {"state_film": film})
    with pytest.raises(SpectraceError, match="the film buffer holds 1 NaN or infinite values"):
        read_checkpoint(damaged)


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
@pytest.mark.slow
def test_sigterm_writes_the_true_partial_image_and_the_render_resumes_exactly(device, tmp_path):
    """A real `spectrace render`, stopped by SIGTERM: the image's spp is the number of samples in it, and the
    checkpoint continues the render to the same floats as an uninterrupted render."""
    partial, resumed, state = tmp_path / "partial.exr", tmp_path / "resumed.exr", tmp_path / "state.npz"
    size = ["--width", "16", "--height", "12", "--seed", "3"]  # not -q: the test reads the device and wrote lines
    process = subprocess.Popen(
        _spectrace(
            "render",
            str(CORNELL),
            "-o",
            str(partial),
            "--spp",
            "1000000",
            *size,
            "--checkpoint",
            str(state),
            "--checkpoint-interval",
            "0",
        ),
        stderr=subprocess.PIPE,
        text=True,
        env=os.environ.copy(),
    )
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
    result = subprocess.run(
        _spectrace("render", str(CORNELL), "-o", str(resumed), "--spp", str(target), *size, "--resume", str(state)),
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert result.returncode == 0, result.stderr
    assert f"resumed {state}: {done} spp done" in " ".join(result.stderr.split())
    resumed_channels, resumed_header = read_exr(resumed)
    assert resumed_header["spectrace:spp"] == str(target)

    reference = Renderer(_cornell(width=16, height=12, seed=3, spp=target), device)
    at_interrupt = reference.render(spp=done)
    assert all(np.array_equal(channels[c], at_interrupt.xyz[..., i]) for i, c in enumerate("XYZ"))
    uninterrupted = reference.render(spp=target)
    assert all(np.array_equal(resumed_channels[c], uninterrupted.xyz[..., i]) for i, c in enumerate("XYZ"))


def _one_error_line(result) -> str:
    assert result.returncode == 2 and "Traceback" not in result.stderr, result.stderr
    lines = result.stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), result.stderr
    return lines[0]


@pytest.mark.slow
def test_a_fresh_render_never_replaces_an_existing_checkpoint(device, tmp_path, monkeypatch, capsys):
    """A fresh render naming an existing checkpoint would replace its samples with its own first pass: refused
    (in a real process: status, one line naming --resume and --overwrite); --overwrite starts again; the same file
    under --resume, spelled another way, continues it."""
    state = tmp_path / "state.npz"
    renderer = Renderer(_cornell(width=8, height=6), device)
    renderer.run_pass(6)
    save_checkpoint(state, renderer)
    before = state.read_bytes()
    size = ["--width", "8", "--height", "6", "--seed", "5", "-q", "--checkpoint-interval", "0"]

    def render_here(*argv):
        return run_in_process(monkeypatch, capsys, ["render", str(CORNELL), *argv, *size])

    again = subprocess.run(
        _spectrace("render", str(CORNELL), "-o", "b.png", "--spp", "2", "--checkpoint", str(state), *size),
        capture_output=True,
        text=True,
        cwd=tmp_path,
        timeout=300,
    )
    line = _one_error_line(again)
    assert line.startswith(f"error: {state}: ") and f"use --resume {state} to continue" in line
    assert "--overwrite to start again" in line
    assert state.read_bytes() == before and not (tmp_path / "b.png").exists()

    monkeypatch.chdir(tmp_path)
    status, stderr = render_here("-o", "c.png", "--spp", "8", "--resume", str(state), "--checkpoint", "./state.npz")
    assert status == 0, stderr
    assert read_checkpoint(state).state.samples_done == 8
    status, stderr = render_here("-o", "d.png", "--spp", "2", "--checkpoint", "state.npz", "--overwrite")
    assert status == 0, stderr
    assert read_checkpoint(state).state.samples_done == 2
    status, stderr = render_here("-o", "e.png", "--resume", "state.npz", "--overwrite")
    assert status == 2 and stderr == "error: --overwrite: starts the render afresh, so it cannot go with --resume\n"


@pytest.mark.slow
def test_resuming_a_damaged_checkpoint_is_one_line_naming_it(device, tmp_path):
    renderer = Renderer(_cornell(width=8, height=6), device)
    renderer.run_pass(1)
    good = tmp_path / "good.npz"
    saved = save_checkpoint(good, renderer)
    film = saved.state.buffers["film"].copy()
    film[3] = np.nan
    damaged = _rewrite(good, tmp_path / "damaged.npz", {"state_film": film})
    result = subprocess.run(
        _spectrace(
            "render",
            str(CORNELL),
            "-o",
            str(tmp_path / "x.png"),
            "--width",
            "8",
            "--height",
            "6",
            "--seed",
            "5",
            "--resume",
            str(damaged),
            "-q",
        ),
        capture_output=True,
        text=True,
        timeout=300,
    )
    line = _one_error_line(result)
    assert line == f"error: {damaged}: the checkpoint's checksum does not match its contents: the file is damaged"
    assert not (tmp_path / "x.png").exists()


# A child that writes the old version of three files, then, in forked grandchildren killed with SIGKILL at chosen
# moments, writes a new version over and over; after each kill it copies the files aside for the test to open.
# Writing happens only in forked children, so no library state is shared across a fork after use.
_KILL_HARNESS = r"""
import json, os, random, shutil, signal, sys, time
from pathlib import Path
import numpy as np
from spectrace.io.exr import write_exr
from spectrace.io.raster import write_display_image as write_png
from spectrace.engine.checkpoint import Checkpoint, RenderIdentity, RenderState, write_checkpoint

folder, delays = Path(sys.argv[1]), json.loads(sys.argv[2])
NAMES = ("image.exr", "image.png", "state.npz")

def pixels(version):
    return np.random.default_rng(version).random((120, 160, 3), dtype=np.float32)

def write_all(version):
    rgb = pixels(version)
    write_exr(folder / "image.exr", rgb, rgb, {"version": str(version)})
    write_png(folder / "image.png", rgb, {"version": str(version)})
    film = np.concatenate([rgb.reshape(-1, 3), np.zeros((rgb.shape[0] * rgb.shape[1], 1), np.float32)], axis=1)
    state = RenderState(version, 0.0, {"film": film, "ray_counts": np.full(len(film), version, np.uint32)})
    write_checkpoint(folder / "state.npz", Checkpoint(RenderIdentity(160, 120, version, "s", "k"), state, "d"))

def in_child(work, started=None):
    pid = os.fork()
    if pid == 0:
        if started is not None:
            os.write(started, b"x")
        work()
        os._exit(0)
    return pid

began = time.perf_counter()
os.waitpid(in_child(lambda: write_all(0)), 0)
period = time.perf_counter() - began  # one write of all three files (and a fork), on this machine, now
orphans = []
for trial, delay in enumerate(delays):
    def forever():
        while True:
            write_all(1)
    read_end, write_end = os.pipe()
    pid = in_child(forever, write_end)
    os.read(read_end, 1)  # the child runs: a loaded machine may take longer to schedule it than a delay lasts
    os.close(read_end)
    os.close(write_end)
    time.sleep(delay if delay >= 0 else -delay * period)
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
        assert np.array_equal(saved.state.buffers["film"][:, :3], expected[version].reshape(-1, 3))
    return version


@pytest.mark.subprocess
@pytest.mark.skipif(not hasattr(os, "fork"), reason="needs fork()")
@pytest.mark.slow
def test_sigkill_at_any_moment_leaves_the_old_or_the_new_file(tmp_path):
    rng = np.random.default_rng(2024)
    landed = []
    # Up to three batches, until at least 5 kills have landed inside writes: how many do depends on the machine's
    # load, not on the writer, and every trial of every batch must keep the old or the new file.
    for batch in range(3):
        folder = tmp_path / f"batch{batch}"
        folder.mkdir()
        # A negative delay is in units of the time one write of the three files takes on this machine, now. 0:
        # killed before writing anything; three writes' time: long after the first complete write; the rest: during
        # writes.
        delays = [0.0, 0.0, -3.0, -3.0] + list(-rng.uniform(0.0, 1.0, 26))
        harness = subprocess.run(
            [sys.executable, "-c", _KILL_HARNESS, str(folder), json.dumps(delays)],
            capture_output=True,
            text=True,
            timeout=300,
        )
        assert harness.returncode == 0, harness.stderr
        orphaned_temporaries = json.loads(harness.stdout)
        seen = {}
        for trial in range(len(delays)):
            for name in ("image.exr", "image.png", "state.npz"):
                seen.setdefault(name, []).append(_version_of(folder / f"trial{trial}" / name))
        for name, versions in seen.items():
            assert versions[:2] == [0, 0], name  # the older file survives a kill before the new one is complete
            assert versions[2:4] == [1, 1], name
        landed += [count > 0 for count in orphaned_temporaries]
        if sum(landed) >= 5:
            break
    # The kills did land inside writes (a temporary file was left behind), so the files above were at risk.
    assert sum(landed) >= 5, landed
