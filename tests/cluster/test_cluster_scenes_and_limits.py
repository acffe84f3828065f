"""`spectrace render --workers/--cluster` on every bundled scene: the image's every channel is bit-identical to the
render in one piece (the light-traced scenes go as one whole-film tile); and the limits of the distributed options,
each one line naming the option, before any cluster starts and with the output already on disk kept."""

import os

import numpy as np
import pytest

from cli_runner import run_in_process, run_spectrace
from spectrace import render
from spectrace.errors import SpectraceError
from spectrace.io.exr import read_exr
from spectrace.resources import bundled_scene_names, scenes_dir
from spectrace.scene import load_scene

distributed = pytest.importorskip("distributed", reason='needs Dask distributed: pip install "spectrace[distributed]"')

SMALL = ["--width", "16", "--height", "12", "--spp", "1", "-q"]


def _cores() -> int:
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:
        return os.cpu_count() or 1


@pytest.fixture(scope="module")
def client():
    from spectrace.distributed import connect

    with connect(workers=2) as dask_client:
        dask_client.wait_for_workers(2, timeout=120)
        yield dask_client


def _assert_same_channels(tiled_exr, whole_exr) -> None:
    tiled, header = read_exr(tiled_exr)
    whole, _ = read_exr(whole_exr)
    assert sorted(tiled) == sorted(whole)
    for name, values in whole.items():
        assert tiled[name].dtype == values.dtype and tiled[name].shape == values.shape, name
        assert np.array_equal(tiled[name].view(np.uint8), values.view(np.uint8)), name
    done, count = str(header["spectrace:tiles"]).split("/")
    assert done == count


@pytest.mark.slow
@pytest.mark.subprocess
@pytest.mark.parametrize("name", bundled_scene_names())
def test_a_bundled_scene_on_a_cluster_is_bit_identical_to_one_render(
    name, client, device, tmp_path, monkeypatch, capsys
):
    """The command line's own path (the job measured and shipped, tiles merged, the image written) on the cluster
    of this module, against the command line's render in one piece."""
    base = ["render", name, *SMALL, "--device", device.report.key]
    whole, tiled = tmp_path / "whole.exr", tmp_path / "tiled.exr"
    status, err = run_in_process(monkeypatch, capsys, [*base, "-o", str(whole)])
    assert status == 0, err
    status, err = run_in_process(monkeypatch, capsys, [*base, "-o", str(tiled), "--cluster", client.scheduler.address])
    assert status == 0, err
    _assert_same_channels(tiled, whole)


@pytest.mark.slow
@pytest.mark.subprocess
def test_render_with_workers_in_a_real_process(device, tmp_path, monkeypatch, capsys):
    """`spectrace render material_showcase --workers 2` as a user runs it: a scene whose spectra are scaled, uplifted
    and sampled (once closures, which plain pickle refused), bit-identical to the render in one piece."""
    base = ["render", "material_showcase", *SMALL, "--device", device.report.key]
    whole, tiled = tmp_path / "whole.exr", tmp_path / "tiled.exr"
    result = run_spectrace(*base, "-o", str(tiled), "--workers", "2", timeout=300)
    assert result.returncode == 0, result.stderr
    assert "Traceback" not in result.stderr and "Warning" not in result.stderr
    status, err = run_in_process(monkeypatch, capsys, [*base, "-o", str(whole)])
    assert status == 0, err
    _assert_same_channels(tiled, whole)


@pytest.mark.slow
@pytest.mark.parametrize(
    ("name", "changes", "tiles"),
    [
        ("cornell_box", {"hide_emitters": True}, "12/12"),  # which shapes emit: the kernels' features
        ("material_showcase", {"integrator": "bdpt"}, "1/1"),  # not every material diffuse: fewer pixels per path
        ("cornell_box", {"integrator": "sppm"}, "1/1"),  # the bounds photons start from
    ],
    ids=["hidden-emitters", "bdpt-glossy", "sppm"],
)
def test_what_a_renderer_decides_from_the_shapes_a_worker_decides_alike(name, changes, tiles, client, device):
    """A worker's renderer decides from the scene's shapes as the client's does; bdpt's and sppm's contributions land
    in any pixel like the light tracer's, so their one tile is the whole film, and smaller ones are refused."""
    scene = load_scene(scenes_dir() / f"{name}.toml").with_overrides(width=16, height=12, spp=2, **changes)
    whole = render(scene, device=device, progress=False)
    tiled = render(scene, device=device.report.key, progress=False, client=client)
    assert tiled.extra["tiles"] == tiles
    assert np.array_equal(tiled.xyz.view(np.uint32), whole.xyz.view(np.uint32))
    if tiles == "1/1":
        with pytest.raises(SpectraceError) as error:
            render(scene, device=device.report.key, progress=False, client=client, tile_rows=4)
        assert str(error.value).startswith("--tile-rows: ") and "\n" not in str(error.value)


# ---------------------------------------------------------------- limits


def _limit_case(scene: str, argv: list[str], tmp_path):
    out = tmp_path / "out.exr"
    out.write_bytes(b"an earlier image")
    return ["render", scene, "-o", str(out), *SMALL, *argv], out


@pytest.mark.parametrize(
    ("scene", "argv", "says"),
    [
        ("cornell_box", ["--workers", "100000"], "--workers: a LocalCluster takes 1 to"),
        ("cornell_box", ["--workers", str(_cores() + 1)], "--workers: a LocalCluster takes 1 to"),
        ("cornell_box", ["--workers", "0"], "--workers: "),
        ("cornell_box", ["--cluster", "tcp://127.0.0.1:9", "--cluster-timeout", "inf"], "--cluster-timeout: must be"),
        ("cornell_box", ["--cluster", "tcp://127.0.0.1:9", "--cluster-timeout", "1e300"], "--cluster-timeout: must be"),
        ("cornell_box", ["--tile-rows", "4"], "--tile-rows: splits a render over --workers or --cluster"),
        # A light-traced film is one tile: smaller tiles are refused before the cluster starts.
        ("prism_sun", ["--workers", "1", "--tile-rows", "4"], "--tile-rows: integrator 'light' renders the whole film"),
    ],
    ids=[
        "workers-100000",
        "workers-over-cores",
        "workers-0",
        "timeout-inf",
        "timeout-1e300",
        "tile-rows-alone",
        "tile-rows-light",
    ],
)
def test_a_distributed_option_out_of_bounds_is_one_line(scene, argv, says, tmp_path, monkeypatch, capsys):
    args, out = _limit_case(scene, argv, tmp_path)
    status, err = run_in_process(monkeypatch, capsys, args)
    assert status == 2
    assert err.startswith(f"error: {says}") and err.count("\n") == 1, err
    assert out.read_bytes() == b"an earlier image"


@pytest.mark.subprocess
@pytest.mark.slow
def test_a_hundred_thousand_workers_are_refused_in_a_real_process(tmp_path):
    args, out = _limit_case("cornell_box", ["--workers", "100000"], tmp_path)
    result = run_spectrace(*args, timeout=120)  # it once started processes until memory ran out
    assert result.returncode == 2
    assert result.stderr.startswith("error: --workers: ") and result.stderr.count("\n") == 1, result.stderr
    assert out.read_bytes() == b"an earlier image"


@pytest.mark.slow
@pytest.mark.subprocess
def test_more_workers_than_tiles_start_only_as_many_as_tiles(tmp_path, monkeypatch, capsys):
    """A light-traced film is one tile: of two workers asked for, one is started (and says so)."""
    if _cores() < 2:
        pytest.skip("needs two cores to ask for two workers")
    out = tmp_path / "out.exr"
    not_quiet = [a for a in SMALL if a != "-q"]  # the lines checked are the ones -q keeps quiet
    status, err = run_in_process(
        monkeypatch, capsys, ["render", "prism_sun", *not_quiet, "-o", str(out), "--workers", "2"]
    )
    assert status == 0, err
    assert "1 of the 2 workers asked for are started" in err and "cluster: 1 workers; 1 tiles" in err
    assert read_exr(out)[1]["spectrace:tiles"] == "1/1"


def test_the_api_refuses_an_impossible_local_cluster_before_starting_it():
    from spectrace.distributed import connect

    for workers, timeout in ((0, 30.0), (100000, 30.0), (True, 30.0), (1, float("nan")), (1, float("inf"))):
        with pytest.raises(SpectraceError) as error, connect(workers=workers, timeout_s=timeout):
            pass
        assert "\n" not in str(error.value)
