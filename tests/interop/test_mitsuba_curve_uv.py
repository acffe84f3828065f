"""Texture coordinates on curves: Mitsuba 3's linearcurve and bsplinecurve give u around the fibre (in turns, from
a frame built on the segment's axis) and v along all the file's curves, (segment index + position in the segment) /
segment count; pbrt-v4's curves u along each curve and v across it. The Mitsuba importer keeps Mitsuba's
(`uv_convention = "mitsuba"`), scene files and the API pbrt's unless told. Checked against Mitsuba 3 rendering a
checkerboard on two linear curves seen side-on."""

import numpy as np
import pytest

import spectrace
from replica_agreement import assert_renders_like_mitsuba
from spectrace.errors import SpectraceError
from spectrace.interop.mitsuba import mitsuba_scene_data
from spectrace.scene.loader import load_scene

SIZE = 48

# Two curves, 3 + 1 segments: the second's v starts at 3/4, where Mitsuba counts on from the first's.
LINEAR = """-1.5 -0.6 0 0.22
-0.5 -0.35 0.15 0.22
0.5 -0.6 0 0.25
1.5 -0.45 -0.15 0.2

-1.3 0.55 0 0.3
1.3 0.75 0.1 0.3
"""

SCENE = """<scene version="3.0.0">
  <integrator type="path"><integer name="max_depth" value="2"/></integrator>
  <sensor type="perspective"><float name="fov" value="45"/>
    <transform name="to_world"><lookat origin="0, 0, 4.2" target="0, 0, 0" up="0, 1, 0"/></transform>
    <film type="hdrfilm"><integer name="width" value="SIZE"/><integer name="height" value="SIZE"/>
      <rfilter type="box"/></film></sensor>
  <bsdf type="diffuse" id="checks"><texture type="checkerboard" name="reflectance">
      <rgb name="color0" value="0.05"/><rgb name="color1" value="0.9"/>
      <transform name="to_uv"><scale x="SCALE_U" y="SCALE_V"/></transform></texture></bsdf>
  <shape type="KIND"><string name="filename" value="curves.txt"/><ref id="checks"/></shape>
  <emitter type="constant"><rgb name="radiance" value="1"/></emitter>
</scene>""".replace("SIZE", str(SIZE))


def _xml(tmp_path, kind: str, points: str, scale_u: int, scale_v: int):
    (tmp_path / "curves.txt").write_text(points)
    path = tmp_path / f"{kind}.xml"
    path.write_text(SCENE.replace("KIND", kind).replace("SCALE_U", str(scale_u)).replace("SCALE_V", str(scale_v)))
    return path


def test_mitsuba_curves_import_with_mitsuba_texture_coordinates(tmp_path):
    data, _ = mitsuba_scene_data(_xml(tmp_path, "linearcurve", LINEAR, 4, 8))
    (curve,) = [shape for shape in data["shapes"] if shape["type"] == "curve"]
    assert curve["uv_convention"] == "mitsuba"


def _load(tmp_path, text: str):
    path = tmp_path / "scene.toml"
    path.write_text(text)
    return load_scene(path)


def test_uv_convention_is_a_curve_key_and_pbrt_by_default(tmp_path):
    materials = "[camera]\norigin = [0, 0, 5]\ntarget = [0, 0, 0]\nfov = 40\n[film]\nwidth = 8\nheight = 8\n"
    materials += '[materials.grey]\ntype = "diffuse"\nreflectance = { value = 0.5 }\n'
    curve = '[[shapes]]\ntype = "curve"\npoints = [[0, 0, 0, 0.1], [1, 0, 0, 0.1], [2, 1, 0, 0.1]]\nmaterial = "grey"\n'
    default = _load(tmp_path, materials + curve).shapes[0].analytic
    mitsuba = _load(tmp_path, materials + curve + 'uv_convention = "mitsuba"\n').shapes[0].analytic
    assert default.pbrt_uv and not mitsuba.pbrt_uv
    assert np.all(default.device_rows()["pbrt_uv"] == 1) and np.all(mitsuba.device_rows()["pbrt_uv"] == 0)
    # Mitsuba's v at the control points: (segment index + position) / segment count, 0, 1/2, 1.
    assert np.allclose(mitsuba.u0, [0.0, 0.5]) and np.allclose(mitsuba.u1, [0.5, 1.0])
    rectangle = '[[shapes]]\ntype = "rectangle"\nmaterial = "grey"\nuv_convention = "mitsuba"\n'
    with pytest.raises(SpectraceError, match=r"shapes\[0\].*uv_convention"):
        _load(tmp_path, materials + rectangle)
    shape = spectrace.curve([[0, 0, 0, 0.1], [1, 0, 0, 0.1]], spectrace.diffuse(0.5), uv_convention="mitsuba")
    assert not shape.analytic.pbrt_uv
    with pytest.raises(SpectraceError, match="uv_convention"):
        spectrace.curve([[0, 0, 0, 0.1], [1, 0, 0, 0.1]], spectrace.diffuse(0.5), uv_convention="blender")


@pytest.mark.peer
@pytest.mark.slow
def test_checkerboard_on_linear_curves_renders_as_in_mitsuba(tmp_path, device, mitsuba_scalar_spectral):
    """A checkerboard of 8 squares per turn around the fibre and 16 along the two curves together (12 on the
    first's 3 segments, 4 on the second's 1), lit by a uniform sky: 8 images from each renderer, 4 x 4-pixel blocks
    within 5 standard errors. The curves show dark and light squares both (else the test could not see where the
    squares lie)."""
    mi = mitsuba_scalar_spectral
    path = _xml(tmp_path, "linearcurve", LINEAR, 4, 8)
    by_mitsuba = assert_renders_like_mitsuba(mi, path, device, 8, 16, 4)
    grey = by_mitsuba.mean(axis=(0, 3))
    assert np.count_nonzero(grey < 0.15) > 40 and np.count_nonzero((grey > 0.4) & (grey < 0.95)) > 40


def test_a_curve_with_mitsuba_coordinates_is_saved_with_them(tmp_path):
    """The scene file written for a Python scene keeps the convention and Mitsuba's v of each segment (two curves,
    2 + 1 segments: v steps by 1/3 across both)."""
    curves = [[[0, 0, 0, 0.1], [1, 0, 0, 0.1], [2, 1, 0, 0.1]], [[0, 2, 0, 0.1], [1, 2, 0, 0.1]]]
    shape = spectrace.curve(curves, spectrace.diffuse(0.5), uv_convention="mitsuba")
    camera = spectrace.Camera(origin=(0, 0, 5), target=(0, 0, 0))
    spectrace.save_scene(spectrace.Scene(camera=camera, width=8, height=8, shapes=[shape]), tmp_path / "s.toml")
    back = load_scene(tmp_path / "s.toml").shapes[0].analytic
    assert not back.pbrt_uv
    assert np.allclose(back.u0, [0, 1 / 3, 2 / 3]) and np.allclose(back.u1, [1 / 3, 2 / 3, 1])
