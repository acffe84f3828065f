"""Mitsuba 3's linearcurve and bsplinecurve: their curve files (x y z radius per line, a blank line between curves)
imported as spectrace's curve shape, to_world moving the points and not the radii, and rendered as Mitsuba 3 renders
the same XML: a bent linear curve of varying radius (joints, end caps) and a B-spline curve, both diffuse, under a
uniform sky and a point light."""

import numpy as np
import pytest

from replica_agreement import assert_replicas_agree, spectrace_replicas
from spectrace.engine.renderer import Renderer
from spectrace.errors import SpectraceError
from spectrace.interop.mitsuba import load_mitsuba_scene, mitsuba_scene_data
from spectrace.spectral import xyz_to_linear_srgb

SIZE = 32

LINEAR = """-1.2 -0.6 0 0.12
-0.4 0.1 0.2 0.2
0.3 -0.3 0 0.15
1.1 0.2 -0.2 0.08

-1.0 0.8 0.3 0.1
0.9 0.7 0.0 0.1
"""
BSPLINE = """-1.4 -1.0 0 0.1
-0.8 -0.2 0.4 0.12
-0.2 -1.2 0.0 0.14
0.4 -0.2 0.3 0.1
1.0 -1.1 0.0 0.12
1.5 -0.5 0.2 0.1
"""

SCENE = f"""<scene version="3.0.0">
  <integrator type="path"><integer name="max_depth" value="4"/></integrator>
  <sensor type="perspective"><float name="fov" value="50"/>
    <transform name="to_world"><lookat origin="0, -0.2, 4.5" target="0, -0.2, 0" up="0, 1, 0"/></transform>
    <film type="hdrfilm"><integer name="width" value="{SIZE}"/><integer name="height" value="{SIZE}"/>
      <rfilter type="box"/></film></sensor>
  <bsdf type="twosided" id="orange"><bsdf type="diffuse"><rgb name="reflectance" value="0.8, 0.4, 0.1"/></bsdf></bsdf>
  <bsdf type="twosided" id="blue"><bsdf type="diffuse"><rgb name="reflectance" value="0.2, 0.3, 0.8"/></bsdf></bsdf>
  <shape type="linearcurve"><string name="filename" value="linear.txt"/>
    <transform name="to_world"><scale x="1.2" y="1" z="1"/><rotate z="1" angle="10"/></transform>
    <ref id="orange"/></shape>
  <shape type="bsplinecurve"><string name="filename" value="bspline.txt"/><ref id="blue"/></shape>
  <emitter type="constant"><rgb name="radiance" value="0.4"/></emitter>
  <emitter type="point"><point name="position" x="1" y="2" z="3"/><rgb name="intensity" value="6"/></emitter>
</scene>"""


def _xml(tmp_path):
    (tmp_path / "linear.txt").write_text(LINEAR)
    (tmp_path / "bspline.txt").write_text(BSPLINE)
    path = tmp_path / "curves.xml"
    path.write_text(SCENE)
    return path


def test_curves_import_as_curve_shapes(tmp_path):
    data, _ = mitsuba_scene_data(_xml(tmp_path))
    curves = [shape for shape in data["shapes"] if shape["type"] == "curve"]
    assert [c["basis"] for c in curves] == ["linear", "bspline"]
    scene = load_mitsuba_scene(_xml(tmp_path))
    linear = next(shape.analytic for shape in scene.shapes if shape.analytic.kind == "curve")
    # 3 + 1 segments; the radii as written, the points moved by to_world.
    assert linear.count == 4
    assert np.allclose(
        np.sort(np.concatenate([linear.ra, linear.rb])), np.sort([0.12, 0.2, 0.2, 0.15, 0.15, 0.08, 0.1, 0.1])
    )
    angle = np.radians(10.0)
    rotation = np.array([[np.cos(angle), -np.sin(angle), 0], [np.sin(angle), np.cos(angle), 0], [0, 0, 1]])
    assert np.allclose(linear.a[0], rotation @ ([1.2, 1, 1] * np.array([-1.2, -0.6, 0.0])), atol=1e-6)


def test_a_bad_curve_file_is_one_line_naming_the_line(tmp_path):
    path = _xml(tmp_path)
    (tmp_path / "bspline.txt").write_text("0 0 0 0.1\n1 0 0 0.1\n2 1 0 0.1\n")
    with pytest.raises(SpectraceError, match=r"line 1: a curve needs at least 4 control points"):
        load_mitsuba_scene(path)
    (tmp_path / "bspline.txt").write_text("0 0 0 0.1\n1 0 zero 0.1\n")
    with pytest.raises(SpectraceError, match=r"line 2: expected 4 finite numbers"):
        load_mitsuba_scene(path)


@pytest.mark.peer
@pytest.mark.slow
def test_curves_render_as_in_mitsuba(tmp_path, device, mitsuba_scalar_spectral):
    """8 independent images from each renderer: 4 x 4-pixel block means and the image mean within 5 standard
    errors (tests/replica_agreement.py)."""
    mi = mitsuba_scalar_spectral
    replicas, replica_spp, block = 8, 64, 4
    path = _xml(tmp_path)
    theirs = mi.load_file(str(path))
    by_mitsuba = np.stack([np.array(mi.render(theirs, spp=replica_spp, seed=seed)) for seed in range(replicas)])
    ours = xyz_to_linear_srgb(spectrace_replicas(Renderer(load_mitsuba_scene(path), device), replicas, replica_spp))
    curve_pixels = np.abs(by_mitsuba.mean(axis=(0, 3)) - 0.4).max() > 0.05  # something other than the sky
    assert curve_pixels
    assert_replicas_agree(ours, by_mitsuba, block)
