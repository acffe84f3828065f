"""Start-up: the command line and the renderer's colour tables load without colour-science, SciPy and matplotlib
(about a second of imports), and what replaced them gives the same values."""

import json
import os
import signal
import subprocess
import sys

import numpy as np
import pytest

from spectrace.resources import scenes_dir


@pytest.mark.subprocess
def test_importing_the_command_line_does_not_import_heavy_modules():
    assert _loaded_after("spectrace.cli", ("colour", "matplotlib", "scipy", "trimesh", "pyopencl")) == []


def _loaded_after(imports: str, modules: tuple[str, ...]) -> list[str]:
    """Which of `modules` a fresh interpreter has loaded after `import <imports>`."""
    code = f"import sys, {imports}; print(' '.join(m for m in {modules!r} if m in sys.modules))"
    result = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, env=os.environ.copy(), timeout=120
    )
    assert result.returncode == 0, result.stderr
    return result.stdout.split()


def _imported_modules(importtime_log: str) -> set[str]:
    """The modules `python -X importtime` reports ("import time: self | cumulative | name", nested names indented)."""
    names = set()
    for line in importtime_log.splitlines():
        fields = line.split("|")
        if line.startswith("import time:") and len(fields) == 3 and fields[0].split()[-1].isdigit():
            names.add(fields[2].strip())
    return names


def _heavy(modules: set[str]) -> set[str]:
    return {m for m in modules if m.split(".")[0] in ("numpy", "pyopencl", "pydantic")}


@pytest.mark.subprocess
def test_spectrace_devices_with_remembered_probes_imports_neither_numpy_nor_pyopencl(tmp_path):
    """The listing is read through ctypes and the probes' answers come from the cache folder, so only a probe that
    really runs (the first time) loads numpy and pyopencl; pydantic (typer's option coercion) is not loaded either."""
    env = {**os.environ, "SPECTRACE_CACHE_DIR": str(tmp_path / "cache")}
    env.pop("SPECTRACE_DEVICE", None)

    def run(*args: str) -> subprocess.CompletedProcess:
        command = [sys.executable, "-X", "importtime", "-m", "spectrace", "devices", *args]
        result = subprocess.run(command, capture_output=True, text=True, env=env, timeout=300)
        assert result.returncode == 0, result.stderr[-2000:]
        return result

    first = run("--json")
    assert _heavy(_imported_modules(first.stderr)) >= {"numpy", "pyopencl"}  # probed: the log is read right
    again = run("--json")
    assert _heavy(_imported_modules(again.stderr)) == set()
    assert json.loads(again.stdout) == json.loads(first.stdout)
    table = run()
    assert _heavy(_imported_modules(table.stderr)) == set()
    assert all(device["key"] in table.stdout for device in json.loads(first.stdout)["devices"])


@pytest.mark.subprocess
def test_importing_the_device_package_does_not_import_numpy_or_pyopencl():
    modules = ("numpy", "pyopencl", "spectrace.device.program_cache")
    assert _loaded_after("spectrace.device, spectrace.device.selection", modules) == []


def test_the_shipped_cmf_table_equals_colour_sciences():
    import colour  # a dependency: missing, the test fails rather than skips

    from spectrace.spectral.colorimetry import CIE_1931_CMFS, CIE_1931_OBSERVER
    from spectrace.spectral.grid import GRID_MAX_NM, GRID_MIN_NM, GRID_STEP_NM

    shape = colour.SpectralShape(GRID_MIN_NM, GRID_MAX_NM, GRID_STEP_NM)
    expected = np.array(colour.MSDS_CMFS[CIE_1931_OBSERVER].copy().align(shape).values, dtype=np.float64)
    assert np.array_equal(CIE_1931_CMFS, expected)


@pytest.mark.parametrize("name", sorted(p.name for p in (scenes_dir() / "cornell_box").glob("*.obj")))
def test_plain_obj_files_read_as_trimesh_reads_them(name):
    import trimesh  # a dependency: missing, the test fails rather than skips

    from spectrace.geometry.mesh import _plain_triangle_obj, load_mesh

    path = scenes_dir() / "cornell_box" / name
    assert _plain_triangle_obj(path) is not None  # the fast path is the one taken
    ours = load_mesh(path, where="test")
    theirs = trimesh.load_scene(path, process=False, maintain_order=True).to_mesh()
    assert np.array_equal(ours.vertices, np.asarray(theirs.vertices))
    assert np.array_equal(ours.faces, np.asarray(theirs.faces))


def test_obj_files_with_more_than_plain_triangles_go_to_trimesh(tmp_path):
    quad = tmp_path / "quad.obj"
    quad.write_text("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n")
    textured = tmp_path / "textured.obj"
    textured.write_text("v 0 0 0\nv 1 0 0\nv 1 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nf 1/1 2/2 3/3\n")
    from spectrace.geometry.mesh import _plain_triangle_obj, load_mesh

    assert _plain_triangle_obj(quad) is None and _plain_triangle_obj(textured) is None
    assert len(load_mesh(quad, where="test").faces) == 2


@pytest.mark.subprocess
def test_ctrl_c_during_start_up_is_one_line_and_status_130():
    """SIGINT while the command line's modules import (held there by the test hook) gets the one line that Ctrl-C
    gets later on, not Python's traceback."""
    env = dict(os.environ, SPECTRACE_STARTUP_PAUSE_S="60")
    process = subprocess.Popen(
        [sys.executable, "-m", "spectrace", "devices"],
        stderr=subprocess.PIPE,
        stdout=subprocess.PIPE,
        text=True,
        env=env,
    )
    try:
        assert process.stderr.readline().strip() == "start-up paused"
        process.send_signal(signal.SIGINT)
        _, stderr = process.communicate(timeout=60)
    finally:
        process.kill()
    assert process.returncode == 130, stderr
    assert "Traceback" not in stderr and stderr.strip() == "interrupted"
