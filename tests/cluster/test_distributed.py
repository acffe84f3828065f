"""Renders split into tiles on a Dask LocalCluster of two worker processes: the merged film is bit-identical to a
one-piece render on the same device (also after a worker is killed mid-render, and resumed from a tiled
checkpoint); sweeps equal their items computed one by one and skip finished items; bad input is one line."""

import os
import signal
import sys

import numpy as np
import pytest

from cli_runner import render_cornell_box, run_in_process
from spectrace import render
from spectrace.engine.checkpoint import read_checkpoint
from spectrace.engine.job import RenderJob
from spectrace.engine.tiles import LocalTiles, PeriodicTileCheckpoints, TiledFilm, render_tiles
from spectrace.errors import SpectraceError
from spectrace.io.exr import read_exr
from spectrace.resources import scenes_dir
from spectrace.scene import load_scene

distributed = pytest.importorskip("distributed", reason='needs Dask distributed: pip install "spectrace[distributed]"')

pytestmark = pytest.mark.subprocess  # the cluster's workers are processes


@pytest.fixture(scope="module")
def client():
    from spectrace.distributed import connect

    with connect(workers=2) as dask_client:
        dask_client.wait_for_workers(2, timeout=120)
        yield dask_client


def _cornell(**changes):
    return load_scene(scenes_dir() / "cornell_box.toml").with_overrides(
        **{"width": 24, "height": 20, "spp": 4, **changes}
    )


def _assert_same_bits(tiled, whole):
    assert tiled.spp == whole.spp
    assert np.array_equal(tiled.xyz, whole.xyz)
    assert tiled.rays_traced == whole.rays_traced
    assert tiled.dropped_samples == whole.dropped_samples
    if whole.spectral is not None:
        assert np.array_equal(tiled.spectral.radiance, whole.spectral.radiance)


@pytest.mark.slow
def test_cornell_box_on_two_workers_is_bit_identical_to_one_render(client, device):
    scene = _cornell()
    whole = render(scene, device=device, progress=False, spectral_bins=5)
    tiled = render(scene, device=device.report.key, progress=False, spectral_bins=5, client=client, tile_rows=3)
    _assert_same_bits(tiled, whole)
    assert tiled.extra["tiles"] == "7/7"
    assert "devices_mixed" not in tiled.extra


@pytest.mark.slow
def test_a_media_scene_on_two_workers_is_bit_identical_to_one_render(client, device):
    scene = load_scene(scenes_dir() / "subsurface.toml").with_overrides(width=20, height=16, spp=3)
    whole = render(scene, device=device, progress=False)
    tiled = render(scene, device=device.report.key, progress=False, client=client, tile_rows=4)
    _assert_same_bits(tiled, whole)


@pytest.mark.slow
def test_a_worker_killed_mid_render_loses_only_time(client, device):
    scene = _cornell(width=32, height=32, spp=8)
    whole = render(scene, device=device, progress=False)
    pids = client.run(os.getpid)  # worker address -> process id
    killed = []

    def kill_the_job_holder(done: int, total: int) -> None:
        # The worst worker to lose: the one holding the job every remaining tile needs (and finished tiles).
        if done >= 1 and not killed:
            holders = [w for key, where in client.who_has().items() if "the_job" in str(key) for w in where]
            killed.append(done)
            os.kill(pids[holders[0] if holders else next(iter(pids))], signal.SIGKILL)

    tiled = render(scene, device=device.report.key, progress=kill_the_job_holder, client=client, tile_rows=2)
    assert killed and killed[0] < 16  # the kill landed while tiles were still to do
    _assert_same_bits(tiled, whole)
    client.wait_for_workers(2, timeout=120)  # the nanny restarts it for the tests after this one


def test_an_interrupted_tiled_render_resumes_bit_identical(client, device, tmp_path):
    scene = _cornell()
    job, identity = RenderJob.make(scene, device=device.report.key, tile_rows=4).tiles()
    saved = tmp_path / "render.ckpt"
    arrived = []
    film = render_tiles(
        job,
        LocalTiles(device),
        progress=lambda done, total: arrived.append(done),
        stop=lambda: len(arrived) >= 3,  # the first report is 0 tiles: stop after two
        checkpoints=PeriodicTileCheckpoints(saved, identity, 0.0),
    )
    assert int(film.done.sum()) == 2
    partial = film.image(scene, job.film())
    assert partial.extra["tiles"] == "2/5"
    assert not partial.xyz[8:].any()  # the tiles not rendered are black

    checkpoint = read_checkpoint(saved)
    resumed_film = TiledFilm.from_checkpoint(checkpoint, identity, job.spp, str(saved))
    from spectrace.distributed import DaskTiles

    resumed = render_tiles(job, DaskTiles(client), resumed_film).image(scene, job.film())
    _assert_same_bits(resumed, render(scene, device=device, progress=False))


def test_the_command_line_resumes_a_tiled_checkpoint_here(device, tmp_path, monkeypatch, capsys):
    scene = _cornell()
    job, identity = RenderJob.make(scene, device=device.report.key, tile_rows=4).tiles()
    saved = tmp_path / "render.ckpt"
    render_tiles(job, LocalTiles(device), stop=lambda: False, checkpoints=PeriodicTileCheckpoints(saved, identity, 0))
    # Keep only the first tile done: the resume renders the other four.
    checkpoint = read_checkpoint(saved)
    film = TiledFilm.from_checkpoint(checkpoint, identity, job.spp, str(saved))
    film.done[1:] = False
    for buffer in film.buffers.values():
        buffer.reshape(24 * 20, -1)[4 * 24 :] = 0
    PeriodicTileCheckpoints(saved, identity, 0).save(film)
    monkeypatch.setenv("SPECTRACE_DEVICE", device.report.key)
    args = render_cornell_box(tmp_path / "out.exr", 4, 24, 20)
    status, err = run_in_process(monkeypatch, capsys, [*args, "--resume", str(saved)])  # not -q: says what it resumed
    assert status == 0, err
    assert "1/5 tiles done" in err
    status, err = run_in_process(monkeypatch, capsys, [*render_cornell_box(tmp_path / "one.exr", 4, 24, 20), "-q"])
    assert status == 0, err
    resumed, one = read_exr(tmp_path / "out.exr")[0], read_exr(tmp_path / "one.exr")[0]
    for name in ("X", "Y", "Z"):
        assert np.array_equal(resumed[name], one[name])


def test_tiles_from_different_devices_are_marked_in_the_metadata(tmp_path):
    from spectrace.device import discover_devices, open_device

    keys = sorted({report.key for report in discover_devices() if report.ok})
    runtimes = {key.split(":")[0].split("-")[0]: key for key in keys}
    if len(runtimes) < 2:
        pytest.skip(f"needs OpenCL devices of two runtimes, found {keys}")
    first, second = list(runtimes.values())[:2]
    scene = _cornell()
    job, _ = RenderJob.make(scene, device=None, tile_rows=10).tiles()
    film = TiledFilm(job.plan, job.spp)
    for index, key in enumerate((first, second)):
        render_tiles(job, _OneTile(LocalTiles(open_device(key)), index), film)
    image = film.image(scene, job.film())
    assert image.extra["devices_mixed"] == "yes"
    assert first in image.device and second in image.device


class _OneTile:
    def __init__(self, runner, index):
        self.runner, self.index = runner, index

    def run(self, job, indices, done, stop):
        self.runner.run(job, [self.index], done, stop)


@pytest.mark.slow
def test_a_sweep_equals_its_items_one_by_one_and_a_rerun_skips_them(client, tmp_path):
    from spectrace.displays import ALL_OBSERVERS, ViewingConditions, compare_displays, load_display
    from spectrace.sweep import SweepItem, display_colour_item, grid_items, run_items, sweep

    grid = {
        "display": ["LCD-Apple_WLED", "OLED-SonyPVM2541", "CRT-Dell"],
        "rgb": [[1.0, 0.0, 0.0], [0.2, 0.7, 0.4]],
        "observer": [observer.value for observer in ALL_OBSERVERS],
    }
    rows = sweep(display_colour_item, grid, tmp_path, client=client)
    assert len(rows) == 3 * 2 * len(ALL_OBSERVERS)
    for row in rows:
        # The display comparison's own numbers for the same display, triple and observer.
        comparison = compare_displays([load_display(row["display"])], row["rgb"], ViewingConditions())
        observer = next(o for o in ALL_OBSERVERS if o.value == row["observer"])
        colour = comparison.colours[0]
        xyz = colour.display.primaries_matrix(observer) @ colour.drive
        assert [row["X"], row["Y"], row["Z"]] == pytest.approx(xyz, rel=1e-12)
        assert [row["L"], row["a"], row["b"]] == pytest.approx(colour.lab[observer], rel=1e-12)
    assert (tmp_path / "results.csv").read_text().count("\n") == len(rows) + 1

    # Here, the same function over the same grid: every item is found done, none computed again.
    again = [SweepItem(params, display_colour_item, params) for params in grid_items(grid)]
    assert run_items(again, tmp_path) == (rows, 0)


def test_an_unreachable_scheduler_is_one_line(tmp_path, monkeypatch, capsys):
    out = tmp_path / "out.exr"
    args = [*render_cornell_box(out, 2, 8, 8), "--cluster", "tcp://127.0.0.1:9", "--cluster-timeout", "0.5"]
    status, err = run_in_process(monkeypatch, capsys, args)
    assert status == 2
    assert err.startswith("error: --cluster tcp://127.0.0.1:9: cannot reach the Dask scheduler")
    assert err.count("\n") == 1 and not out.exists()


def test_a_missing_mesh_is_one_line_before_the_cluster_starts(tmp_path, monkeypatch, capsys):
    scene = tmp_path / "scene.toml"
    text = (
        (scenes_dir() / "cornell_box.toml").read_text().replace('file = "cornell_box/white.obj"', 'file = "gone.obj"')
    )
    scene.write_text(text)
    out = tmp_path / "out.exr"
    status, err = run_in_process(monkeypatch, capsys, ["render", str(scene), "-o", str(out), "--workers", "2"])
    assert status == 2 and err.count("\n") == 1 and "gone.obj" in err
    assert not out.exists()


def test_a_worker_without_the_device_is_one_line(client):
    with pytest.raises(SpectraceError) as error:
        render(_cornell(), device="no-such-opencl-device", progress=False, client=client)
    assert "\n" not in str(error.value) and "no-such-opencl-device" in str(error.value)


def test_without_dask_the_cluster_option_says_what_to_install(tmp_path, monkeypatch, capsys):
    monkeypatch.setitem(sys.modules, "distributed", None)
    args = [*render_cornell_box(tmp_path / "out.exr", 2, 8, 8), "--cluster", "tcp://127.0.0.1:8786"]
    status, err = run_in_process(monkeypatch, capsys, args)
    assert status == 2
    assert (
        err.strip()
        == 'error: --cluster: needs Dask distributed, which is not installed: pip install "spectrace[distributed]"'
    )


@pytest.mark.slow
def test_ctrl_c_writes_the_finished_tiles_and_a_checkpoint_that_resume_completes(device, tmp_path, monkeypatch, capsys):
    import subprocess
    import time

    partial, saved = tmp_path / "partial.exr", tmp_path / "tiles.npz"
    args = [
        *render_cornell_box(partial, 256, 64, 64),
        "--workers",
        "2",
        "--tile-rows",
        "4",
    ]  # not -q: its lines are read
    env = {**os.environ, "SPECTRACE_DEVICE": device.report.key}
    command = [sys.executable, "-m", "spectrace", *args, "--checkpoint", str(saved), "--checkpoint-interval", "0"]
    process = subprocess.Popen(command, stderr=subprocess.PIPE, text=True, env=env, start_new_session=True)
    deadline = time.monotonic() + 240
    while not saved.exists() and process.poll() is None and time.monotonic() < deadline:
        time.sleep(0.05)
    os.killpg(process.pid, signal.SIGINT)  # as a terminal's Ctrl-C: the whole process group, workers included
    _, err = process.communicate(timeout=120)
    assert process.returncode == 130, err
    assert "Traceback" not in err and "interrupted: partial image" in err
    assert partial.exists()
    checkpoint = read_checkpoint(saved)
    assert checkpoint.tiles is not None and 0 < checkpoint.tiles.done.sum() < 16

    monkeypatch.setenv("SPECTRACE_DEVICE", device.report.key)
    done = tmp_path / "done.exr"
    status, err = run_in_process(
        monkeypatch, capsys, [*render_cornell_box(done, 256, 64, 64), "--resume", str(saved), "-q"]
    )
    assert status == 0, err
    whole = render(_cornell(width=64, height=64, spp=256), device=device, progress=False)
    resumed = read_exr(done)[0]
    assert np.array_equal(np.stack([resumed[c] for c in "XYZ"], axis=-1), whole.xyz)
