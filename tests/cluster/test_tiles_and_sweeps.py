"""Tiled checkpoints and sweeps without a cluster: a damaged tile map is refused as one line, a plain checkpoint
is not resumed tile by tile, scene overrides by key path equal the edited file, and `spectrace sweep` writes one
table whose rerun computes nothing."""

import json

import numpy as np
import pytest

from cli_runner import render_cornell_box, run_in_process
from spectrace.engine.checkpoint import TileMap, read_checkpoint, save_checkpoint, write_checkpoint
from spectrace.engine.job import RenderJob
from spectrace.engine.renderer import Renderer
from spectrace.engine.tiles import LocalTiles, PeriodicTileCheckpoints, render_tiles
from spectrace.errors import SpectraceError
from spectrace.resources import scenes_dir
from spectrace.scene import load_scene

CORNELL = scenes_dir() / "cornell_box.toml"


def _cornell(**changes):
    return load_scene(CORNELL).with_overrides(**{"width": 12, "height": 10, "spp": 2, **changes})


def test_a_tile_map_that_does_not_fit_the_film_is_refused(device, tmp_path):
    job, identity = RenderJob.make(_cornell(), device=device.report.key, tile_rows=3).tiles()
    path = tmp_path / "tiles.npz"
    render_tiles(job, LocalTiles(device), checkpoints=PeriodicTileCheckpoints(path, identity, 0))
    checkpoint = read_checkpoint(path)
    assert checkpoint.tiles is not None and checkpoint.tiles.done.tolist() == [True] * 4  # 10 rows in tiles of 3
    checkpoint.tiles = TileMap(3, np.ones(5, bool))  # written with a valid checksum, but 5 tiles of 3 rows ≠ 10 rows
    write_checkpoint(path, checkpoint)
    with pytest.raises(SpectraceError) as error:
        read_checkpoint(path)
    assert "damaged checkpoint: tiles_done must be 4 booleans" in str(error.value)


def test_a_plain_checkpoint_is_not_resumed_tile_by_tile(device, tmp_path, monkeypatch, capsys):
    pytest.importorskip("distributed", reason='needs Dask distributed: pip install "spectrace[distributed]"')
    renderer = Renderer(_cornell(), device)
    renderer.render()
    path = tmp_path / "plain.npz"
    save_checkpoint(path, renderer)
    args = [*render_cornell_box(tmp_path / "out.exr", 2, 12, 10), "--resume", str(path), "--workers", "2", "-q"]
    status, err = run_in_process(monkeypatch, capsys, args)
    assert status == 2 and err.count("\n") == 1
    assert "was not split into tiles: resume it without --workers/--cluster" in err
    assert not (tmp_path / "out.exr").exists()


def test_a_tiled_checkpoint_is_not_loaded_into_a_plain_renderer(device, tmp_path):
    from spectrace.engine.checkpoint import restore_checkpoint

    job, identity = RenderJob.make(_cornell(), device=device.report.key, tile_rows=5).tiles()
    path = tmp_path / "tiles.npz"
    render_tiles(job, LocalTiles(device), checkpoints=PeriodicTileCheckpoints(path, identity, 0))
    with pytest.raises(SpectraceError, match="split into tiles"):
        restore_checkpoint(Renderer(_cornell(), device), read_checkpoint(path), str(path))


def test_overrides_by_key_path_equal_the_edited_file(tmp_path):
    edited = tmp_path / "box.toml"
    text = CORNELL.read_text().replace("width = 256", "width = 40").replace("seed = 0", "seed = 7")
    edited.write_text(text.replace('file = "cornell_box/', f'file = "{scenes_dir().as_posix()}/cornell_box/'))
    overridden = load_scene(CORNELL, overrides={"film.width": 40, "sampler.seed": 7})
    from_file = load_scene(edited)
    assert (overridden.width, overridden.seed) == (from_file.width, from_file.seed) == (40, 7)
    with pytest.raises(SpectraceError) as error:
        load_scene(CORNELL, overrides={"film.nosuch.width": 1})
    assert str(error.value).endswith("film.nosuch.width: the scene has no film.nosuch")


def test_the_sweep_command_writes_one_table_and_a_rerun_computes_nothing(tmp_path, monkeypatch, capsys):
    from spectrace.sweep import display_colour_item

    spec = tmp_path / "sweep.toml"
    spec.write_text(
        '[sweep]\nkind = "display"\n[grid]\ndisplay = ["CRT-Dell", "LCD-Apple_WLED"]\n'
        'rgb = [[0.0, 1.0, 0.0], [1.0, 1.0, 1.0]]\nobserver = ["cie1964_10"]\n'
    )
    out = tmp_path / "results"
    status, err = run_in_process(monkeypatch, capsys, ["sweep", str(spec), "-o", str(out)])
    assert status == 0, err
    assert "4/4 items (4 computed now, 0 already done)" in err
    rows = json.loads((out / "results.json").read_text())
    assert [(row["display"], row["rgb"]) for row in rows] == [
        ("CRT-Dell", [0.0, 1.0, 0.0]),
        ("CRT-Dell", [1.0, 1.0, 1.0]),
        ("LCD-Apple_WLED", [0.0, 1.0, 0.0]),
        ("LCD-Apple_WLED", [1.0, 1.0, 1.0]),
    ]
    for row in rows:
        expected = display_colour_item(row["display"], row["rgb"], "cie1964_10")
        assert {name: row[name] for name in expected} == expected
    status, err = run_in_process(monkeypatch, capsys, ["sweep", str(spec), "-o", str(out), "-q"])
    assert (status, err) == (0, "")  # -q: nothing but warnings and errors
    status, err = run_in_process(monkeypatch, capsys, ["sweep", str(spec), "-o", str(out)])
    assert status == 0 and "(0 computed now, 4 already done)" in err


def test_a_sweep_file_with_an_unknown_grid_key_is_one_line(tmp_path, monkeypatch, capsys):
    spec = tmp_path / "sweep.toml"
    spec.write_text('[sweep]\nkind = "display"\n[grid]\ndisplay = ["CRT-Dell"]\nrgb = [[1, 1, 1]]\ncolour = [1]\n')
    status, err = run_in_process(monkeypatch, capsys, ["sweep", str(spec), "-o", str(tmp_path / "out")])
    assert status == 2 and err.count("\n") == 1
    assert f"{spec}: grid.colour: unknown key" in err
    assert not (tmp_path / "out").exists()


def test_a_worker_with_other_kernels_refuses_the_job(device):
    from dataclasses import replace

    from spectrace.distributed import render_tile_task

    job, _ = RenderJob.make(_cornell(), device=device.report.key, tile_rows=5).tiles()
    assert job.kernels_digest  # the client's, always sent
    with pytest.raises(SpectraceError, match="other spectrace kernels than the client"):
        render_tile_task(replace(job, kernels_digest="0" * 64, key="other kernels"), 0)


def test_a_tiled_render_keeps_the_aovs_of_a_render_in_one_piece(device):
    """AOV sums are per-pixel sums like the film's, so tiles merge them into the same bits, and the merged image
    makes the same AOV images (the albedo's channel scale included)."""

    scene = _cornell(aovs=("albedo", "depth", "variance"))
    whole = Renderer(scene, device)
    whole.render()
    expected = whole.image()
    job, _ = RenderJob.make(scene, device=device.report.key, tile_rows=3).tiles()
    merged = render_tiles(job, LocalTiles(device)).image(scene, job.film())
    assert np.array_equal(merged.xyz, expected.xyz)
    assert sorted(merged.aovs) == sorted(expected.aovs) == ["albedo", "depth", "variance"]
    for name, values in expected.aovs.items():
        assert np.array_equal(merged.aovs[name], values, equal_nan=True), name
