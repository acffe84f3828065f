"""Mitsuba 3's linearcurve and bsplinecurve: their curve files (x y z radius per line, a blank line between curves)
imported as spectrace's curve shape, to_world moving the points and not the radii, and rendered as Mitsuba 3 renders
the same XML: a bent linear curve of varying radius (joints, end caps) and a B-spline curve, both diffuse, under a
uniform sky and a point light; a B-spline curve of Mitsuba's `hair` under a sky and a distant light."""

import numpy as np
import pytest

from replica_agreement import assert_renders_like_mitsuba, assert_replicas_agree, spectrace_replicas
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


HAIR = """<bsdf type="hair" id="fibre"><spectrum name="sigma_a" value="400:1.2, 550:0.6, 700:0.2"/>
    <float name="longitudinal_roughness" value="0.25"/><float name="azimuthal_roughness" value="0.4"/></bsdf>"""
BLACK = '<bsdf type="diffuse" id="fibre"><rgb name="reflectance" value="0"/></bsdf>'
HAIR_SCENE = """<scene version="3.0.0">
  <integrator type="path"><integer name="max_depth" value="6"/></integrator>
  <sensor type="perspective"><float name="fov" value="40"/>
    <transform name="to_world"><lookat origin="0, -0.6, 4.5" target="0, -0.6, 0" up="0, 1, 0"/></transform>
    <film type="hdrfilm"><integer name="width" value="SIZE"/><integer name="height" value="SIZE"/>
      <rfilter type="box"/></film></sensor>
  FIBRE
  <shape type="bsplinecurve"><string name="filename" value="bspline.txt"/><ref id="fibre"/></shape>
  <emitter type="constant"><rgb name="radiance" value="0.4"/></emitter>
  <emitter type="directional"><vector name="direction" x="-0.3" y="-1" z="-0.6"/>
    <rgb name="irradiance" value="2"/></emitter>
</scene>""".replace("SIZE", str(SIZE))


@pytest.mark.peer
@pytest.mark.slow
def test_hair_on_bspline_curves_renders_as_in_mitsuba(tmp_path, device, mitsuba_scalar_spectral):
    """Mitsuba 3's `hair` BSDF on its bsplinecurve: h across the fibre, the fibre's direction and light that
    crosses the fibre (TT, TRT) as Mitsuba has them; 8 images from each renderer, 4 x 4-pixel blocks and the
    fibre's pixels (those the same curve in black hides) within 5 standard errors. σa as a spectrum: Mitsuba's
    spectral variants turn melanin's RGB absorption into a spectrum with its components cut at 1
    (docs/mitsuba.md), which spectrace does not."""
    mi = mitsuba_scalar_spectral
    (tmp_path / "bspline.txt").write_text(BSPLINE)
    black = tmp_path / "black.xml"
    black.write_text(HAIR_SCENE.replace("FIBRE", BLACK))
    fibre = np.array(mi.render(mi.load_file(str(black)), spp=16, seed=0))[..., :3].mean(axis=-1) < 0.05
    assert np.count_nonzero(fibre) > 25
    path = tmp_path / "hair.xml"
    path.write_text(HAIR_SCENE.replace("FIBRE", HAIR))
    by_mitsuba = assert_renders_like_mitsuba(mi, path, device, 8, 64, 4, region=fibre)
    assert by_mitsuba[:, fibre].mean() > 0.05  # the fibre is lit
