"""What the public sample models showed the importer lacked (tests/tooling/gltf_samples.py runs them all): a
binary glTF whose JSON chunk leaves its padding out of the file (older writers), a file of points and lines only,
and material variants, whose default materials a viewer shows."""

from __future__ import annotations

import json
import struct

import numpy as np
import pytest
from tests.interop.gltf_builder import Gltf

from spectrace.errors import SpectraceError
from spectrace.interop.gltf import gltf_scene_data

JSON_CHUNK, BIN_CHUNK = 0x4E4F534A, 0x004E4942


def _glb(document: dict, data: bytes, pad_json: bool) -> bytes:
    text = json.dumps(document).encode()
    if pad_json:
        text += b" " * (-len(text) % 4)
    chunks = struct.pack("<II", len(text), JSON_CHUNK) + text + struct.pack("<II", len(data), BIN_CHUNK) + data
    return struct.pack("<4sII", b"glTF", 2, 12 + len(chunks)) + chunks


@pytest.mark.parametrize("pad_json", [True, False], ids=["padded", "unpadded"])
def test_a_glb_s_binary_chunk_is_found_whether_or_not_its_json_was_padded(tmp_path, pad_json):
    gltf = Gltf()
    gltf.node(mesh=gltf.quad(2.0))
    document = json.loads(json.dumps(gltf.json))
    data = bytes(gltf.data) + b"\0" * (-len(gltf.data) % 4)
    document["buffers"] = [{"byteLength": len(data)}]
    for extra in range(4):  # every length of JSON modulo 4
        document["asset"]["generator"] = "x" * extra
        path = tmp_path / f"model{extra}.glb"
        path.write_bytes(_glb(document, data, pad_json))
        data_out, ctx = gltf_scene_data(path, tmp_path / "out.toml")
        (mesh,) = ctx.meshes.values()
        np.testing.assert_allclose(np.abs(mesh.vertices[:, :2]), 2.0)
        assert len(mesh.faces) == 2


def test_a_file_of_points_and_lines_only_says_so(tmp_path):
    gltf = Gltf()
    points = [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]]
    gltf.node(mesh=gltf.mesh(points, mode=0))
    gltf.node(mesh=gltf.mesh(points, mode=3))
    path = gltf.write(tmp_path / "lines.glb")
    with pytest.raises(SpectraceError, match="primitives are line strips and points, which have no area") as raised:
        gltf_scene_data(path, tmp_path / "out.toml")
    assert raised.value.where == f"{path}: /"


def test_material_variants_keep_the_default_material_with_a_warning(tmp_path):
    gltf = Gltf()
    red = gltf.material(pbrMetallicRoughness={"baseColorFactor": [1.0, 0.0, 0.0, 1.0]})
    blue = gltf.material(pbrMetallicRoughness={"baseColorFactor": [0.0, 0.0, 1.0, 1.0]})
    mesh = gltf.quad(material=red)
    gltf.json["meshes"][mesh]["primitives"][0]["extensions"] = {
        "KHR_materials_variants": {"mappings": [{"material": blue, "variants": [0]}]}
    }
    gltf.json["extensions"] = {"KHR_materials_variants": {"variants": [{"name": "blue"}]}}
    gltf.json["extensionsUsed"] = gltf.json["extensionsRequired"] = ["KHR_materials_variants"]
    gltf.node(mesh=mesh)
    data, ctx = gltf_scene_data(gltf.write(tmp_path / "variants.glb"), tmp_path / "out.toml")
    (shape,) = data["shapes"]
    assert data["materials"][shape["material"]]["base_color"] == {"rgb": [1.0, 0.0, 0.0]}
    assert any("variants are not imported" in warning for warning in ctx.warnings)


def test_the_sample_script_tabulates_each_file_and_each_refusal_s_line(tmp_path, capsys):
    from tests.tooling.gltf_samples import main

    gltf = Gltf()
    gltf.node(mesh=gltf.quad())
    gltf.write(tmp_path / "good.glb")
    (tmp_path / "broken").mkdir()
    (tmp_path / "broken" / "bad.gltf").write_text('{"asset": {"version": "2.0"}, "scene": "hello"}')
    assert main([str(tmp_path), "--no-render"]) == 0
    out = capsys.readouterr().out
    assert "| good.glb | yes | - | 2 | 0 | 0 | 0 |" in out
    assert "| broken/bad.gltf | NO | - |" in out
    assert '- broken/bad.gltf: bad.gltf: /scene: expected an index (an integer >= 0), got "hello"' in out
    assert "2 files: 1 imported, 0 rendered, 0 crashed" in out


def test_an_unlit_material_is_a_diffuse_surface_of_its_base_colour_with_a_warning(tmp_path):
    gltf = Gltf()
    unlit = gltf.material(
        pbrMetallicRoughness={"baseColorFactor": [0.2, 0.4, 0.6, 1.0], "metallicFactor": 1.0},
        extensions={"KHR_materials_unlit": {}},
    )
    gltf.json["extensionsUsed"] = gltf.json["extensionsRequired"] = ["KHR_materials_unlit"]
    gltf.node(mesh=gltf.quad(material=unlit))
    data, ctx = gltf_scene_data(gltf.write(tmp_path / "unlit.glb"), tmp_path / "out.toml")
    (shape,) = data["shapes"]
    material = data["materials"][shape["material"]]
    assert material == {"type": "diffuse", "reflectance": {"rgb": [0.2, 0.4, 0.6]}, "two_sided": False}
    assert [w for w in ctx.warnings if "unlit" in w] == [
        "/materials/0/extensions/KHR_materials_unlit: unlit materials are imported as diffuse surfaces of their "
        "base colour (lit by the scene's light)"
    ]
    with pytest.raises(SpectraceError, match="--strict"):
        gltf_scene_data(tmp_path / "unlit.glb", tmp_path / "out.toml", strict=True)


@pytest.mark.slow
def test_an_unlit_surface_under_the_default_environment_shows_its_base_colour(tmp_path):
    """A convex unlit box facing the camera, lit by the uniform white environment a file without lights gets:
    a Lambertian face of reflectance ρ facing a radiance of 1 over its hemisphere returns ρ."""
    from spectrace.api import render
    from spectrace.interop.gltf import load_gltf_scene

    gltf = Gltf()
    unlit = gltf.material(
        pbrMetallicRoughness={"baseColorFactor": [0.25, 0.5, 0.75, 1.0]}, extensions={"KHR_materials_unlit": {}}
    )
    gltf.json["extensionsUsed"] = ["KHR_materials_unlit"]
    gltf.node(mesh=gltf.quad(1.0, material=unlit))
    camera = gltf.camera(type="perspective", perspective={"yfov": 0.3, "aspectRatio": 1.0, "znear": 0.01})
    gltf.node(camera=camera, translation=[0.0, 0.0, 3.0])
    scene = load_gltf_scene(gltf.write(tmp_path / "unlit.glb")).with_overrides(width=16, height=16, spp=64)
    image = render(scene, progress=False, aovs="variance")
    y = image.to_linear_srgb() @ np.array([0.2126, 0.7152, 0.0722])
    expected = 0.2126 * 0.25 + 0.7152 * 0.5 + 0.0722 * 0.75
    stderr = np.sqrt((image.aovs["variance"] ** 2).sum()) / y.size
    assert abs(y.mean() - expected) < 4 * stderr + 0.01 * expected
