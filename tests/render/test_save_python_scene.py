"""spectrace.save_scene: a scene built in Python written as a scene file (TOML, its meshes as PLY beside it) that the
loader reads back into the same render, bit for bit with the same seed; a scene or a path that cannot be written is
one error line, with what was on disk before left as it was."""

from dataclasses import replace

import numpy as np
import pytest
from tests.render.test_session_python import WOOD, build

import spectrace
from spectrace.errors import SpectraceError
from spectrace.geometry.mesh import TriangleMesh


def _python_scene() -> spectrace.Scene:
    """The live session's Python scene (diffuse, textured, mixed and metal materials, a medium, an area light, a
    point light, an environment, an instanced object) with a mesh made in Python and a second placement."""
    scene = build()
    # A tent of two quads with its own texture coordinates and smooth normals, under a plastic of a textured colour.
    vertices = np.array([[-1, 0, -1], [1, 0, -1], [-1, 0.6, 0], [1, 0.6, 0], [-1, 0, 1], [1, 0, 1]], float) * 0.4
    faces = np.array([[0, 2, 1], [1, 2, 3], [2, 4, 3], [3, 4, 5]])
    uvs = np.array([[0, 0], [1, 0], [0, 0.5], [1, 0.5], [0, 1], [1, 1]], float)
    tent = spectrace.shape(
        TriangleMesh(vertices=vertices, faces=faces, uvs=uvs),
        spectrace.plastic(spectrace.bitmap(WOOD, uv_scale=2.0), roughness=0.3),
        transform=[{"rotate": {"axis": [0, 1, 0], "angle": 30}}, {"translate": [0.1, 0.0, -0.9]}],
        face_normals=False,
        name="tent",
    )
    # Spectra given as samples: a Spectrum object and (wavelengths, values) arrays.
    lights = [
        spectrace.point_light((-1.0, 1.5, 1.0), power_w=15.0, spectrum=(np.array([400, 600, 700]), [1, 2, 0.5])),
        *scene.lights,
    ]
    sampled = spectrace.diffuse(spectrace.spectrum({450: 0.2, 550: 0.7, 650: 0.4}))
    shapes = [replace(s, material=sampled) if s.name == "floor" else s for s in scene.shapes]
    post = scene.instances[0].object
    again = spectrace.instance(post, [{"rotate": {"axis": [0, 1, 0], "angle": 45}}, {"translate": [-1.1, 0.4, 0.6]}])
    return replace(scene, shapes=[*shapes, tent], lights=lights, instances=[*scene.instances, again], spp=2)


def test_a_python_scene_saved_renders_the_same_bits(tmp_path):
    scene = _python_scene()
    path = spectrace.save_scene(scene, tmp_path / "built.toml")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["built.toml", "built_meshes"]
    assert path.read_text().count("values = [[360.0, ") == 2  # the floor's and the light's samples
    loaded = spectrace.load_scene(path)
    assert len(loaded.shapes) == len(scene.shapes) and len(loaded.instances) == 2 and len(loaded.lights) == 3
    expected = spectrace.render(scene, progress=False)
    saved = spectrace.render(loaded, progress=False)
    assert expected.xyz.any()
    np.testing.assert_array_equal(saved.xyz, expected.xyz)


def test_a_scene_that_cannot_be_written_leaves_the_earlier_save(tmp_path):
    path = spectrace.save_scene(build(), tmp_path / "built.toml")
    before = {p.relative_to(tmp_path): p.read_bytes() for p in tmp_path.rglob("*") if p.is_file()}
    scene = build()
    # An image given as an array has no file for the scene to name.
    painted = spectrace.diffuse(spectrace.bitmap(np.full((4, 4, 3), 0.5)))
    shapes = [replace(s, material=painted) if s.name == "panel" else s for s in scene.shapes]
    # A folder where the file would go, and a file where its folder would be: the path cannot be written.
    (tmp_path / "taken.toml").mkdir()
    (tmp_path / "file").write_text("not a folder")
    for target, unsaved, where in [
        (path, replace(scene, shapes=shapes), "materials.panel.reflectance: is an image given as a ndarray"),
        (tmp_path / "taken.toml", build(), "taken.toml"),
        (tmp_path / "file" / "built.toml", build(), "file"),
    ]:
        with pytest.raises(SpectraceError) as caught:
            spectrace.save_scene(unsaved, target)
        assert where in str(caught.value) and "\n" not in str(caught.value)
    after = {p.relative_to(tmp_path): p.read_bytes() for p in tmp_path.rglob("*") if p.is_file()}
    assert after == before | {tmp_path.joinpath("file").relative_to(tmp_path): b"not a folder"}


def test_a_fluorescent_dye_saved_names_its_base_and_renders_the_same_bits(tmp_path):
    """A material that holds another (a fluorescent dye's base) is written as the scene file names it: by the
    base's table name, the dye's spectra and yield beside it."""
    from tests.fluorescence.test_donaldson_matrix import _separable, _write_matrix

    _write_matrix(tmp_path / "dye.csv", _separable())
    scene = build()
    base = spectrace.diffuse(0.4)
    dyes = {
        "floor": spectrace.fluorescent(
            base, excitation={400: 0.8, 480: 0.7, 520: 0.0}, emission={510: 0, 560: 1, 600: 0}
        ),
        "panel": spectrace.fluorescent(base, matrix=tmp_path / "dye.csv", quantum_yield=0.5),
    }
    shapes = [replace(s, material=dyes[s.name]) if s.name in dyes else s for s in scene.shapes]
    dyed = replace(scene, shapes=shapes)
    path = spectrace.save_scene(dyed, tmp_path / "saved" / "dyed.toml")
    loaded = spectrace.load_scene(path)
    bases = {s.name: s.material.base for s in loaded.shapes if s.name in dyes}
    assert bases["floor"] is bases["panel"]  # one base, written once and named by both
    expected = spectrace.render(dyed, progress=False)
    assert expected.xyz.any()
    np.testing.assert_array_equal(spectrace.render(loaded, progress=False).xyz, expected.xyz)
