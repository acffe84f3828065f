"""Mitsuba 3's plastic with a specular_reflectance other than 1 (a tint of the coat's reflection) imported as
spectrace's plastic specular_reflectance: a smooth plastic sphere with a dark base and a coloured coat tint, in a
uniform environment under a small area light, renders like Mitsuba 3 renders the same XML."""

from pathlib import Path

import pytest

from replica_agreement import assert_renders_like_mitsuba
from spectrace.interop.mitsuba import mitsuba_scene_data

TINT = '<rgb name="specular_reflectance" value="0.9, 0.5, 0.1"/>'


def _xml(folder: Path, tint: str = TINT) -> Path:
    path = folder / "plastic.xml"
    # The sphere fills the frame: the environment seen directly is noise-free, where a constant difference of the
    # two renderers' XYZ normalisations (docs/performance.md) would stand out against a zero standard error.
    path.write_text(
        f"""<scene version="3.0.0">
<integrator type="path"><integer name="max_depth" value="4"/></integrator>
<sensor type="perspective"><float name="fov" value="18"/>
  <transform name="to_world"><lookat origin="0, -4, 1" target="0, 0, 0" up="0, 0, 1"/></transform>
  <film type="hdrfilm"><integer name="width" value="32"/><integer name="height" value="32"/>
  <rfilter type="box"/></film></sensor>
<emitter type="constant"><spectrum name="radiance" value="0.5"/></emitter>
<shape type="rectangle">
  <transform name="to_world"><scale value="0.6"/><rotate x="1" angle="60"/><translate x="0.3" y="1" z="2"/></transform>
  <emitter type="area"><spectrum name="radiance" value="6"/></emitter></shape>
<shape type="sphere"><float name="radius" value="1"/>
  <bsdf type="plastic"><rgb name="diffuse_reflectance" value="0.1, 0.1, 0.1"/>{tint}</bsdf></shape>
</scene>
"""
    )
    return path


def test_specular_reflectance_is_mapped_and_one_is_left_out(tmp_path):
    data, _ = mitsuba_scene_data(_xml(tmp_path))
    (material,) = [m for m in data["materials"].values() if m["type"] == "plastic"]
    assert material["specular_reflectance"] == {"rgb": [0.9, 0.5, 0.1]}
    data, _ = mitsuba_scene_data(_xml(tmp_path, '<float name="specular_reflectance" value="1"/>'))
    (material,) = [m for m in data["materials"].values() if m["type"] == "plastic"]
    assert "specular_reflectance" not in material


@pytest.mark.peer
def test_tinted_plastic_renders_like_mitsuba(tmp_path, device, mitsuba_scalar_spectral):
    """Both renderers, spectral, REPLICAS independent images each; 8 x 8-pixel block means and the image mean agree
    within 5 standard errors (tests/replica_agreement.py)."""
    mi = mitsuba_scalar_spectral
    replicas, replica_spp, block = 16, 8, 8
    path = _xml(tmp_path)
    assert_renders_like_mitsuba(mi, path, device, replicas, replica_spp, block)
