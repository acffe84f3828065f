"""`spectrace import-gltf` and `spectrace render MODEL.glb` as a user runs them: the TOML and its folder written,
one line and a non-zero exit for a bad file or option (nothing earlier lost), and a glTF file rendered directly."""

from __future__ import annotations

import math

import numpy as np
import pytest
from PIL import Image
from tests.cli_runner import run_in_process, run_spectrace
from tests.interop.gltf_builder import Gltf


def _model(tmp_path, with_mesh: bool = True):
    gltf = Gltf()
    if with_mesh:
        gltf.node(mesh=gltf.quad())
    gltf.node(
        extensions={"KHR_lights_punctual": {"light": gltf.light(type="point", intensity=50.0)}}, translation=[0, 0, 2]
    )
    camera = gltf.camera(type="perspective", perspective={"yfov": 0.9, "aspectRatio": 2.0})
    gltf.node(camera=camera, translation=[0, 0, 4], name="front")
    return gltf.write(tmp_path / "model.glb")


def _one_line_error(result) -> str:
    assert result.returncode != 0
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in result.stderr, result.stderr
    return lines[0]


@pytest.mark.subprocess
@pytest.mark.slow
def test_import_writes_the_toml_and_its_assets(tmp_path):
    model = _model(tmp_path)
    out = tmp_path / "out" / "scene.toml"
    result = run_spectrace("import-gltf", str(model), "-o", str(out), "--materials", "diffuse")
    assert result.returncode == 0, result.stderr
    assert out.is_file() and (out.parent / "scene_assets" / "mesh0.ply").is_file()
    text = out.read_text()
    assert 'file = "scene_assets/mesh0.ply"' in text and 'type = "point"' in text


@pytest.mark.slow
@pytest.mark.subprocess
def test_bad_input_and_options_are_one_line_and_keep_the_earlier_import(tmp_path):
    model = _model(tmp_path)
    out = tmp_path / "scene.toml"
    assert run_spectrace("import-gltf", str(model), "-o", str(out), "--materials", "diffuse").returncode == 0
    before = out.read_bytes()
    broken = tmp_path / "broken.gltf"
    broken.write_text('{"asset": {"version": "2.0"}, "nodes": [{"mesh": 3}]}')
    line = _one_line_error(run_spectrace("import-gltf", str(broken), "-o", str(out)))
    assert f"{broken}: /nodes/0/mesh" in line and "meshes[3]" in line
    line = _one_line_error(run_spectrace("import-gltf", str(model), "-o", str(out), "--materials", "shiny"))
    assert "--materials" in line
    line = _one_line_error(run_spectrace("import-gltf", str(model), "-o", str(out), "--camera", "side"))
    assert "no camera 'side'" in line and "/cameras" in line
    assert out.read_bytes() == before


@pytest.mark.subprocess
@pytest.mark.slow
def test_render_a_glb_directly(tmp_path):
    """The file's camera (aspect 2) and light; no meshes, so no material: the dispatch from `render`, whatever
    materials this build has. The image is black: nothing reflects the light."""
    model = _model(tmp_path, with_mesh=False)
    image = tmp_path / "image.png"
    result = run_spectrace("render", str(model), "-o", str(image), "--spp", "1", "--width", "8", "--height", "4")
    assert result.returncode == 0, result.stderr
    assert np.asarray(Image.open(image)).shape[:2] == (4, 8)


def test_render_of_the_glb_equals_the_render_of_its_import(tmp_path, monkeypatch, capsys):
    """Rendering MODEL.glb is rendering its imported TOML: the same bits (metallic-roughness as principled). In this
    process: the other tests run the commands as real processes; this one is about the images."""
    from spectrace.materials import MATERIALS

    if "principled" not in MATERIALS:
        pytest.skip("this build has no principled material, which glTF's metallic-roughness imports as")
    model = _model(tmp_path)
    out = tmp_path / "scene.toml"
    assert run_in_process(monkeypatch, capsys, ["import-gltf", str(model), "-o", str(out)])[0] == 0
    size = ["--spp", "2", "--width", "8", "--height", "4"]
    direct, imported = tmp_path / "direct.exr", tmp_path / "imported.exr"
    for scene, image in ((model, direct), (out, imported)):
        status, stderr = run_in_process(monkeypatch, capsys, ["render", str(scene), "-o", str(image), *size])
        assert status == 0, stderr
    from spectrace.io.exr import read_exr

    (a, _), (b, _) = read_exr(direct), read_exr(imported)
    assert a.keys() == b.keys() and math.isfinite(float(a["Y"].sum())) and a["Y"].max() > 0
    for name in a:
        np.testing.assert_array_equal(a[name], b[name], err_msg=name)


@pytest.mark.subprocess
@pytest.mark.slow
def test_an_output_that_is_the_input_or_a_folder_is_refused(tmp_path):
    model = _model(tmp_path)
    before = model.read_bytes()
    line = _one_line_error(run_spectrace("import-gltf", str(model), "-o", str(model)))
    assert "would destroy the input" in line
    line = _one_line_error(run_spectrace("import-gltf", str(model), "-o", f"{tmp_path}/"))
    assert "names a folder" in line
    assert model.read_bytes() == before
