"""A Mitsuba scene without a <sensor>. Mitsuba 3 makes no default camera (its scene stopped making one before
3.0.0): it loads such a file with no sensor and refuses to render it. The import refuses it too, in one line that
says so, and writes nothing."""

import pytest

from cli_runner import run_in_process

# Shapes at known places, a light and an integrator: all a scene needs but the camera (as in an <include> fragment).
SCENE = """<scene version="3.0.0">
  <integrator type="path"/>
  <shape type="sphere"><point name="center" x="1" y="2" z="3"/><float name="radius" value="0.5"/></shape>
  <shape type="rectangle"><transform name="to_world"><scale value="2"/><translate x="-1" z="-4"/></transform></shape>
  <emitter type="constant"/>
</scene>
"""


@pytest.mark.peer
def test_mitsuba_loads_it_without_a_camera_and_renders_nothing(tmp_path, mitsuba_scalar_spectral):
    """The behaviour the import follows: no default sensor is made, and rendering is refused."""
    mi = mitsuba_scalar_spectral
    path = tmp_path / "fragment.xml"
    path.write_text(SCENE)
    scene = mi.load_file(str(path))
    assert len(scene.sensors()) == 0
    assert scene.bbox().valid()  # the shapes are there: a default camera would have had a scene to frame
    with pytest.raises(Exception, match="No sensor specified"):
        mi.render(scene, spp=1)


def test_the_import_refuses_it_in_one_line_and_keeps_the_output(tmp_path, monkeypatch, capsys):
    path = tmp_path / "fragment.xml"
    path.write_text(SCENE)
    out = tmp_path / "scene.toml"
    out.write_text("# the previous import\n")
    status, stderr = run_in_process(monkeypatch, capsys, ["import-mitsuba", str(path), "-o", str(out)])
    assert status == 2, stderr
    assert "Traceback" not in stderr and stderr.count("\n") == 1, stderr
    assert stderr.startswith(f"error: {path}: the scene has no <sensor>"), stderr
    assert "Mitsuba 3 loads such a file but renders nothing from it either" in stderr, stderr
    assert out.read_text() == "# the previous import\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["fragment.xml", "scene.toml"]
