"""One way in for every scene: any format `render` takes is read by suffix or, failing that, by its first bytes;
bare scene names work wherever a scene is named; `--set`, `--integrator`, `--version`; a lone `--width` keeps the
scene's aspect; `-q` leaves only warnings and errors; long commands show progress."""

import importlib.metadata
import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from cli_runner import run_here
from spectrace.errors import SpectraceError
from spectrace.interop.scene_files import load_any_scene, scene_format, sniff_format
from spectrace.resources import scenes_dir

# A pbrt-v4 scene in pbrt's own words (pbrt-v4 file format): a quad under a point light, 32 x 16 pixels.
QUAD_PBRT = """# a quad lit by a point light
LookAt 0 0 5  0 0 0  0 1 0
Camera "perspective" "float fov" 40
Film "rgb" "integer xresolution" 32 "integer yresolution" 16 "string filename" "quad.exr"
Sampler "independent" "integer pixelsamples" 4
WorldBegin
LightSource "point" "rgb I" [10 10 10] "point3 from" [0 0 3]
Material "diffuse"
Shape "trianglemesh" "point3 P" [-1 -1 0 1 -1 0 1 1 0 -1 1 0] "integer indices" [0 1 2 0 2 3]
"""


def _spectrace(*args: str, cwd: Path | None = None) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "spectrace", *args],
        capture_output=True,
        text=True,
        cwd=cwd,
        env=os.environ.copy(),
        timeout=300,
    )


def _one_error_line(result: subprocess.CompletedProcess) -> str:
    assert result.returncode == 2, result.stderr
    assert "Traceback" not in result.stderr and result.stdout == "", result.stderr
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), result.stderr
    return lines[0]


@pytest.mark.parametrize(
    ("head", "kind"),
    [
        (b'<?xml version="1.0"?>\n<scene version="3.0.0">', "mitsuba"),
        (b'\xef\xbb\xbf  <scene version="3.0.0">', "mitsuba"),
        (b"# pbrt\n\nLookAt 0 0 5  0 0 0  0 1 0\n", "pbrt"),
        (b"WorldBegin\n", "pbrt"),
        (b'{"asset": {"version": "2.0"}}', "gltf"),
        (b"glTF\x02\x00\x00\x00", "gltf"),
        (b"BLENDER-v405", "blender"),
        (b"[camera]\norigin = [0, 0, 5]\n", "toml"),
        (b"# a scene\nCamera = 3\n", "toml"),  # a TOML key spelt like a pbrt directive
        (b"Film.width = 3\n", "toml"),
    ],
)
def test_a_file_is_known_by_its_first_bytes(head, kind):
    assert sniff_format(head) == kind


def test_the_suffix_comes_first_and_the_bytes_decide_without_one(tmp_path):
    xml = (scenes_dir() / "veach_mis.xml").read_bytes()
    for name, content, kind in [
        ("a.xml", b"", "mitsuba"),
        ("a.pbrt", b"", "pbrt"),
        ("a.pbrt.gz", b"", "pbrt"),
        ("a.GLB", b"", "gltf"),
        ("a.blend", b"", "blender"),
        ("a.toml", xml, "toml"),  # the suffix says TOML: the loader reports the file as TOML
        ("scene.txt", xml, "mitsuba"),
        ("scene", QUAD_PBRT.encode(), "pbrt"),
    ]:
        (tmp_path / name).write_bytes(content)
        assert scene_format(tmp_path / name) == kind, name


def test_a_pbrt_file_without_its_suffix_loads_as_pbrt(tmp_path):
    (tmp_path / "quad").write_text(QUAD_PBRT)
    scene = load_any_scene(tmp_path / "quad")
    # pbrt's Film and Sampler, as the file gives them
    assert (scene.width, scene.height, scene.spp) == (32, 16, 4)
    assert len(scene.shapes) == 1 and len(scene.lights) == 1 and scene.source == tmp_path / "quad"


def test_a_toml_named_file_of_another_format_says_which_it_is(tmp_path):
    shutil.copy(scenes_dir() / "veach_mis.xml", tmp_path / "veach.toml")
    (tmp_path / "quad.toml").write_text(QUAD_PBRT)
    for name, says in (("veach.toml", "a Mitsuba 3 XML scene: name it veach.xml"), ("quad.toml", "quad.pbrt")):
        with pytest.raises(SpectraceError) as failure:
            load_any_scene(tmp_path / name)
        assert str(failure.value).startswith(f"{tmp_path / name}: TOML syntax error") and says in str(failure.value)


def test_an_imported_scenes_warnings_are_reported(tmp_path):
    (tmp_path / "plane.xml").write_text(
        '<scene version="3.0.0">\n'
        '  <sensor type="perspective"><float name="fov" value="40"/>\n'
        '    <film type="hdrfilm"><integer name="width" value="16"/><integer name="height" value="8"/></film>\n'
        "  </sensor>\n"
        '  <shape type="rectangle"><bsdf type="diffuse"><float name="bogus" value="1"/></bsdf></shape>\n'
        '  <emitter type="constant"/>\n'
        "</scene>\n"
    )
    lines: list[str] = []
    scene = load_any_scene(tmp_path / "plane.xml", report=lines.append)
    assert (scene.width, scene.height) == (16, 8)
    assert [line for line in lines if line.startswith("warning: ")] == [
        f"warning: {tmp_path / 'plane.xml'}:5: bsdf 'diffuse': property 'bogus' is not imported (spectrace does not "
        "know it)"
    ]


def test_set_on_an_imported_scene_names_the_imported_file_not_a_temporary_one(tmp_path):
    (tmp_path / "quad.pbrt").write_text(QUAD_PBRT)
    scene = load_any_scene(tmp_path / "quad.pbrt", {"film.width": 8})
    assert (scene.width, scene.height) == (8, 16)
    with pytest.raises(SpectraceError) as failure:
        load_any_scene(tmp_path / "quad.pbrt", {"film.widht": 8})
    assert str(failure.value).startswith(f"{tmp_path / 'quad.pbrt'}: film.widht: unknown key")
    assert "spectrace-pbrt-" not in str(failure.value)


def test_render_takes_a_mitsuba_file_by_its_bytes_and_a_pbrt_file_by_its_suffix(tmp_path, monkeypatch):
    from PIL import Image

    shutil.copy(scenes_dir() / "veach_mis.xml", tmp_path / "veach.txt")
    (tmp_path / "quad.pbrt").write_text(QUAD_PBRT)
    monkeypatch.chdir(tmp_path)
    for scene, size in (("veach.txt", (24, 16)), ("quad.pbrt", (24, 12))):
        result = run_here("render", scene, "-o", "out.png", "--width", "24", "--spp", "1", "-q")
        assert result.returncode == 0 and "TOML" not in result.stderr, result.stderr
        with Image.open(tmp_path / "out.png") as image:
            assert image.size == size  # the width asked for, the height after the scene's aspect


@pytest.mark.slow
@pytest.mark.subprocess
def test_bare_scene_names_work_in_spectra_and_import_mitsuba(tmp_path):
    listed = _spectrace("spectra", "list", "--scene", "cornell_box", "--json", cwd=tmp_path)
    assert listed.returncode == 0, listed.stderr
    assert "materials.red.reflectance" in json.loads(listed.stdout)["scene"]
    imported = _spectrace("import-mitsuba", "veach_mis", "-o", "veach.toml", cwd=tmp_path)
    assert imported.returncode == 0, imported.stderr
    assert (tmp_path / "veach.toml").is_file()
    line = _one_error_line(_spectrace("spectra", "list", "--scene", "cornel_box", cwd=tmp_path))
    assert line.startswith("error: cornel_box: no such scene file") and "cornell_box" in line


def test_a_sweep_names_a_bundled_scene_by_its_name(tmp_path):
    from spectrace.cli.sweep import sweep_items

    spec = tmp_path / "sweep.toml"
    spec.write_text('[sweep]\nkind = "render"\nscene = "cornell_box"\n\n[grid]\n"film.width" = [4, 6]\n')
    items = sweep_items(spec, None)
    assert [item.params["film.width"] for item in items] == [4, 6]
    assert [item.arguments["scene"].width for item in items] == [4, 6]
    spec.write_text('[sweep]\nkind = "render"\nscene = "cornel_box"\n\n[grid]\n"film.width" = [4]\n')
    with pytest.raises(SpectraceError) as failure:
        sweep_items(spec, None)
    assert str(failure.value).startswith(f"{spec}: sweep.scene: no such scene file")


@pytest.mark.subprocess
def test_version_is_the_installed_distributions():
    result = _spectrace("--version")
    assert result.returncode == 0 and result.stderr == ""
    assert result.stdout.strip() == f"spectrace {importlib.metadata.version('spectrace')}"


@pytest.mark.parametrize(
    ("arguments", "line"),
    [
        (("--set", "film.widht=8"), "error: --set film.widht: unknown key 'widht' (did you mean 'width'?)"),
        (("--set", "film.width=0"), "error: --set film.width: must be > 0, got 0"),
        (("--set", "film.width=wide"), "error: --set film.width: expected a whole number, got 'wide'"),
        (("--set", "nokey"), "error: --set: expected KEY.PATH=VALUE (such as film.width=64), got 'nokey'"),
        (("--set", "cameras.fov=3"), "error: --set cameras.fov: the scene has no cameras"),
        (("--integrator", "pathy"), "error: --integrator: integrator must be one of path, direct, light, bdpt, sppm"),
        (("--spp", "0"), "error: --spp: must be ≥ 1, got '0'"),
    ],
)
def test_a_bad_setting_is_one_line_naming_it(tmp_path, monkeypatch, arguments, line):
    """The messages, through the entry point in this process (test_set_and_quiet runs the command as a process)."""
    monkeypatch.chdir(tmp_path)
    result = run_here("render", "cornell_box", "-o", "x.png", *arguments)
    assert _one_error_line(result).startswith(line)
    assert not (tmp_path / "x.png").exists()


@pytest.mark.subprocess
@pytest.mark.slow
def test_set_and_quiet(tmp_path):
    """--set replaces the scene's values as the file would (a TOML array, a number); -q prints nothing."""
    from PIL import Image

    arguments = ["render", "cornell_box", "-o", "x.png", "--spp", "1", "-q"]
    settings = [
        "--set",
        "film.width=8",
        "--set",
        "film.height=6",
        "--set",
        "materials.red.reflectance={ rgb = [0.6, 0.1, 0.1] }",
    ]
    result = _spectrace(*arguments, *settings, cwd=tmp_path)
    assert result.returncode == 0 and result.stderr == "" and result.stdout == "", result.stderr
    with Image.open(tmp_path / "x.png") as image:
        assert image.size == (8, 6)


def test_set_values_are_toml_values_or_text():
    from spectrace.cli.scene_settings import parse_settings

    parsed = parse_settings(["a.b=1", "a.c=0.5", "a.d=[1, 2]", "a.e=bdpt", 'a.f="x y"', "a.g=true", "a.b=2"], "--set")
    assert parsed == {"a.b": 2, "a.c": 0.5, "a.d": [1, 2], "a.e": "bdpt", "a.f": "x y", "a.g": True}


@pytest.mark.parametrize(
    ("width", "height", "expected"),
    [(160, None, (160, 90)), (None, 90, (160, 90)), (7, None, (7, 4)), (1, None, (1, 1)), (50, 50, (50, 50))],
)
def test_one_film_side_keeps_the_scenes_aspect(width, height, expected):
    from spectrace.engine.job import COMMAND_LINE, RenderJob
    from spectrace.scene import load_scene

    scene = load_scene("cornell_box").with_overrides(width=480, height=270)
    job = RenderJob.make(scene, COMMAND_LINE, width=width, height=height)
    assert (job.scene.width, job.scene.height) == expected


def test_integrator_replaces_the_scenes():
    from spectrace.engine.job import COMMAND_LINE, RenderJob
    from spectrace.scene import load_scene

    scene = load_scene("cornell_box")
    assert scene.integrator != "bdpt"
    assert RenderJob.make(scene, COMMAND_LINE, integrator="bdpt").scene.integrator == "bdpt"


@pytest.mark.slow
@pytest.mark.subprocess
def test_quiet_render_prints_nothing_but_warnings_and_errors(tmp_path):
    arguments = ["render", "cornell_box", "-o", "x.png", "--width", "8", "--spp", "1"]
    talkative = _spectrace(*arguments, cwd=tmp_path)
    assert talkative.returncode == 0 and "device:" in talkative.stderr and "wrote x.png" in talkative.stderr
    quiet = _spectrace(*arguments, "-q", cwd=tmp_path)
    assert quiet.returncode == 0 and quiet.stderr == "" and quiet.stdout == ""


@pytest.mark.subprocess
@pytest.mark.slow
def test_validate_shows_progress_unless_quiet():
    shown = _spectrace("validate", "--case", "distant")
    assert shown.returncode == 0, shown.stderr
    assert "validating" in shown.stderr and "1/1 cases" in shown.stderr
    quiet = _spectrace("validate", "--case", "distant", "-q")
    assert quiet.returncode == 0 and quiet.stderr == ""


@pytest.mark.subprocess
@pytest.mark.slow
def test_metamerism_columns_are_headed_by_the_displays_names():
    result = _spectrace("display", "metamerism", "--from", "LCD-Dell_CCFL", "--to", "LCD-Apple_WLED")
    assert result.returncode == 0, result.stderr
    heading = " ".join(result.stdout.split())
    assert "L*a*b* under LCD-Dell_CCFL" in heading and "L*a*b* under LCD-Apple_WLED" in heading
    assert "half" not in heading.split("ΔE2000")[1]


@pytest.mark.slow
def test_metamerism_standard_errors_fall_with_samples(device):
    """The rendered ΔE's standard error falls as 1/sqrt(samples): 16 times the samples, a quarter of it (within
    the spread of two 16-trial estimates of a standard error, about 25 % each way), and progress counts readings."""
    from spectrace.displays.metamerism import measure_scene_patches
    from spectrace.scene import load_scene
    from spectrace.spectral.spectrum_io import colorchecker_patch_names

    scene = load_scene("display_lcd_vs_led")
    patches = ("white 9.5 (.05 D)", "neutral 5 (.70 D)")
    others = set(colorchecker_patch_names()) - set(patches)
    kept = [
        s
        for s in scene.shapes
        if not (s.name or "").startswith(("left ", "right ")) or s.name.split(" ", 1)[1] not in others
    ]
    scene = scene.with_overrides(shapes=kept)
    calls = []
    few = measure_scene_patches(scene, device, 32, 1, progress=lambda done, total: calls.append((done, total)))
    many = measure_scene_patches(scene, device, 32, 16)
    assert calls == [(1, 4), (2, 4), (3, 4), (4, 4)]
    grey = [np.mean([p.delta_e_standard_error for p in run if p.patch == patches[1]]) for run in (few, many)]
    assert 2.0 < grey[0] / grey[1] < 8.0, grey
