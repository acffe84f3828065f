"""Bad input, case by case: `spectrace render` exits with status 2 and one line that names the file and the key
path and says what is wrong, never a traceback.

Every case runs through the command line's entry point in this process (fast); a few also run as a real
subprocess, to show that nothing but that line reaches the terminal.
"""

import importlib
import os
import sys
from dataclasses import dataclass, field

import pytest

from cli_runner import run_in_process as _run_in_process
from cli_runner import run_spectrace
from scene_text import glowing_rectangle
from spectrace import cli

BASE = glowing_rectangle()

FILES = {
    "garbage.obj": bytes(range(256)) * 8,
    "garbage.ply": b"ply\nformat ascii 1.0\nelement vertex 3\n" + bytes(range(128, 256)),
    "empty.obj": b"# an exported mesh with nothing in it\n",
    "points.obj": b"v 0 0 0\nv 1 0 0\nv 0 1 0\n",
    "nan.obj": b"v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n",
    "inf.obj": b"v 0 0 0\nv 1 0 0\nv 0 inf 0\nf 1 2 3\n",
    "far.obj": b"v 0 0 0\nv 1e15 0 0\nv 0 1 0\nf 1 2 3\n",
    "nan.csv": b"wavelength_nm,r\n400,0.5\n500,nan\n",
    "negative.csv": b"wavelength_nm,r\n400,0.5\n500,-0.2\n",
    "descending.csv": b"wavelength_nm,r\n500,0.5\n400,0.2\n",
    "binary.exr": bytes(range(256)) * 4,
    "underscore.csv": b"wavelength_nm,r\n400,0.5\n500,0_5\n",
    "repeated.csv": b"wavelength_nm,r,g,r\n400,0.5,0.5,0.1\n500,0.5,0.5,0.1\n",
    "zero-index.obj": b"v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3\nf 2 4 0\n",
}


def _huge_header_exr() -> bytes:
    """A 2x2 OpenEXR whose header claims 20000x20000 pixels (what a damaged or hostile file can do)."""
    import struct
    import tempfile

    import numpy as np
    import OpenEXR

    with tempfile.TemporaryDirectory() as folder:
        path = f"{folder}/small.exr"
        with OpenEXR.File(
            {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage},
            {"RGB": np.ones((2, 2, 3), np.float32)},
        ) as exr:
            exr.write(path)
        with open(path, "rb") as stream:
            data = stream.read()
    # The attribute is its name, its type, a 4-byte size and the box: x_min, y_min, x_max, y_max (int32).
    box = data.index(b"dataWindow\0box2i\0") + len(b"dataWindow\0box2i\0") + 4
    return data[:box] + struct.pack("<4i", 0, 0, 19999, 19999) + data[box + 16 :]


FILES["huge.exr"] = _huge_header_exr()


@dataclass(frozen=True)
class BadInput:
    name: str
    old: str  # replaced in BASE by `new`; "" appends `new`
    new: str
    where: str  # the key path after "<scene file>: "; "" for file-level errors
    says: str  # a fragment of the message
    argv: tuple = field(default=())  # extra command-line options


def replace(name, old, new, where, says, argv=()):
    return BadInput(name, old, new, where, says, tuple(argv))


def append(name, text, where, says):
    return BadInput(name, "", text, where, says)


SHAPE = 'type = "rectangle"'
REFLECTANCE = "reflectance = { value = 0.5 }"
RADIANCE = "radiance = { value = 1.0 }"

CASES = [
    # syntax and structure
    replace("toml-syntax", "fov = 40", "fov = = 40", "", "TOML syntax error: Invalid value (at line 8, column 7)"),
    replace("toml-duplicate-key", "fov = 40", "fov = 40\nfov = 41", "", "Cannot overwrite a value (at line 9"),
    replace("not-utf8", "fov = 40", "fov = 40 # \udcff", "", "not a UTF-8 text file"),
    replace("unknown-key", "fov = 40", "fvo = 40", "camera.fvo", "unknown key 'fvo' (did you mean 'fov'?)"),
    replace(
        "unknown-nested-key",
        REFLECTANCE,
        "reflectance = { valeu = 0.5 }",
        "materials.grey.reflectance.valeu",
        "unknown key 'valeu' (did you mean 'value'?)",
    ),
    replace("wrong-type-int", "width = 8", 'width = "eight"', "film.width", "expected a whole number"),
    replace("wrong-type-fraction", "width = 8", "width = 8.5", "film.width", "expected a whole number, got 8.5"),
    replace("wrong-type-bool-int", "width = 8", "width = true", "film.width", "expected a whole number, got true"),
    replace(
        "wrong-type-vector", "origin = [0, 0, 5]", 'origin = "here"', "camera.origin", "expected an array, got 'here'"
    ),
    replace("wrong-type-table", "[film]\nwidth = 8\nheight = 6", "film = 3", "film", "expected a table"),
    replace("short-vector", "origin = [0, 0, 5]", "origin = [0, 5]", "camera.origin[2]", "required key is missing"),
    replace("missing-required", "fov = 40", "", "camera.fov", "required key is missing"),
    replace("missing-section", "[film]\nwidth = 8\nheight = 6", "", "film", "required key is missing"),
    replace("unknown-shape-type", SHAPE, 'type = "torus"', "shapes[0].type", "'mesh', 'rectangle', 'cube'"),
    append(
        "unknown-light-type",
        '[[lights]]\ntype = "laser"\nposition = [0, 0, 0]\n',
        "lights[0].type",
        "unknown type 'laser' (one of",
    ),
    replace(
        "toml-nested-too-deep",
        "fov = 40",
        "fov = 40\nx = " + "[" * 5000 + "]" * 5000,
        "",
        "arrays or inline tables nested too deep to parse",
    ),
    append(
        "toml-tables-nested-too-deep", "[x" + ".a" * 5000 + "]\n", "x.a.a", "values nested more than 64 levels deep"
    ),
    # references
    replace(
        "undefined-material",
        'material = "grey"',
        'material = "gery"',
        "shapes[0].material",
        "undefined material 'gery' (did you mean 'grey'?)",
    ),
    replace(
        "undefined-spectrum",
        REFLECTANCE,
        'reflectance = { spectrum = "whte" }',
        "materials.grey.reflectance.spectrum",
        "undefined spectrum 'whte'",
    ),
    replace(
        "undefined-library-column",
        REFLECTANCE,
        'reflectance = { spectrum = "cornell_box/reflectance:blue" }',
        "materials.grey.reflectance.spectrum",
        "unknown column 'blue' (available: white, red, green)",
    ),
    # files
    replace("missing-mesh", SHAPE, 'type = "mesh"\nfile = "nope.obj"', "shapes[0].file", "nope.obj' does not exist"),
    replace("mesh-is-a-folder", SHAPE, 'type = "mesh"\nfile = "."', "shapes[0].file", "is a folder, not a file"),
    replace(
        "garbage-mesh",
        SHAPE,
        'type = "mesh"\nfile = "garbage.obj"',
        "shapes[0].file",
        # trimesh either refuses the text or reads no triangles from it, depending on its release: the line names
        # the file either way.
        "mesh file '{folder}/garbage.obj'",
    ),
    replace("garbage-ply", SHAPE, 'type = "mesh"\nfile = "garbage.ply"', "shapes[0].file", "cannot read mesh file"),
    replace("empty-mesh", SHAPE, 'type = "mesh"\nfile = "empty.obj"', "shapes[0].file", "contains no triangles"),
    replace(
        "mesh-without-faces", SHAPE, 'type = "mesh"\nfile = "points.obj"', "shapes[0].file", "contains no triangles"
    ),
    replace(
        "missing-spectrum-file",
        REFLECTANCE,
        'reflectance = { file = "nope.csv" }',
        "materials.grey.reflectance.file",
        "nope.csv: spectrum file does not exist",
    ),
    replace(
        "spectrum-file-is-a-folder",
        REFLECTANCE,
        'reflectance = { file = "." }',
        "materials.grey.reflectance.file",
        "spectrum file is a folder, not a file",
    ),
    replace(
        "garbage-spectrum-file",
        REFLECTANCE,
        'reflectance = { file = "garbage.obj" }',
        "materials.grey.reflectance.file",
        "cannot read spectrum file: not a UTF-8 text file (byte 0x80 at offset 128)",
    ),
    replace(
        "descending-spectrum-file",
        REFLECTANCE,
        'reflectance = { file = "descending.csv" }',
        "materials.grey.reflectance.file",
        "strictly ascending",
    ),
    append(
        "missing-texture",
        '[[lights]]\ntype = "envmap"\nfile = "sky.exr"\n',
        "lights[0].file",
        "sky.exr' does not exist",
    ),
    append(
        "garbage-texture",
        '[[lights]]\ntype = "envmap"\nfile = "binary.exr"\n',
        "lights[0].file",
        "cannot read environment map",
    ),
    replace(
        "spectrum-file-underscore",
        REFLECTANCE,
        'reflectance = { file = "underscore.csv" }',
        "materials.grey.reflectance.file",
        "underscore.csv:3: '0_5' is not a number (value in column 'r')",
    ),
    replace(
        "spectrum-file-repeated-column",
        REFLECTANCE,
        'reflectance = { file = "repeated.csv", column = "r" }',
        "materials.grey.reflectance.file",
        "repeated.csv:1: column 'r' appears twice in the header",
    ),
    replace(
        "mesh-face-index-zero",
        SHAPE,
        'type = "mesh"\nfile = "zero-index.obj"',
        "shapes[0].file",
        "zero-index.obj' line 6: face index 0 (OBJ indices start at 1)",
    ),
    append(
        "huge-environment-map",
        '[[lights]]\ntype = "envmap"\nfile = "huge.exr"\n',
        "lights[0].file",
        "a 20000x20000 image (400.0 Mpixels) would need about 26.8 GiB of host memory and 6.0 GiB of device "
        "memory; at most 134.2 Mpixels are allowed",
    ),
    # non-physical values
    replace(
        "negative-reflectance",
        REFLECTANCE,
        "reflectance = { value = -0.1 }",
        "materials.grey.reflectance",
        "spectrum has negative values",
    ),
    replace(
        "reflectance-above-one",
        REFLECTANCE,
        "reflectance = { value = 1.2 }",
        "materials.grey.reflectance",
        "reflectance exceeds 1 (max 1.2): it would create energy",
    ),
    replace(
        "rgb-reflectance-above-one",
        REFLECTANCE,
        "reflectance = { rgb = [1.2, 0.5, 0.5] }",
        "materials.grey.reflectance.rgb",
        "must lie in [0, 1]",
    ),
    replace(
        "negative-spectrum-file",
        REFLECTANCE,
        'reflectance = { file = "negative.csv" }',
        "materials.grey.reflectance",
        "negative",
    ),
    replace(
        "negative-radiance",
        RADIANCE,
        "radiance = { value = -1.0 }",
        "shapes[0].emitter.radiance",
        "spectrum has negative values",
    ),
    replace(
        "negative-scale",
        RADIANCE,
        "radiance = { value = 1.0, scale = -2 }",
        "shapes[0].emitter.radiance",
        "scale must be >= 0",
    ),
    replace(
        "overflowing-radiance", RADIANCE, "radiance = { value = 1e30 }", "shapes[0].emitter.radiance", "beyond 1e+20"
    ),
    append(
        "negative-power",
        '[[lights]]\ntype = "point"\nposition = [0, 1, 0]\npower = -5\n',
        "lights[0]",
        "power must be >= 0 W",
    ),
    replace(
        "zero-blackbody",
        RADIANCE,
        "radiance = { blackbody = 0 }",
        "shapes[0].emitter.radiance",
        "blackbody temperature must be > 0 K",
    ),
    # NaN and infinity
    replace("nan-number", "fov = 40", "fov = nan", "camera.fov", "finite number"),
    replace("inf-in-vector", "origin = [0, 0, 5]", "origin = [0, inf, 5]", "camera.origin[1]", "finite number"),
    replace(
        "nan-reflectance",
        REFLECTANCE,
        "reflectance = { value = nan }",
        "materials.grey.reflectance.value",
        "finite number",
    ),
    replace(
        "nan-inline-spectrum",
        REFLECTANCE,
        'reflectance = { values = "400:0.5, 500:nan" }',
        "materials.grey.reflectance.values",
        "is nan; spectra must be finite",
    ),
    replace(
        "inf-inline-spectrum-list",
        REFLECTANCE,
        "reflectance = { values = [[400, 0.5], [500, inf]] }",
        "materials.grey.reflectance.values[1][1]",
        "finite number",
    ),
    replace(
        "nan-spectrum-file",
        REFLECTANCE,
        'reflectance = { file = "nan.csv" }',
        "materials.grey.reflectance.file",
        "nan.csv:3: value in column 'r' is nan",
    ),
    replace(
        "nan-mesh-vertex",
        SHAPE,
        'type = "mesh"\nfile = "nan.obj"',
        "shapes[0].file",
        "nan.obj' has 1 vertices with NaN or infinite coordinates",
    ),
    replace(
        "inf-mesh-vertex",
        SHAPE,
        'type = "mesh"\nfile = "inf.obj"',
        "shapes[0].file",
        "inf.obj' has 1 vertices with NaN or infinite coordinates",
    ),
    replace(
        "transform-overflow",
        'material = "grey"',
        'material = "grey"\ntransform = [{ scale = 1e300 }, { scale = 1e300 }]',
        "shapes[0].transform",
        "NaN or infinite entries (the product of its steps overflows)",
    ),
    # sizes and ranges
    replace("zero-width", "width = 8", "width = 0", "film.width", "must be > 0"),
    replace("negative-height", "height = 6", "height = -6", "film.height", "must be > 0"),
    replace("fov-zero", "fov = 40", "fov = 0", "camera.fov", "fov must lie in (0, 180) degrees"),
    replace("fov-180", "fov = 40", "fov = 180", "camera.fov", "fov must lie in (0, 180) degrees"),
    replace("absurd-width", "width = 8", "width = 1000000", "film.width", "exceeds the limit of 16384 px"),
    replace(
        "absurd-resolution",
        "width = 8\nheight = 6",
        "width = 16384\nheight = 16384",
        "film",
        "would need 5.0 GiB of device memory",
    ),
    append("absurd-spp", "[sampler]\nspp = 100000000\n", "sampler.spp", "exceeds the limit of 1048576"),
    replace(
        "camera-target-is-origin",
        "target = [0, 0, 0]",
        "target = [0, 0, 5]",
        "camera.target",
        "camera target equals origin",
    ),
    replace("camera-up-parallel", "fov = 40", "fov = 40\nup = [0, 0, 1]", "camera.up", "parallel"),
    replace(
        "huge-coordinates-file", SHAPE, 'type = "mesh"\nfile = "far.obj"', "shapes[0].file", "beyond ±1e+12 scene units"
    ),
    replace("huge-camera", "origin = [0, 0, 5]", "origin = [0, 0, 1e14]", "camera.origin", "beyond ±1e+12"),
    replace(
        "singular-transform",
        'material = "grey"',
        'material = "grey"\ntransform = [{ scale = [1, 0, 1] }]',
        "shapes[0].transform[0].scale",
        "non-zero",
    ),
    # command-line overrides
    replace(
        "override-absurd-size",
        "",
        "",
        "--width/--height",
        "would need 5.0 GiB of device memory",
        argv=("--width", "16384", "--height", "16384"),
    ),
    replace("override-absurd-spp", "", "", "--spp", "exceeds the limit of 1048576", argv=("--spp", "2000000")),
    replace("override-zero-spp", "", "", "--spp", "must be ≥ 1", argv=("--spp", "0")),
    replace(
        "override-non-integer-width", "", "", "--width", "must be a whole number, got 'wide'", argv=("--width", "wide")
    ),
    replace("unknown-output-format", "", "", "out.bmp", "unknown image format '.bmp'", argv=("-o", "{folder}/out.bmp")),
    replace(
        "missing-checkpoint",
        "",
        "",
        "nope.npz",
        "checkpoint file does not exist",
        argv=("--resume", "{folder}/nope.npz"),
    ),
    replace(
        "damaged-checkpoint",
        "",
        "",
        "{folder}/garbage.obj",
        "not a spectrace checkpoint",
        argv=("--resume", "{folder}/garbage.obj"),
    ),
    # options no scene file sets, at the limits the kernels and the outputs can take
    replace(
        "override-seed-beyond-int32",
        "",
        "",
        "--seed",
        "seed must lie in 0..2147483647 (the kernels take it as a 32-bit signed integer), got 2147483648",
        argv=("--seed", "2147483648"),
    ),
    replace("override-negative-seed", "", "", "--seed", "must be ≥ 0", argv=("--seed", "-1")),
    replace(
        "override-huge-depth",
        "",
        "",
        "--max-depth",
        "max_depth must be at most 2147483647",
        argv=("--max-depth", "99999999999"),
    ),
    replace(
        "override-zero-depth",
        "",
        "",
        "--max-depth",
        "max_depth must be -1 (unbounded) or >= 1, got 0",
        argv=("--max-depth", "0"),
    ),
    replace(
        "override-negative-depth",
        "",
        "",
        "--max-depth",
        "max_depth must be -1 (unbounded) or >= 1, got -5",
        argv=("--max-depth", "-5"),
    ),
    replace(
        "override-nan-exposure",
        "",
        "",
        "--exposure",
        "must be a finite number, got nan",
        argv=("--exposure", "nan"),
    ),
    replace(
        "override-inf-exposure", "", "", "--exposure", "must be a finite number, got inf", argv=("--exposure", "inf")
    ),
    replace(
        "override-huge-exposure",
        "",
        "",
        "--exposure",
        "exposure 1e+308 stops is beyond ±64",
        argv=("--exposure", "1e308"),
    ),
    append(
        "huge-depth",
        "[integrator]\nmax_depth = 99999999999\n",
        "integrator.max_depth",
        "must be ≤ 2147483647",
    ),
    append("seed-beyond-int32", "[sampler]\nseed = 2147483648\n", "sampler.seed", "must be ≤ 2147483647"),
    # outputs that could not be written, or would replace something, are refused before the render
    replace(
        "output-is-a-folder",
        "",
        "",
        "{folder}/a-folder.png",
        "--output names a folder",
        argv=("-o", "{folder}/a-folder.png"),
    ),
    replace(
        "output-folder-missing",
        "",
        "",
        "{folder}/nope/out.png",
        "the folder {folder}/nope for --output does not exist",
        argv=("-o", "{folder}/nope/out.png"),
    ),
    replace(
        "output-folder-is-a-file",
        "",
        "",
        "{folder}/garbage.obj/out.png",
        "is not a folder",
        argv=("-o", "{folder}/garbage.obj/out.png"),
    ),
    replace(
        "output-read-only",
        "",
        "",
        "{folder}/read-only.png",
        "--output names a read-only file",
        argv=("-o", "{folder}/read-only.png"),
    ),
    replace(
        "false-colour-is-a-folder",
        "",
        "",
        "{folder}/a-folder.png",
        "--false-color names a folder",
        argv=("--false-color", "{folder}/a-folder.png"),
    ),
    replace(
        "false-colour-folder-missing",
        "",
        "",
        "{folder}/nope/map.png",
        "for --false-color does not exist",
        argv=("--false-color", "{folder}/nope/map.png"),
    ),
    replace(
        "false-colour-read-only",
        "",
        "",
        "{folder}/read-only.png",
        "--false-color names a read-only file",
        argv=("--false-color", "{folder}/read-only.png"),
    ),
    replace(
        "checkpoint-is-a-folder",
        "",
        "",
        "{folder}/a-folder.npz",
        "--checkpoint names a folder",
        argv=("--checkpoint", "{folder}/a-folder.npz"),
    ),
    replace(
        "checkpoint-folder-missing",
        "",
        "",
        "{folder}/nope/state.npz",
        "for --checkpoint does not exist",
        argv=("--checkpoint", "{folder}/nope/state.npz"),
    ),
    replace(
        "output-is-false-colour",
        "",
        "",
        "{folder}/out.png",
        "--output and --false-color name the same file",
        argv=("--false-color", "{folder}/out.png"),
    ),
    replace(
        "output-is-checkpoint",
        "",
        "",
        "{folder}/x.png",
        "--output and --checkpoint name the same file",
        argv=("-o", "{folder}/x.png", "--checkpoint", "{folder}/a-folder.png/../x.png"),
    ),
    replace(
        "output-is-resumed-checkpoint",
        "",
        "",
        "{folder}/garbage.png",
        "--output and --resume name the same file",
        argv=("-o", "{folder}/garbage.png", "--resume", "{folder}/garbage.png"),
    ),
    replace(
        "false-colour-is-checkpoint",
        "",
        "",
        "{folder}/map.png",
        "--false-color and --checkpoint name the same file",
        argv=("--false-color", "{folder}/map.png", "--checkpoint", "{folder}/link-to-map.png"),
    ),
    replace(
        "checkpoint-is-the-scene",
        "",
        "",
        "{folder}/scene.toml",
        "--checkpoint names the scene file",
        argv=("--checkpoint", "{folder}/scene.toml"),
    ),
    replace(
        "overwrite-with-resume",
        "",
        "",
        "--overwrite",
        "cannot go with --resume",
        argv=("--resume", "{folder}/garbage.obj", "--overwrite"),
    ),
]
# Which part of the message is the place: most name the scene, these the option or the file it gave.
NAMES_OTHER_FILE = {
    "unknown-output-format",
    "missing-checkpoint",
    "damaged-checkpoint",
    "override-absurd-size",
    "override-absurd-spp",
    "override-zero-spp",
    "override-non-integer-width",
}
NAMES_OTHER_FILE |= {c.name for c in CASES if c.argv and c.name not in ("huge-depth", "seed-beyond-int32")}


def _write_case(folder, case: BadInput):
    for name, content in FILES.items():
        (folder / name).write_bytes(content)
    for name in ("a-folder.png", "a-folder.npz"):
        (folder / name).mkdir()
    (folder / "read-only.png").write_bytes(b"a picture to keep")
    (folder / "read-only.png").chmod(0o444)
    (folder / "link-to-map.png").symlink_to(folder / "map.png")  # dangling until the map is written
    text = BASE + case.new if case.old == "" else BASE.replace(case.old, case.new)
    assert case.old == "" or case.old in BASE, case.name
    scene = folder / "scene.toml"
    scene.write_bytes(text.encode("utf-8", "surrogateescape"))
    argv = [a.format(folder=folder) for a in case.argv]
    if "-o" not in argv:
        argv += ["-o", str(folder / "out.png")]
    return scene, ["render", str(scene), *argv, "-q"]


def _no_device(*args, **kwargs):
    raise AssertionError("the device was opened before the input was refused")


@pytest.mark.parametrize("case", CASES, ids=[c.name for c in CASES])
def test_bad_input_is_one_line_naming_file_and_key(case, tmp_path, monkeypatch, capsys):
    scene, argv = _write_case(tmp_path, case)
    before = {path: path.read_bytes() for path in tmp_path.iterdir() if path.is_file()}
    # refused before any device work
    monkeypatch.setattr(importlib.import_module("spectrace.engine.wavefront"), "make_renderer", _no_device)
    status, stderr = _run_in_process(monkeypatch, capsys, argv)
    assert status == 2, stderr
    lines = [line for line in stderr.splitlines() if line.strip() and not line.startswith(("device: ", "scene: "))]
    assert len(lines) == 1, stderr
    message = lines[0]
    assert "Traceback" not in stderr
    if case.name in NAMES_OTHER_FILE:
        expected_place = f"{case.where.format(folder=tmp_path)}: "
    else:
        expected_place = f"{scene}: {case.where}: " if case.where else f"{scene}: "
    assert message.startswith("error: ") and expected_place in message, message
    assert case.says.format(folder=tmp_path) in message, message
    assert {path: path.read_bytes() for path in tmp_path.iterdir() if path.is_file()} == before  # nothing replaced


@pytest.mark.subprocess
@pytest.mark.slow
def test_a_real_process_prints_only_the_line(tmp_path):
    case = next(c for c in CASES if c.name == "nan-mesh-vertex")
    scene, argv = _write_case(tmp_path, case)
    result = run_spectrace(*argv, timeout=300)
    assert result.returncode == 2
    assert "Traceback" not in result.stderr and result.stdout == ""
    assert result.stderr.count("\n") == 1 and result.stderr.startswith("error: "), result.stderr
    assert case.says in result.stderr


def test_a_missing_device_says_how_to_list_and_pick(tmp_path, monkeypatch, capsys):
    scene, argv = _write_case(tmp_path, replace("fine", "", "", "", ""))
    status, stderr = _run_in_process(monkeypatch, capsys, [*argv, "--device", "no-such-device"])
    assert status == 2 and stderr.count("\n") == 1, stderr
    assert "no OpenCL device matches 'no-such-device'; available devices:" in stderr
    assert "pick one with --device KEY or SPECTRACE_DEVICE=KEY; `spectrace devices` shows each" in stderr


@pytest.mark.skipif(
    hasattr(os, "geteuid") and os.geteuid() == 0,
    reason="the superuser can create files in a read-only folder: there is nothing to refuse",
)
def test_a_read_only_folder_is_refused_before_rendering(tmp_path, monkeypatch, capsys):
    scene, argv = _write_case(tmp_path, replace("fine", "", "", "", ""))
    locked = tmp_path / "locked"
    locked.mkdir()
    locked.chmod(0o555)
    monkeypatch.setattr(importlib.import_module("spectrace.engine.wavefront"), "make_renderer", _no_device)
    try:
        for option in ("-o", "--false-color", "--checkpoint"):
            status, stderr = _run_in_process(monkeypatch, capsys, [*argv, option, str(locked / "file.png")])
            assert status == 2 and stderr.count("\n") == 1, stderr
            assert f"cannot create files in the folder {locked} for " in stderr
    finally:
        locked.chmod(0o755)


def test_unbounded_depth_stays_valid(tmp_path, monkeypatch, capsys):
    scene, argv = _write_case(tmp_path, replace("fine", "", "", "", ""))
    status, stderr = _run_in_process(monkeypatch, capsys, [*argv, "--max-depth", "-1", "--spp", "1"])
    assert status == 0, stderr
    assert (tmp_path / "out.png").is_file()


@pytest.mark.parametrize(
    "argv, says",
    [
        (("--max-depth", "0"), "error: --max-depth: max_depth must be -1 (unbounded) or >= 1, got 0"),
        (("--max-depth", "99999999999"), "error: --max-depth: max_depth must be at most 2147483647"),
        (("--size", "100000"), "error: --size: film width 100000 px exceeds the limit of 16384 px"),
        (("quality", "--seconds", "inf"), "error: --seconds: must be a finite number, got inf"),
        (("scaling", "--size", "0"), "error: --size: width must be ≥ 1, got 0"),
    ],
)
def test_bench_applies_the_render_limits(argv, says, monkeypatch, capsys):
    monkeypatch.setattr(importlib.import_module("spectrace.engine.wavefront"), "make_renderer", _no_device)
    status, stderr = _run_in_process(monkeypatch, capsys, ["bench", *argv])
    assert status == 2 and stderr.count("\n") == 1 and stderr.startswith(says), stderr


@pytest.mark.parametrize("luminance", ["nan", "0", "5e-324", "1e-7", "2e10", "1e300"])
def test_white_luminance_outside_any_display_is_refused(luminance, monkeypatch, capsys):
    status, stderr = _run_in_process(
        monkeypatch,
        capsys,
        ["display", "metamerism", "--from", "CRT-Dell", "--to", "LCD-Apple_WLED", "--white-luminance", luminance],
    )
    assert status == 2 and stderr.count("\n") == 1 and stderr.startswith("error: --white-luminance: "), stderr


@pytest.mark.parametrize("luminance", ["1e-6", "1e10"])
def test_the_ends_of_the_white_luminance_range_give_finite_figures(luminance, monkeypatch, capsys):
    import json
    import math

    monkeypatch.setattr(
        sys,
        "argv",
        [
            "spectrace",
            "display",
            "metamerism",
            "--from",
            "CRT-Dell",
            "--to",
            "LCD-Apple_WLED",
            "--white-luminance",
            luminance,
            "--json",
        ],
    )
    with pytest.raises(SystemExit) as exit_info:
        cli.main()
    captured = capsys.readouterr()
    assert exit_info.value.code == 0, captured.err
    report = json.loads(captured.out)
    differences = [patch["delta_e_2000"] for patch in report["patches"]]
    assert differences and all(math.isfinite(d) for d in differences)


@pytest.mark.parametrize(
    "title, says",
    [
        ("$$", "error: --title: cannot typeset '$$': ParseException: Expected end of text, found '$'"),
        ("$^$", "error: --title: cannot typeset '$^$': ParseSyntaxException: Expected ..., found end of text"),
    ],
)
def test_a_title_matplotlib_cannot_typeset_is_one_line(title, says, tmp_path, monkeypatch, capsys):
    status, stderr = _run_in_process(
        monkeypatch, capsys, ["spectra", "plot", "cie:D65", "-o", str(tmp_path / "x.png"), "--title", title]
    )
    assert status == 2 and stderr.count("\n") == 1 and stderr.startswith(says), stderr
    assert "write \\$ for a dollar sign" in stderr and not (tmp_path / "x.png").exists()


def test_a_file_name_with_line_breaks_still_gives_one_line(tmp_path, monkeypatch, capsys):
    scene, argv = _write_case(tmp_path, replace("fine", "", "", "", ""))
    odd = tmp_path / "line\nbreak\x85\u2028.bmp"
    status, stderr = _run_in_process(monkeypatch, capsys, [*argv, "-o", str(odd)])
    assert status == 2 and stderr.count("\n") == 1 and len(stderr.splitlines()) == 1, stderr
    assert f"error: {tmp_path}/line\\nbreak\\x85\\u2028.bmp: unknown image format '.bmp'" in stderr


def test_black_on_the_displays(tmp_path, monkeypatch, capsys):
    """Black emits nothing: `compare` shows it (no chromaticity) and plots it without numpy warnings; `metamerism`,
    which needs the light as its white, refuses it in one line. (Both failed with a traceback once.)"""
    import warnings

    plot = tmp_path / "black.png"
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        status, stderr = _run_in_process(
            monkeypatch,
            capsys,
            [
                "display",
                "compare",
                "--rgb",
                "0",
                "0",
                "0",
                "-d",
                "CRT-Dell",
                "-d",
                "LCD-Apple_WLED",
                "--plot",
                str(plot),
            ],
        )
    assert status == 0 and stderr == "" and plot.stat().st_size > 0
    status, stderr = _run_in_process(
        monkeypatch,
        capsys,
        ["display", "metamerism", "--from", "CRT-Dell", "--to", "LCD-Apple_WLED", "--rgb", "0", "0", "0"],
    )
    assert status == 2 and stderr == (
        "error: --rgb: the triple (0.0, 0.0, 0.0) on CRT-Dell gives no light to see the patches by\n"
    ), stderr
