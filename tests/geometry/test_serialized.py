"""Mitsuba's .serialized meshes (spectrace.geometry.serialized): files written here from the format Mitsuba 3's plugin
reference documents, read by spectrace and, as the independent reference, by Mitsuba 3 itself (which can read but
not write the format), and the scene file's `shape_index`."""

import struct
import zlib

import numpy as np
import pytest

from scene_text import camera_film
from spectrace.errors import SpectraceError
from spectrace.geometry.mesh import load_mesh


def _mesh_stream(vertices, faces, normals=None, uvs=None, double=False, version=4, name=b"part") -> bytes:
    flags = (0x0001 if normals is not None else 0) | (0x0002 if uvs is not None else 0)
    flags |= 0x2000 if double else 0x1000
    real = "<f8" if double else "<f4"
    body = struct.pack("<I", flags) + (name + b"\0" if version == 4 else b"")
    body += struct.pack("<QQ", len(vertices), len(faces))
    for rows in (vertices, normals, uvs):
        if rows is not None:
            body += np.asarray(rows, real).tobytes()
    body += np.asarray(faces, "<u4").tobytes()
    return struct.pack("<HH", 0x041C, version) + zlib.compress(body)


def write_serialized(path, meshes, version=4) -> None:
    streams = [_mesh_stream(**mesh, version=version) for mesh in meshes]
    offsets = np.cumsum([0] + [len(s) for s in streams[:-1]])
    table = np.asarray(offsets, "<u8" if version == 4 else "<u4").tobytes() + struct.pack("<I", len(streams))
    path.write_bytes(b"".join(streams) + table)


def _meshes():
    rng = np.random.default_rng(7)
    quad = {"vertices": [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], "faces": [[0, 1, 2], [0, 2, 3]]}
    normals = rng.normal(size=(5, 3))
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    smooth = {
        "vertices": rng.uniform(-2, 2, size=(5, 3)),
        "faces": [[0, 1, 2], [1, 3, 2], [2, 3, 4]],
        "normals": normals,
        "uvs": rng.uniform(0, 1, size=(5, 2)),
    }
    wide = {"vertices": rng.uniform(-1, 1, size=(4, 3)) * 1e3, "faces": [[0, 1, 2], [0, 2, 3]], "double": True}
    return [quad, smooth, wide]


@pytest.mark.parametrize("version", [3, 4])
def test_each_mesh_of_a_file_reads_back(tmp_path, version):
    path = tmp_path / "parts.serialized"
    meshes = _meshes()
    write_serialized(path, meshes, version)
    for index, expected in enumerate(meshes):
        mesh = load_mesh(path, "shapes[0].file", shape_index=index)
        real = np.float64 if expected.get("double") else np.float32
        np.testing.assert_array_equal(mesh.vertices, np.asarray(expected["vertices"], real))
        np.testing.assert_array_equal(mesh.faces, expected["faces"])
        if "normals" in expected:
            np.testing.assert_array_equal(mesh.normals, np.asarray(expected["normals"], np.float32))
            uv = np.asarray(expected["uvs"], np.float32).astype(np.float64)
            np.testing.assert_array_equal(mesh.uvs, np.column_stack([uv[:, 0], 1.0 - uv[:, 1]]))
        else:
            assert mesh.normals is None and mesh.uvs is None


@pytest.mark.peer
def test_mitsuba_reads_the_same_mesh(tmp_path, mitsuba_scalar_spectral):
    mi = mitsuba_scalar_spectral
    path = tmp_path / "parts.serialized"
    write_serialized(path, _meshes())
    ours = load_mesh(path, "file", shape_index=1)
    theirs = mi.load_dict({"type": "serialized", "filename": str(path), "shape_index": 1})
    params = mi.traverse(theirs)
    np.testing.assert_allclose(ours.vertices.ravel(), np.array(params["vertex_positions"]), rtol=0, atol=1e-6)
    np.testing.assert_array_equal(ours.faces.ravel(), np.array(params["faces"]))
    np.testing.assert_allclose(ours.normals.ravel(), np.array(params["vertex_normals"]), atol=1e-6)
    their_uv = np.array(params["vertex_texcoords"]).reshape(-1, 2)
    np.testing.assert_allclose(ours.uvs, np.column_stack([their_uv[:, 0], 1.0 - their_uv[:, 1]]), atol=1e-7)


def test_bad_files_name_the_file_and_key(tmp_path):
    path = tmp_path / "one.serialized"
    write_serialized(path, _meshes()[:1])
    with pytest.raises(SpectraceError, match="shape_index 1 is out of range") as error:
        load_mesh(path, "shapes[0].file", shape_index=1)
    assert error.value.where == "shapes[0].file"
    path.write_bytes(b"\x1c\x04\x04\x00" + b"junk" * 4)
    with pytest.raises(SpectraceError, match="table of meshes is damaged|does not start|damaged"):
        load_mesh(path, "shapes[0].file")
    path.write_bytes(b"ply\nformat ascii 1.0\n")
    with pytest.raises(SpectraceError, match="not a Mitsuba serialized mesh"):
        load_mesh(path, "shapes[0].file")
    data = bytearray()
    write_serialized(path, _meshes()[:1])
    data = bytearray(path.read_bytes())
    data[10:14] = b"\xff\xff\xff\xff"  # inside the zlib stream
    path.write_bytes(bytes(data))
    with pytest.raises(SpectraceError, match="damaged|ends early|missing vertices"):
        load_mesh(path, "shapes[0].file")


def test_scene_file_takes_shape_index(tmp_path):
    from spectrace.scene.loader import load_scene

    write_serialized(tmp_path / "parts.serialized", _meshes())
    text = (
        camera_film(origin="[0, 0, 5]", target="[0, 0, 0]", fov="40", width="8", height="8")
        + """[materials.white]
type = "diffuse"
reflectance = { value = 0.5 }
[[shapes]]
type = "mesh"
file = "parts.serialized"
shape_index = 2
material = "white"
"""
    )
    (tmp_path / "scene.toml").write_text(text)
    scene = load_scene(tmp_path / "scene.toml")
    assert len(scene.shapes[0].mesh.faces) == 2
    assert np.abs(scene.shapes[0].mesh.vertices).max() > 10  # the third mesh, scaled by 1e3
    (tmp_path / "bad.toml").write_text(text.replace("parts.serialized", "parts.obj"))
    with pytest.raises(SpectraceError, match="shape_index"):
        load_scene(tmp_path / "bad.toml")


_XML = """<scene version="3.0.0">
<sensor type="perspective"><float name="fov" value="45"/>
<film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="6"/></film></sensor>
<shape type="serialized" id="part">
  <string name="filename" value="parts.serialized"/>
  <integer name="shape_index" value="1"/>
  <transform name="to_world"><scale value="2"/><rotate y="1" angle="30"/><translate x="1" y="-2" z="0.5"/></transform>
  <bsdf type="diffuse"/>
</shape>
</scene>
"""


def test_mitsuba_import_places_the_mesh_as_mitsuba_does(tmp_path, mitsuba_scalar_spectral):
    from spectrace.interop.mitsuba import load_mitsuba_scene

    mi = mitsuba_scalar_spectral
    write_serialized(tmp_path / "parts.serialized", _meshes())
    (tmp_path / "scene.xml").write_text(_XML)
    scene = load_mitsuba_scene(tmp_path / "scene.xml")
    mesh = scene.shapes[0].mesh
    theirs = mi.load_file(str(tmp_path / "scene.xml")).shapes()[0]
    params = mi.traverse(theirs)
    np.testing.assert_allclose(mesh.vertices.ravel(), np.array(params["vertex_positions"]), atol=1e-5)
    np.testing.assert_array_equal(mesh.faces.ravel(), np.array(params["faces"]))
    np.testing.assert_allclose(mesh.normals.ravel(), np.array(params["vertex_normals"]), atol=1e-5)
