"""A `bdpt` integrator in a Mitsuba scene (Mitsuba 0.6's bidirectional path tracer; Mitsuba 3 has none) imported as
spectrace's BDPT, with the same max_depth and rr_depth, and BDPT rendering an XML scene as Mitsuba 3's `path` renders
the same scene with its integrator swapped: a floor and a sphere under a rectangular area light the camera sees and
a point light."""

from pathlib import Path

import pytest

from replica_agreement import assert_renders_like_mitsuba
from spectrace.interop.mitsuba import mitsuba_scene_data


def _xml(folder: Path, size: int, integrator: str) -> Path:
    path = folder / f"{integrator}.xml"
    path.write_text(
        f"""<scene version="3.0.0">
<integrator type="{integrator}"><integer name="max_depth" value="4"/><integer name="rr_depth" value="3"/>
</integrator>
<sensor type="perspective"><float name="fov" value="60"/>
  <transform name="to_world"><lookat origin="0, -2.2, 1.4" target="0, 0, 0.3" up="0, 0, 1"/></transform>
  <film type="hdrfilm"><integer name="width" value="{size}"/><integer name="height" value="{size}"/>
  <rfilter type="box"/></film></sensor>
<shape type="rectangle"><transform name="to_world"><scale value="3"/></transform>
  <bsdf type="diffuse"><rgb name="reflectance" value="0.6, 0.5, 0.4"/></bsdf></shape>
<shape type="sphere"><point name="center" x="0.3" y="0.2" z="0.4"/><float name="radius" value="0.4"/>
  <bsdf type="roughplastic"><rgb name="diffuse_reflectance" value="0.2, 0.5, 0.7"/>
  <float name="alpha" value="0.2"/></bsdf></shape>
<shape type="rectangle">
  <transform name="to_world"><scale value="0.3"/><rotate x="1" angle="180"/><translate x="-0.4" y="0.3" z="1.2"/>
  </transform>
  <emitter type="area"><rgb name="radiance" value="6, 5, 4"/></emitter></shape>
<emitter type="point"><point name="position" x="0.8" y="-0.5" z="1.0"/><rgb name="intensity" value="1, 1.5, 2"/>
</emitter>
</scene>
"""
    )
    return path


def test_bdpt_imports_as_bdpt(tmp_path):
    data, notes = mitsuba_scene_data(_xml(tmp_path, 8, "bdpt"))
    assert not notes, notes
    assert data["integrator"]["type"] == "bdpt"
    assert data["integrator"]["max_depth"] == 4


@pytest.mark.peer
@pytest.mark.slow
def test_bdpt_renders_like_mitsuba_path(tmp_path, device, mitsuba_scalar_spectral):
    """8 independent images each; 8 x 8-pixel block means and the image mean agree within 5 standard errors."""
    mi = mitsuba_scalar_spectral
    replicas, replica_spp, size, block = 8, 8, 32, 8
    path, ours = _xml(tmp_path, size, "path"), _xml(tmp_path, size, "bdpt")
    by_mitsuba = assert_renders_like_mitsuba(mi, path, device, replicas, replica_spp, block, ours=ours)
    assert by_mitsuba.mean() > 0.02  # the comparison saw a lit image
