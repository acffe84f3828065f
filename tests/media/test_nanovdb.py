"""NanoVDB files (spectrace.geometry.nanovdb, docs/media.md): float grids read into dense density grids, checked
against NVIDIA Warp's NanoVDB reader (an independent implementation) on the real files Warp ships and on files
Warp writes; the scene keys, pbrt-v4's `nanovdb` medium and the one-line refusals.

Warp (`warp-lang`) is not a dependency: the tests that need its reader or its files skip without it."""

import struct
from pathlib import Path

import numpy as np
import pytest
from scipy import ndimage

from scene_text import CAMERA_FILM_GREY
from spectrace.errors import SpectraceError
from spectrace.geometry.nanovdb import read_nanovdb
from spectrace.scene import load_scene

REAL_FILES = ("tests/assets/test_grid.nvdb", "tests/assets/torus.nvdb", "examples/assets/rocks.nvdb")


def _warp():
    wp = pytest.importorskip("warp", reason="NVIDIA Warp (warp-lang) reads NanoVDB independently and ships files")
    wp.config.quiet = True
    wp.init()
    return wp


def _real_files(wp) -> list[Path]:
    root = Path(wp.__file__).parent
    files = [root / name for name in REAL_FILES if (root / name).is_file()]
    if not files:
        pytest.skip("this Warp installation ships none of its NanoVDB test files")
    return files


def _kernels(wp):
    """Warp kernels: the value at each index of a box, and the trilinear sample at each world point."""

    @wp.kernel
    def index_lookup(volume: wp.uint64, low: wp.vec3i, n: wp.vec3i, out: wp.array(dtype=float)):
        t = wp.tid()
        x = t % n[0]
        y = (t // n[0]) % n[1]
        z = t // (n[0] * n[1])
        out[t] = wp.volume_lookup_f(volume, x + low[0], y + low[1], z + low[2])

    @wp.kernel
    def world_sample(volume: wp.uint64, points: wp.array(dtype=wp.vec3), out: wp.array(dtype=float)):
        t = wp.tid()
        out[t] = wp.volume_sample_f(volume, wp.volume_world_to_index(volume, points[t]), wp.Volume.LINEAR)

    return index_lookup, world_sample


def _warp_lookups(wp, path: Path, low: np.ndarray, high: np.ndarray, world: np.ndarray):
    """Warp's values at every index of [low, high] (shaped (nz, ny, nx)) and its trilinear samples at world points."""
    index_lookup, world_sample = _kernels(wp)
    with path.open("rb") as file:
        volume = wp.Volume.load_from_nvdb(file, device="cpu")
    n = high - low + 1
    values = wp.zeros(int(np.prod(n)), dtype=float, device="cpu")
    wp.launch(index_lookup, dim=int(np.prod(n)), inputs=[volume.id, wp.vec3i(*low), wp.vec3i(*n), values], device="cpu")
    points = wp.array(world.astype(np.float32), dtype=wp.vec3, device="cpu")
    samples = wp.zeros(len(world), dtype=float, device="cpu")
    wp.launch(world_sample, dim=len(world), inputs=[volume.id, points, samples], device="cpu")
    return values.numpy().reshape(n[2], n[1], n[0]), samples.numpy()


def _spectrace_lookup(values: np.ndarray, to_world: np.ndarray, world: np.ndarray) -> np.ndarray:
    """spectrace's density lookup (voxel centres, clamped at the box's faces, 0 outside), computed with scipy."""
    unit = (np.c_[world, np.ones(len(world))] @ np.linalg.inv(to_world).T)[:, :3]
    nz, ny, nx = values.shape
    coords = np.stack([unit[:, 2] * nz - 0.5, unit[:, 1] * ny - 0.5, unit[:, 0] * nx - 0.5])
    looked = ndimage.map_coordinates(values.astype(np.float64), coords, order=1, mode="nearest")
    return np.where(np.all((unit >= 0) & (unit <= 1), axis=1), looked, 0.0)


@pytest.mark.slow
def test_real_nanovdb_files_read_as_warp_reads_them():
    """Every voxel of the stored box grown by three (tiles, leaves and background alike) equals Warp's lookup,
    bit for bit, on the files Warp ships (ZIP-compressed float grids: a test grid, a torus level set, rocks of
    many nodes); and spectrace's trilinear lookup of the dense grid at random world points in and around the grid
    equals Warp's trilinear sample there (the placement: voxel centres on the integer index coordinates, one voxel
    of background around the stored ones); beyond that box the medium ends (pbrt-v4 bounds it by the grid's box)."""
    wp = _warp()
    rng = np.random.default_rng(3)
    for path in _real_files(wp):
        grid = next(iter(read_nanovdb(path, "test").values()))
        low, high = np.array(grid.index_min) - 3, np.array(grid.index_max) + 3
        dense, to_world = grid.dense_grid()
        index_points = rng.uniform(low, high, (4000, 3))
        world = (np.c_[index_points, np.ones(len(index_points))] @ grid.index_to_world.T)[:, :3]
        by_warp, samples = _warp_lookups(wp, path, low, high, world)
        assert np.array_equal(grid.dense(low, high), by_warp), path.name
        ours = _spectrace_lookup(dense, to_world, world)
        unit = (np.c_[world, np.ones(len(world))] @ np.linalg.inv(to_world).T)[:, :3]
        inside = np.all((unit >= 0) & (unit <= 1), axis=1)
        np.testing.assert_allclose(ours[inside], samples[inside], atol=2e-4 * np.abs(dense).max())
        assert np.all(ours[~inside] == 0.0) and 0 < inside.sum() < len(inside)  # the medium ends at the grid's box
        assert np.ptp(by_warp) > 0  # the files hold varying values


def _written_by_warp(wp, tmp_path: Path, codec: str) -> tuple[Path, np.ndarray]:
    density = np.random.default_rng(11).uniform(0.1, 2.0, (7, 6, 5)).astype(np.float32)  # indexed [x][y][z]
    volume = wp.Volume.load_from_numpy(density, min_world=(0.5, -1.0, 2.0), voxel_size=0.25, bg_value=0.0, device="cpu")
    path = tmp_path / f"cloud_{codec}.nvdb"
    volume.save_to_nvdb(str(path), codec=codec)
    return path, density


@pytest.mark.slow
@pytest.mark.parametrize("codec", ["none", "zip"])
def test_a_density_written_by_warp_loads_from_a_scene_file(tmp_path, codec):
    """A scene's `file = "cloud.nvdb"`: the medium's density holds Warp's values at their voxels (x fastest in
    spectrace, [x][y][z] in Warp) and background around them, placed so that voxel (i, j, k) sits at
    min_world + voxel_size · (i, j, k), then moved by `transform`."""
    wp = _warp()
    path, density = _written_by_warp(wp, tmp_path, codec)
    scene = tmp_path / "cloud.toml"
    moved = "transform = [{ translate = [1, 0, 0] }]"
    interior = f'{{ sigma_a = {{ value = 1.0 }}, density = {{ file = "{path.name}", {moved} }} }}'
    scene.write_text(CAMERA_FILM_GREY + f'\n[[shapes]]\ntype = "cube"\ninterior = {interior}\n')
    grid = load_scene(scene).shapes[0].interior.density
    nx, ny, nz = density.shape
    stored = grid.density[1 : 1 + nz, 1 : 1 + ny, 1 : 1 + nx]
    assert np.array_equal(stored, density.transpose(2, 1, 0))
    assert grid.density.sum() == pytest.approx(density.sum())  # the rest is background 0
    index = np.array([[0, 0, 0], [nx - 1, ny - 1, nz - 1], [3, 1, 4]], np.float64)
    world = np.array([0.5, -1.0, 2.0]) + 0.25 * index + np.array([1.0, 0.0, 0.0])
    looked = _spectrace_lookup(grid.density, grid.to_world, world)
    np.testing.assert_allclose(looked, [density[0, 0, 0], density[-1, -1, -1], density[3, 1, 4]], rtol=1e-5)


@pytest.mark.slow
def test_pbrt_nanovdb_medium_imports_its_grids(tmp_path):
    """pbrt-v4's `nanovdb` medium: its file (the density grid; Warp's unnamed one, the only float grid, is read as
    the density),
    placed by the CTM at MakeNamedMedium; a missing `filename` is one line naming the place."""
    from spectrace.interop.pbrt import pbrt_scene_data

    wp = _warp()
    path, _ = _written_by_warp(wp, tmp_path, "zip")
    text = f"""WorldBegin
AttributeBegin
Translate 0 0 1
MakeNamedMedium "cloud" "string type" "nanovdb" "string filename" "{path.name}"
  "rgb sigma_a" [1 1 1] "rgb sigma_s" [1 1 1]
AttributeEnd
MediumInterface "cloud" ""
Material "interface"
Shape "sphere" "float radius" 3
"""
    (tmp_path / "cloud.pbrt").write_text(text)
    density = pbrt_scene_data(tmp_path / "cloud.pbrt")[0]["shapes"][0]["interior"]["density"]
    assert Path(density["file"]).name == path.name
    assert np.allclose(np.array(density["transform"][0]["matrix"])[:3, 3], [0, 0, 1])
    (tmp_path / "bad.pbrt").write_text(text.replace(f'"string filename" "{path.name}"', ""))
    with pytest.raises(SpectraceError, match="filename") as caught:
        pbrt_scene_data(tmp_path / "bad.pbrt")
    assert "\n" not in str(caught.value) and "bad.pbrt" in str(caught.value)


def _header(codec: int) -> bytes:
    """A NanoVDB 32.x file's header and one grid record (no grid after it): enough to reach the codec check."""
    version = 32 << 21
    meta = struct.pack("<QQQQII6d6i3dI4I3IHHI", 800, 16, 0, 0, 1, 0, *([0.0] * 6), *([0] * 6), 1.0, 1.0, 1.0, 8,
                       0, 0, 0, 0, 0, 0, 0, codec, 0, version)  # fmt: skip
    return struct.pack("<QIHH", 0x304244566F6E614E, version, 1, codec) + meta + b"density\0" + bytes(16)


@pytest.mark.parametrize(
    ("content", "words"),
    [
        (b"VOL\x03" + bytes(60), "is not a NanoVDB file"),
        (_header(2), "compressed with BLOSC"),
        (_header(0)[:40], "ends inside"),
    ],
)
def test_refusals_name_the_file_and_key_in_one_line(tmp_path, content, words):
    (tmp_path / "cloud.nvdb").write_bytes(content)
    scene = tmp_path / "cloud.toml"
    scene.write_text(
        CAMERA_FILM_GREY + '\n[[shapes]]\ntype = "cube"\ninterior = { sigma_a = { value = 1.0 }, '
        'density = { file = "cloud.nvdb" } }\n'
    )
    with pytest.raises(SpectraceError, match=words) as caught:
        load_scene(scene)
    text = str(caught.value)
    assert "\n" not in text and "cloud.toml" in text and "density.file" in text, text


def test_a_box_for_a_nanovdb_grid_is_refused(tmp_path):
    (tmp_path / "cloud.nvdb").write_bytes(_header(0))
    scene = tmp_path / "cloud.toml"
    scene.write_text(
        CAMERA_FILM_GREY + '\n[[shapes]]\ntype = "cube"\ninterior = { sigma_a = { value = 1.0 }, '
        'density = { file = "cloud.nvdb", box = [[0, 0, 0], [1, 1, 1]] } }\n'
    )
    with pytest.raises(SpectraceError, match="index-to-world map") as caught:
        load_scene(scene)
    assert "density.box" in str(caught.value)
