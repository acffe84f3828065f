"""pbrt-v4 scenes whose asset files are missing: refused in one line naming the file by default; with
missing_assets="placeholder" (the survey's option) each missing file is stood in for and reported. Also what the
survey of pbrt-v4's scene collection found in the parser: parameters after an Include continue the included file's
last directive, `Material ""` is the former name of `interface`, and a subsurface reflectance given as a constant
texture is that constant."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from spectrace.errors import SpectraceError
from spectrace.interop.pbrt import load_pbrt_scene, pbrt_scene_data
from spectrace.interop.pbrt.placeholders import GREY

HEADER = """LookAt 0 0 5  0 0 0  0 1 0
Camera "perspective" "float fov" 30
Film "rgb" "integer xresolution" 8 "integer yresolution" 6
WorldBegin
LightSource "distant" "point3 from" [0 0 1] "point3 to" [0 0 0]
"""
PLANE = 'Shape "trianglemesh" "point3 P" [-9 -9 0  9 -9 0  9 9 0  -9 9 0] "integer indices" [0 1 2 0 2 3]\n'

# One scene line per kind of asset file, the file it names, and the warning's stand-in.
ASSETS = {
    "mesh": ('Shape "plymesh" "string filename" "geometry/mesh.ply"\n', "geometry/mesh.ply", "one-triangle"),
    "image": (
        'Texture "t" "spectrum" "imagemap" "string filename" "textures/wood.png"\n'
        'Material "diffuse" "texture reflectance" "t"\n' + PLANE,
        "textures/wood.png",
        "the constant 0.5",
    ),
    "envmap": ('LightSource "infinite" "string filename" "textures/sky.exr"\n', "textures/sky.exr", "grey map"),
    "bsdf": (
        'Material "measured" "string filename" "bsdfs/x.bsdf"\n' + PLANE,
        "bsdfs/x.bsdf",
        "diffuse material of reflectance 0.5",
    ),
    "spectrum": (
        'Material "conductor" "spectrum eta" "spds/Au.eta.spd" "spectrum k" [300 3 800 3]\n' + PLANE,
        "spds/Au.eta.spd",
        "the constant 1",
    ),
    "nanovdb": (
        'MakeNamedMedium "smoke" "string type" "nanovdb" "string filename" "smoke.nvdb"\n'
        'AttributeBegin\nMediumInterface "smoke" ""\nMaterial "interface"\nShape "sphere"\nAttributeEnd\n' + PLANE,
        "smoke.nvdb",
        "the homogeneous medium",
    ),
    "goniometric": (
        'LightSource "goniometric" "string filename" "profile.exr"\n' + PLANE,
        "profile.exr",
        "isotropic",
    ),
    "include": ('Include "geometry/more.pbrt"\n' + PLANE, "geometry/more.pbrt", "skipped"),
}


def _write(folder: Path, body: str, header: str = HEADER) -> Path:
    path = folder / "scene.pbrt"
    path.write_text(header + body)
    return path


@pytest.mark.parametrize("kind", sorted(ASSETS))
def test_by_default_a_missing_asset_is_one_error_naming_it(tmp_path, kind):
    body, missing, _ = ASSETS[kind]
    with pytest.raises(SpectraceError) as failure:
        load_pbrt_scene(_write(tmp_path, body))
    assert Path(missing).name in str(failure.value) and "\n" not in str(failure.value)


@pytest.mark.parametrize("kind", sorted(ASSETS))
def test_with_placeholders_each_missing_asset_is_stood_in_for_and_reported(tmp_path, kind):
    body, missing, stand_in = ASSETS[kind]
    path = _write(tmp_path, body)
    _, importer = pbrt_scene_data(path, tmp_path / "out.toml", missing_assets="placeholder")
    placeholders = [text for text in importer.warnings if text.startswith("placeholder: ")]
    assert len(placeholders) == 1, importer.warnings
    assert f"'{missing}' is missing" in placeholders[0] and stand_in in placeholders[0]
    assert f"{path}:" in placeholders[0]  # at the line that names it
    load_pbrt_scene(path, missing_assets="placeholder")  # and the scene loads


def test_placeholders_are_what_they_say(tmp_path):
    body = 'Material "dielectric"\n' + "".join(ASSETS[kind][0] for kind in ("mesh", "image", "bsdf"))
    path = _write(tmp_path, body)
    data, importer = pbrt_scene_data(path, tmp_path / "out.toml", missing_assets="placeholder")
    (mesh,) = [mesh for name, mesh in importer.meshes.items() if name.startswith("plymesh")]
    assert len(mesh.faces) == 1
    assert mesh.world_area(np.eye(4)) == pytest.approx(0.5)  # the unit right triangle
    reflectances = [table["reflectance"] for table in data["materials"].values() if "reflectance" in table]
    assert reflectances == [{"value": GREY}, {"value": GREY}]  # the image's constant, the measured's diffuse


def test_a_lens_file_is_stood_in_for_by_the_bundled_lens(tmp_path):
    from spectrace.cameras.realistic import PLACEHOLDER_LENS

    header = HEADER.replace('Camera "perspective" "float fov" 30', 'Camera "realistic" "string lensfile" "wide.dat"')
    path = _write(tmp_path, PLANE, header)
    with pytest.raises(SpectraceError, match="wide.dat"):
        load_pbrt_scene(path)
    data, importer = pbrt_scene_data(path, tmp_path / "out.toml", missing_assets="placeholder")
    assert data["camera"]["lens_file"] == PLACEHOLDER_LENS
    assert any("'wide.dat' is missing" in text for text in importer.warnings)
    load_pbrt_scene(path, missing_assets="placeholder")


def test_an_unknown_policy_is_refused(tmp_path):
    with pytest.raises(SpectraceError, match="refuse, placeholder"):
        pbrt_scene_data(_write(tmp_path, PLANE), missing_assets="guess")


@pytest.mark.subprocess
@pytest.mark.slow
def test_command_line_option_and_its_refusals_are_one_line(tmp_path):
    path = _write(tmp_path, ASSETS["mesh"][0] + PLANE)
    out = tmp_path / "out.toml"
    out.write_text("kept\n")

    def run(*args: str) -> subprocess.CompletedProcess:
        command = [sys.executable, "-m", "spectrace", "import-pbrt", str(path), "-o", str(out), *args]
        return subprocess.run(command, capture_output=True, text=True, env=os.environ.copy(), timeout=300)

    for args, named in ((), "geometry/mesh.ply"), (("--missing-assets", "guess"), "--missing-assets"):
        done = run(*args)
        lines = done.stderr.strip().splitlines()
        assert done.returncode != 0 and len(lines) == 1 and named in lines[0], done.stderr
        assert "Traceback" not in done.stderr
        assert out.read_text() == "kept\n"
    done = run("--missing-assets", "placeholder")
    assert done.returncode == 0, done.stderr
    assert "warning: placeholder:" in done.stderr and "geometry/mesh.ply" in done.stderr
    assert out.read_text() != "kept\n"


# ---------------------------------------------------------------- what the survey found


MEDIUM_FILE = 'MakeNamedMedium "smoke" "string type" "homogeneous"\n'
INSIDE = 'AttributeBegin\nMediumInterface "smoke" ""\nMaterial "interface"\nShape "sphere"\nAttributeEnd\n' + PLANE


def _shapes(data: dict) -> list[dict]:
    """The shapes without their mesh files' names (which differ with the TOML's name and the line)."""
    return [{key: value for key, value in shape.items() if key != "file"} for shape in data["shapes"]]


def _interior(data: dict) -> dict:
    (sphere,) = [shape for shape in data["shapes"] if shape["type"] == "sphere"]
    return sphere["interior"]


def test_parameters_after_an_include_continue_its_last_directive(tmp_path):
    """pbrt-v4 splices an included file into the token stream (pbrt-v4-scenes' smoke plume gives its medium's
    coefficients after the Include of the file that declares it): the same medium as when they are inside."""
    (tmp_path / "medium.pbrt").write_text(MEDIUM_FILE)
    after = _write(tmp_path, 'Include "medium.pbrt" "rgb sigma_a" [1 2 3] "float scale" 4\n' + INSIDE)
    spliced = _interior(pbrt_scene_data(after, tmp_path / "a.toml")[0])
    inline = MEDIUM_FILE.strip() + ' "rgb sigma_a" [1 2 3] "float scale" 4\n'
    together = _interior(pbrt_scene_data(_write(tmp_path, inline + INSIDE), tmp_path / "b.toml")[0])
    assert spliced == together and spliced["scale"] == 4


def test_parameters_after_an_include_of_nothing_are_refused_in_one_line(tmp_path):
    (tmp_path / "empty.pbrt").write_text("# nothing\n")
    with pytest.raises(SpectraceError, match="no directive for them to continue"):
        pbrt_scene_data(_write(tmp_path, 'Include "empty.pbrt" "float scale" 4\n' + PLANE))


def test_a_skipped_include_takes_the_parameters_after_it(tmp_path):
    path = _write(tmp_path, 'Include "medium.pbrt" "rgb sigma_a" [1 2 3]\n' + PLANE)
    _, importer = pbrt_scene_data(path, tmp_path / "out.toml", missing_assets="placeholder")
    assert any("'medium.pbrt' is missing: skipped (and the 1 parameters after it)" in w for w in importer.warnings)


@pytest.mark.parametrize("name", ["", "none"])
def test_material_none_and_empty_are_interface(tmp_path, name):
    """pbrt-v4 makes no material for `Material ""` or `"none"` (deprecated names of interface): the shape is a
    medium's boundary only, as with "interface"."""
    body = 'MakeNamedMedium "smoke" "string type" "homogeneous"\nAttributeBegin\nMediumInterface "smoke" ""\n'
    body += f'Material "{name}"\nShape "sphere"\nAttributeEnd\n' + PLANE
    data, importer = pbrt_scene_data(_write(tmp_path, body), tmp_path / "a.toml")
    reference, _ = pbrt_scene_data(_write(tmp_path, body.replace(f'"{name}"', '"interface"')), tmp_path / "b.toml")
    assert _shapes(data) == _shapes(reference)
    assert any('former name of "interface"' in note for note in importer.notes)


@pytest.mark.slow
def test_subsurface_reflectance_from_a_constant_texture_is_that_constant(tmp_path):
    material = 'Material "subsurface" "float eta" 1.33 "rgb mfp" [0.5 0.4 0.3] '
    textured = 'Texture "albedo" "spectrum" "constant" "rgb value" [0.6 0.5 0.4]\n'
    textured += material + '"texture reflectance" "albedo"\n' + PLANE
    direct = material + '"rgb reflectance" [0.6 0.5 0.4]\n' + PLANE
    from_texture, _ = pbrt_scene_data(_write(tmp_path, textured), tmp_path / "a.toml")
    from_rgb, _ = pbrt_scene_data(_write(tmp_path, direct), tmp_path / "b.toml")
    assert _shapes(from_texture) == _shapes(from_rgb)
    assert from_texture["materials"] == from_rgb["materials"]
