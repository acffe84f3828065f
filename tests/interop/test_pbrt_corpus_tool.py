"""The pbrt-v4 corpus table (tests/tooling/pbrt_corpus.py) on files written here: a scene whose mesh file is
missing (imports with one asset absent, or is refused naming it without placeholders), a scene with a material
spectrace does not have (refused in one line, grouped by what it names), and a file without WorldBegin (a part for
Include, not a scene: not tabulated)."""

from __future__ import annotations

import json

from tests.tooling.pbrt_corpus import main

HEADER = """LookAt 0 0 5  0 0 0  0 1 0
Camera "perspective" "float fov" 30
Film "rgb" "integer xresolution" 8 "integer yresolution" 6
WorldBegin
LightSource "distant" "point3 from" [0 0 1] "point3 to" [0 0 0]
"""
PLANE = 'Shape "trianglemesh" "point3 P" [-9 -9 0  9 -9 0  9 9 0  -9 9 0] "integer indices" [0 1 2 0 2 3]\n'


def _corpus(tmp_path):
    root = tmp_path / "corpus"
    (root / "nested").mkdir(parents=True)
    (root / "mesh.pbrt").write_text(HEADER + 'Include "part.pbrt"\n')
    (root / "part.pbrt").write_text('Shape "plymesh" "string filename" "geometry/missing.ply"\n' + PLANE)
    (root / "nested" / "velvet.pbrt").write_text(HEADER + 'Material "velvet"\n' + PLANE)
    return root


def test_each_scene_file_is_tabulated_with_its_absent_assets_or_its_refusal(tmp_path, capsys):
    root = _corpus(tmp_path)
    assert main([str(root), "--json", str(tmp_path / "rows.json")]) == 0
    out = capsys.readouterr().out
    data = json.loads((tmp_path / "rows.json").read_text())
    rows = {row["file"]: row for row in data["rows"]}
    assert set(rows) == {"corpus/mesh.pbrt", "corpus/nested/velvet.pbrt"}  # part.pbrt has no WorldBegin
    mesh, velvet = rows["corpus/mesh.pbrt"], rows["corpus/nested/velvet.pbrt"]
    assert mesh["imported"] and mesh["absent"] == ["geometry/missing.ply"] and mesh["reason"] == ""
    assert not velvet["imported"] and velvet["features"] == ["unknown material 'velvet'"]
    assert velvet["reason"].startswith("corpus/nested/velvet.pbrt:6: unknown material 'velvet'")
    # scene files, import, of which with every asset present, refused
    assert "| 2 | 1 | 0 | 1 |" in out
    assert "| corpus/mesh.pbrt | yes | 1 |  |" in out
    assert "| unknown material 'velvet' | 1 |" in out
    # The plugins counted include those of the included part.
    assert {"plugin": "Shape plymesh", "files": 1} in data["plugins"]
    assert {"plugin": "Material velvet", "files": 1} in data["plugins"]
    assert str(tmp_path) not in out  # files are named from the folder above the root named


def test_without_placeholders_a_missing_asset_refuses_the_scene_naming_it(tmp_path, capsys):
    root = _corpus(tmp_path)
    assert main([str(root / "mesh.pbrt"), "--missing-assets", "refuse", "--json", str(tmp_path / "rows.json")]) == 0
    (row,) = json.loads((tmp_path / "rows.json").read_text())["rows"]
    assert not row["imported"] and "geometry/missing.ply" in row["reason"]
    assert "| 1 | 0 | 0 | 1 |" in capsys.readouterr().out
