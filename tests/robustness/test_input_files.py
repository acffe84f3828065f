"""Files named in user input that are not what they seem: named pipes and devices, images whose header claims a
huge size, OBJ texture seams, large meshes, and a cache folder that cannot be written.

Anything that would hang or exhaust memory if the check were missing runs in a child process with a timeout.
"""

import json
import os
import struct
import subprocess
import sys
import zlib

import numpy as np
import pytest

from scene_text import emitting_screen as _scene_text
from spectrace.displays import load_display
from spectrace.engine.renderer import Renderer
from spectrace.geometry import mesh as mesh_module
from spectrace.geometry.mesh import load_mesh
from spectrace.scene import load_scene

# ---------------------------------------------------------------- pipes, devices, and an image bomb

# Loads each scene given on the command line and prints, as JSON, the error of each and the peak memory; then
# runs `spectrace render` on the first one as the command line would, with its exit status and stderr.
LOADER = """
import contextlib, io, json, sys
from spectrace import cli
from spectrace.errors import SpectraceError
from spectrace.scene import load_scene
output, scenes = sys.argv[1], sys.argv[2:]
results = {}
for path in scenes:
    try:
        load_scene(path)
        results[path] = None
    except SpectraceError as error:
        results[path] = str(error)
# VmHWM, the peak of this process image: ru_maxrss would keep the peak of the pytest worker that started it, which
# Linux carries across fork and exec (a worker grown by earlier tests made this child look 1.8 GiB).
peak = next(int(line.split()[1]) * 1024 for line in open("/proc/self/status") if line.startswith("VmHWM:"))
sys.argv = ["spectrace", "render", scenes[0], "-o", output]
stderr = io.StringIO()
with contextlib.redirect_stderr(stderr):
    try:
        cli.main()
    except SystemExit as exit:
        status = exit.code
print(json.dumps({"errors": results, "peak_bytes": peak, "cli_status": status, "cli_stderr": stderr.getvalue()}))
"""

# Each case: scene text with {bad} where the pipe or device goes, the key path named, and a file name for the
# FIFO (its extension picks the reader).
SPECIAL_CASES = {
    "spectrum": (_scene_text(reflectance='file = "{bad}"'), "materials.black.reflectance.file", "r.csv"),
    "display": (
        _scene_text(radiance='display = "{bad}", rgb = [1, 1, 1], white_luminance = 100'),
        "shapes[0].emitter.radiance.display",
        "screen.csv",
    ),
    "mesh": (_scene_text(shape='type = "mesh"\nfile = "{bad}"'), "shapes[0].file", "m.obj"),
    "picture": (
        _scene_text(radiance='display = "LCD-Dell_CCFL", image = "{bad}"'),
        "shapes[0].emitter.radiance.image",
        "p.png",
    ),
    "environment map": (
        _scene_text(extra='[[lights]]\ntype = "envmap"\nfile = "{bad}"\n'),
        "lights[0].file",
        "sky.exr",
    ),
}


def _png_claiming(width: int, height: int) -> bytes:
    """A valid 1-bit greyscale PNG of zeros: width x height pixels in a file of a few tens of kilobytes."""

    def chunk(kind: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))

    row = b"\0" * (1 + (width + 7) // 8)  # filter byte, then the packed bits
    pixels = zlib.compress(row * height, 9)
    header = struct.pack(">IIBBBBB", width, height, 1, 0, 0, 0, 0)
    return b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", pixels) + chunk(b"IEND", b"")


@pytest.fixture(scope="module")
def special_loads(tmp_path_factory):
    """One child process loads every scene whose file is a FIFO or /dev/zero, and the image bomb."""
    folder = tmp_path_factory.mktemp("special")
    scenes, expected = [], {}
    for name, (text, key, fifo_name) in SPECIAL_CASES.items():
        os.mkfifo(folder / fifo_name)
        for label, bad in (("FIFO", fifo_name), ("/dev/zero", "/dev/zero")):
            scene = folder / f"{name.replace(' ', '_')}-{label.strip('/').replace('/', '_')}.toml"
            scene.write_text(text.replace("{bad}", bad))
            kind = "a named pipe (FIFO)" if label == "FIFO" else "a character device"
            expected[str(scene)] = (f"{scene}: {key}: ", kind)
            scenes.append(str(scene))
    os.mkfifo(folder / "scene.toml")
    expected[str(folder / "scene.toml")] = (f"{folder / 'scene.toml'}: ", "a named pipe (FIFO)")
    expected["/dev/zero"] = ("/dev/zero: ", "a character device")
    (folder / "bomb.png").write_bytes(_png_claiming(12000, 12000))
    bomb = folder / "bomb.toml"
    bomb.write_text(_scene_text(radiance='display = "LCD-Dell_CCFL", image = "bomb.png"'))
    scenes = [str(folder / "scene.toml"), *scenes, "/dev/zero", str(bomb)]
    result = subprocess.run(
        [sys.executable, "-c", LOADER, str(folder / "out.png"), *scenes],
        capture_output=True,
        text=True,
        timeout=180,
        cwd=folder,
    )
    assert result.returncode == 0, result.stderr
    return json.loads(result.stdout), expected, str(bomb), folder


@pytest.mark.subprocess
@pytest.mark.slow
def test_pipes_and_devices_are_refused_without_reading(special_loads):
    """A FIFO with no writer would block the reader forever, /dev/zero would be read without end: every reader
    (scene, spectrum CSV, display CSV, mesh, picture, environment map) refuses both at once, naming the key."""
    loaded, expected, _, _ = special_loads
    for scene, (place, kind) in expected.items():
        message = loaded["errors"][scene]
        assert message is not None and message.startswith(place), (scene, message)
        assert f"is {kind}, not a regular file" in message and "\n" not in message, message


@pytest.mark.subprocess
@pytest.mark.slow
def test_an_image_whose_header_claims_a_huge_size_is_refused_before_decoding(special_loads):
    """A 12000x12000 PNG of zeros is a few kilobytes on disk; decoding it into the float RGB the screen needs
    would take about 10 GB. The size is read from the header, so the child's peak memory stays that of a
    Python process with its libraries."""
    loaded, _, bomb, folder = special_loads
    assert (folder / "bomb.png").stat().st_size < 100_000
    message = loaded["errors"][bomb]
    assert message == (
        f"{bomb}: shapes[0].emitter.radiance.image: image '{folder / 'bomb.png'}': a 12000x12000 "
        "image (144.0 Mpixels) would need about 9.7 GiB of host memory and 2.1 GiB of device memory; "
        "at most 134.2 Mpixels are allowed (e.g. 16384x8192)"
    )
    assert loaded["peak_bytes"] < 1.5 * 2**30, loaded["peak_bytes"]


@pytest.mark.subprocess
def test_a_fifo_scene_on_the_command_line_is_one_line(special_loads):
    loaded, _, _, folder = special_loads
    assert loaded["cli_status"] == 2
    fifo = folder / "scene.toml"
    assert loaded["cli_stderr"] == f"error: {fifo}: scene file is a named pipe (FIFO), not a regular file\n"


# ---------------------------------------------------------------- OBJ texture coordinates

# Two quads side by side, x in [-1, 0] and [0, 1], facing +z; each maps the whole picture (u 0 -> 1 left to
# right), so the two vertices on the shared edge carry u = 1 for the left quad and u = 0 for the right one:
# a texture seam, as on every UV-unwrapped model.
SEAM_POSITIONS = [(-1, -1, 0), (0, -1, 0), (0, 1, 0), (-1, 1, 0), (1, -1, 0), (1, 1, 0)]
SEAM_VT = [(0, 0), (1, 0), (1, 1), (0, 1)]  # OBJ: v up
SEAM_FACES = [
    ((1, 1), (2, 2), (3, 3)),
    ((1, 1), (3, 3), (4, 4)),  # (position, vt) indices, 1-based
    ((2, 1), (5, 2), (6, 3)),
    ((2, 1), (6, 3), (3, 4)),
]


def _write_seam_obj(path):
    lines = [f"v {x} {y} {z}" for x, y, z in SEAM_POSITIONS] + [f"vt {u} {v}" for u, v in SEAM_VT]
    lines += ["f " + " ".join(f"{p}/{t}" for p, t in face) for face in SEAM_FACES]
    path.write_text("\n".join(lines) + "\n")


def test_every_face_corner_keeps_its_own_texture_coordinate(tmp_path):
    _write_seam_obj(tmp_path / "seam.obj")
    mesh = load_mesh(tmp_path / "seam.obj", where="w")
    assert mesh.faces.shape == (4, 3)
    for face, corners in enumerate(SEAM_FACES):
        for k, (position, texture) in enumerate(corners):
            np.testing.assert_array_equal(mesh.vertices[mesh.faces[face, k]], SEAM_POSITIONS[position - 1])
            u, v = SEAM_VT[texture - 1]
            np.testing.assert_array_equal(mesh.triangle_uvs()[face, k], (u, 1 - v))  # spectrace's v runs down


def test_a_picture_on_an_obj_screen_follows_its_texture_coordinates(device, tmp_path):
    """A 2x1 picture (red | blue) on the two quads: the screen shows red, blue, red, blue from left to right,
    each stripe with the XYZ of the display's primary."""
    from PIL import Image as PILImage

    _write_seam_obj(tmp_path / "seam.obj")
    PILImage.fromarray(np.array([[[255, 0, 0], [0, 0, 255]]], np.uint8), "RGB").save(tmp_path / "picture.png")
    width, fov = 64, 40
    path = tmp_path / "screen.toml"
    path.write_text(
        _scene_text(
            shape='type = "mesh"\nfile = "seam.obj"',
            width=width,
            height=16,
            fov=fov,
            radiance='display = "LCD-Dell_CCFL", image = "picture.png", encoding = "srgb"',
        )
    )
    xyz = Renderer(load_scene(path), device).render().xyz.astype(np.float64)
    display = load_display("LCD-Dell_CCFL")
    # Image right is +x; pixel centres sit at x = ((column + 0.5) / width * 2 - 1) * 3 tan(fov / 2).
    x = ((np.arange(width) + 0.5) / width * 2 - 1) * 3 * np.tan(np.radians(fov / 2))
    for left, primary in ((-1.0, 0), (-0.5, 2), (0.0, 0), (0.5, 2)):
        columns = (x > left + 0.08) & (x < left + 0.42)
        region = xyz[:, columns].reshape(-1, 3)
        expected = display.film_xyz(np.eye(3)[primary])
        mean, standard_error = region.mean(axis=0), region.std(axis=0, ddof=1) / np.sqrt(len(region))
        assert np.all(np.abs(mean - expected) < 4 * standard_error + 1e-6 * expected.max()), (left, mean, expected)


# ---------------------------------------------------------------- large meshes say they are loading


def test_a_large_mesh_says_it_is_loading(tmp_path, monkeypatch, capsys):
    path = tmp_path / "m.obj"
    path.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    load_mesh(path, where="w")
    assert capsys.readouterr().err == ""  # below the threshold: nothing
    monkeypatch.setenv(mesh_module.PROGRESS_ENVIRONMENT, "0.00001")  # 10 bytes
    load_mesh(path, where="w")
    lines = capsys.readouterr().err.splitlines()
    assert lines[0] == f"loading mesh '{path}' (0.0 MB)..."
    assert lines[1].startswith(f"loaded mesh '{path}': 1 triangles in ") and lines[1].endswith(" s")
    assert len(lines) == 2


# ---------------------------------------------------------------- cache folder


@pytest.mark.subprocess
@pytest.mark.slow
def test_an_unwritable_cache_folder_falls_back_and_rendering_works(tmp_path):
    """XDG_CACHE_HOME naming a file made PoCL and pyopencl fail, reported as 'no working OpenCL device'."""
    from spectrace.device.discovery import cache_root

    not_a_folder = tmp_path / "cache"
    not_a_folder.write_text("a file, not a folder")
    scene = tmp_path / "scene.toml"
    scene.write_text(_scene_text(reflectance="value = 0.5"))
    # The usual kernel cache stays in use, so that only the broken XDG_CACHE_HOME is at stake (and no rebuild).
    environment = dict(os.environ, XDG_CACHE_HOME=str(not_a_folder), SPECTRACE_CACHE_DIR=str(cache_root()))
    result = subprocess.run(
        [sys.executable, "-m", "spectrace", "render", str(scene), "-o", str(tmp_path / "x.png"), "--spp", "1", "-q"],
        capture_output=True,
        text=True,
        timeout=300,
        env=environment,
    )
    assert result.returncode == 0, result.stderr
    assert (tmp_path / "x.png").stat().st_size > 0
    warnings = [line for line in result.stderr.splitlines() if line.startswith("warning:")]
    assert len(warnings) == 1 and f"cache folder '{not_a_folder}' cannot be written (it is not a folder)" in warnings[0]
    assert "Traceback" not in result.stderr and "matplotlib" not in result.stderr.replace(warnings[0], "")


def test_an_unwritable_spectrace_cache_dir_points_at_a_private_folder(tmp_path, monkeypatch, capsys):
    from spectrace import cache_folder

    blocked = tmp_path / "file"
    blocked.write_text("")
    monkeypatch.setattr(cache_folder, "_checked", False)
    monkeypatch.setenv("SPECTRACE_CACHE_DIR", str(blocked / "spectrace"))
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    cache_folder.ensure_usable_cache_folder()
    stand_in = os.environ["SPECTRACE_CACHE_DIR"]
    assert os.environ["XDG_CACHE_HOME"] == str(tmp_path / "xdg")  # writable: left alone
    assert stand_in != str(blocked / "spectrace")
    folder = os.path.dirname(stand_in)
    status = os.stat(folder)
    assert status.st_uid == os.getuid() and status.st_mode & 0o077 == 0  # nobody else can plant kernels there
    assert capsys.readouterr().err.count("\n") == 1
