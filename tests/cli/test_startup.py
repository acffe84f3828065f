"""Start-up: the command line and the renderer's colour tables load without colour-science, SciPy and matplotlib
(about a second of imports), and what replaced them gives the same values."""

import json
import os
import signal
import subprocess
import sys

import numpy as np
import pytest

from scene_text import camera_film
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
@pytest.mark.slow
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


def test_the_shipped_d65_table_equals_colour_sciences():
    import colour  # a dependency: missing, the test fails rather than skips

    from spectrace.spectral.illuminants import shipped_illuminant_table

    wavelengths, values = shipped_illuminant_table("D65")
    reference = colour.SDS_ILLUMINANTS["D65"]
    assert np.array_equal(wavelengths, np.asarray(reference.wavelengths, np.float64))
    assert np.array_equal(values, np.asarray(reference.values, np.float64))


def test_illuminant_a_on_the_grid_is_colour_sciences_bits():
    import colour  # a dependency: missing, the test fails rather than skips

    from spectrace.spectral.grid import GRID_MAX_NM, GRID_MIN_NM, GRID_STEP_NM
    from spectrace.spectral.illuminants import cie_illuminant

    shape = colour.SpectralShape(GRID_MIN_NM, GRID_MAX_NM, GRID_STEP_NM)
    expected = np.asarray(colour.sd_CIE_standard_illuminant_A(shape).values, np.float64)
    assert np.array_equal(cie_illuminant("A").values, expected)


_RGB_XML = """<scene version="3.0.0">
    <sensor type="perspective">
        <float name="fov" value="40"/>
        <transform name="to_world"><lookat origin="0,0,4" target="0,0,0" up="0,1,0"/></transform>
        <film type="hdrfilm"><integer name="width" value="4"/><integer name="height" value="4"/></film>
    </sensor>
    <bsdf type="diffuse" id="red"><rgb name="reflectance" value="0.7, 0.2, 0.1"/></bsdf>
    <shape type="rectangle"><ref id="red"/></shape>
    <emitter type="constant"><rgb name="radiance" value="1, 1, 1"/></emitter>
</scene>
"""

_LAMP_TOML = (
    camera_film(origin="[0, 0, 4]", target="[0, 0, 0]", fov="40", width="4", height="4")
    + """
[materials.green]
type = "diffuse"
reflectance = { rgb = [0.2, 0.5, 0.3] }

[[shapes]]
type = "rectangle"
material = "green"

[[shapes]]
type = "rectangle"
material = "green"
transform = [{ translate = [0, 3, 0] }]
emitter = { radiance = { spectrum = "cie:A", scale = 0.1 } }
"""
)

_COLOUR_SCIENCE_AND_WHAT_IT_BRINGS = ("colour", "scipy", "matplotlib")


@pytest.mark.subprocess
@pytest.mark.slow
def test_importing_and_loading_scenes_with_rgb_colours_does_not_import_colour_science(tmp_path):
    """RGB colours are uplifted against D65 and the bundled scenes' lamps are CIE A: both come without colour-science
    (and the SciPy and matplotlib it brings). import-mitsuba loads the TOML it writes, so that is a load too."""
    (tmp_path / "rgb.xml").write_text(_RGB_XML)
    command = [sys.executable, "-X", "importtime", "-m", "spectrace", "import-mitsuba", "rgb.xml", "-o", "rgb.toml"]
    imported = subprocess.run(command, capture_output=True, text=True, cwd=tmp_path, timeout=300)
    assert imported.returncode == 0, imported.stderr[-2000:]
    modules = _imported_modules(imported.stderr)
    assert "spectrace.spectral.uplift" in modules  # the RGB colours were uplifted: the log is read right
    assert not {m for m in modules if m.split(".")[0] in _COLOUR_SCIENCE_AND_WHAT_IT_BRINGS}

    (tmp_path / "lamp.toml").write_text(_LAMP_TOML)
    loaded = _loaded_after_running(
        "from spectrace.scene.loader import load_scene; load_scene(sys.argv[1])",
        (*_COLOUR_SCIENCE_AND_WHAT_IT_BRINGS, "spectrace.spectral.uplift"),
        str(tmp_path / "lamp.toml"),
    )
    assert loaded == ["spectrace.spectral.uplift"]


def _loaded_after_running(statement: str, modules: tuple[str, ...], *args: str) -> list[str]:
    """Which of `modules` a fresh interpreter has loaded after running `statement` (with sys imported, argv = args)."""
    code = f"import sys; {statement}; print(' '.join(m for m in {modules!r} if m in sys.modules))"
    result = subprocess.run([sys.executable, "-c", code, *args], capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stderr[-2000:]
    return result.stdout.split()


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
