"""The corpus table (tests/tooling/mitsuba_corpus.py) on three files written here: one both renderers take, one
spectrace refuses for a plugin it lacks (Mitsuba's depth integrator, an output that is no light), one Mitsuba itself
refuses (a BSDF of a type it has not); and the comparison it makes of the first."""

from __future__ import annotations

import json
import math

import pytest

pytest.importorskip("mitsuba", reason="the corpus table compares with Mitsuba 3: `pip install spectrace[test]`")

from tests.tooling.mitsuba_corpus import main  # noqa: E402

# A diffuse square of reflectance 0.5 and half-width 0.5 facing the camera under a uniform white sky: it shows 0.5,
# the sky 1. With a box filter the image's mean is the sky less half the share of the film the square covers.
DISTANCE, FOV, HALF, ASPECT = 4.0, 30.0, 0.5, 0.75
SCENE = """<scene version="3.0.0">
  <integrator type="{integrator}"/>
  <sensor type="perspective"><float name="fov" value="30"/>
    <transform name="to_world"><lookat origin="0, 0, 4" target="0, 0, 0" up="0, 1, 0"/></transform>
    <film type="hdrfilm"><integer name="width" value="32"/><integer name="height" value="24"/>
      <rfilter type="box"/></film></sensor>
  <shape type="rectangle"><transform name="to_world"><scale value="0.5"/></transform><bsdf type="{bsdf}"/></shape>
  <emitter type="constant"><rgb name="radiance" value="1"/></emitter>
</scene>"""


def _write(folder, name: str, integrator: str = "path", bsdf: str = "diffuse"):
    (folder / name).write_text(SCENE.format(integrator=integrator, bsdf=bsdf))


@pytest.fixture
def corpus(tmp_path, mitsuba_scalar_spectral):
    root = tmp_path / "corpus"
    (root / "nested").mkdir(parents=True)
    _write(root, "plain.xml")
    _write(root / "nested", "depth.xml", integrator="depth")
    _write(root, "velvet.xml", bsdf="velvet")
    return root


@pytest.mark.slow
def test_each_file_is_tabulated_with_what_each_renderer_makes_of_it(corpus, tmp_path, capsys):
    assert main([str(corpus), "--json", str(tmp_path / "rows.json")]) == 0
    out = capsys.readouterr().out
    rows = {row["file"]: row for row in json.loads((tmp_path / "rows.json").read_text())["rows"]}
    assert set(rows) == {"corpus/plain.xml", "corpus/nested/depth.xml", "corpus/velvet.xml"}
    plain, depth, velvet = rows["corpus/plain.xml"], rows["corpus/nested/depth.xml"], rows["corpus/velvet.xml"]
    assert (plain["mitsuba"], plain["imported"], plain["reason"]) == ("renders", True, "")
    assert (depth["mitsuba"], depth["imported"]) == ("renders", False)
    assert depth["features"] == ["integrator 'depth'"]
    assert depth["reason"].startswith("unsupported Mitsuba 3 plugins: integrator 'depth' (line 2)")
    assert velvet["mitsuba"] == "refuses" and "velvet" in velvet["mitsuba_reason"]
    assert not velvet["imported"] and velvet["features"] == ["bsdf 'velvet'"]
    # files, Mitsuba renders (polarised only), loads without a sensor, refuses, spectrace imports, both take
    assert "| 3 | 2 | 0 | 0 | 1 | 1 | 1 |" in out
    # Grouped by what is lacking: the depth integrator keeps out one file Mitsuba renders, velvet one it refuses.
    assert "| integrator 'depth' | 1 | 1 |" in out
    assert "| bsdf 'velvet' | 1 | 0 |" in out
    assert str(tmp_path) not in out  # files are named from the folder above the root named


@pytest.mark.peer
@pytest.mark.slow
def test_a_file_both_take_is_rendered_by_both_and_their_means_compared(corpus, tmp_path, capsys):
    """At 8 x 6 pixels the square's edges cross pixels, whose samples see it or the sky: the noise the comparison
    measures. Both renderers' means are the closed form's (within 2 %, more than 5 standard errors of either), and
    the table says they agree, with the power of the comparison."""
    half_width = DISTANCE * math.tan(math.radians(FOV / 2))  # of the film's view at the square's distance
    covered = (HALF / half_width) * (HALF / (half_width * ASPECT))
    expected = 1.0 - 0.5 * covered
    assert main([str(corpus / "plain.xml"), "--render", "--size", "8", "--json", str(tmp_path / "rows.json")]) == 0
    (row,) = json.loads((tmp_path / "rows.json").read_text())["rows"]
    assert row["means"] == pytest.approx([expected] * 6, rel=0.02)
    assert row["compared"] == "agrees" and row["z"] <= 5.0
    assert 0 < row["power"] < 0.05
    assert "| plain.xml | renders | yes | agrees |" in capsys.readouterr().out
