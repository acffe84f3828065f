"""Mitsuba 3's roughconductor without a material (its default "none": η = 0, k = 1, a Fresnel term of 1 at every
angle) imported as a rough conductor of η 0 and k 1: the Fresnel term is exactly 1 (|(c − i)/(c + i)|² = 1 for the
s wave, likewise p), and the sphere renders as Mitsuba 3 renders the same XML."""

import pytest

from replica_agreement import assert_renders_like_mitsuba
from spectrace.interop.mitsuba import load_mitsuba_scene, mitsuba_scene_data


def _xml(folder, size: int):
    path = folder / "rough_none.xml"
    path.write_text(
        f"""<scene version="3.0.0">
<integrator type="path"><integer name="max_depth" value="4"/></integrator>
<sensor type="perspective"><float name="fov" value="40"/>
  <transform name="to_world"><lookat origin="0, 0, 4" target="0, 0, 0" up="0, 1, 0"/></transform>
  <film type="hdrfilm"><integer name="width" value="{size}"/><integer name="height" value="{size}"/>
  <rfilter type="box"/></film></sensor>
<emitter type="constant"><rgb name="radiance" value="0.2, 0.4, 0.8"/></emitter>
<shape type="rectangle"><transform name="to_world"><scale value="0.6"/><translate value="0.6, 0.6, 1.2"/></transform>
  <emitter type="area"><rgb name="radiance" value="6, 5, 4"/></emitter></shape>
<shape type="sphere"><bsdf type="roughconductor"><float name="alpha" value="0.3"/>
  <rgb name="specular_reflectance" value="0.9, 0.7, 0.5"/></bsdf></shape>
</scene>
"""
    )
    return path


def test_rough_material_none_is_a_conductor_of_eta_0_k_1(tmp_path):
    data, notes = mitsuba_scene_data(_xml(tmp_path, 8))
    assert not notes, notes
    (material,) = [table for table in data["materials"].values() if table["type"] == "conductor"]
    assert material["roughness"] == 0.3
    assert (material["eta"], material["k"]) == ({"value": 0.0}, {"value": 1.0})
    load_mitsuba_scene(_xml(tmp_path, 8))  # η = 0 is a valid conductor


@pytest.mark.peer
def test_rough_material_none_renders_like_mitsuba(tmp_path, device, mitsuba_scalar_spectral):
    """Both renderers, spectral, REPLICAS independent images each; 8 x 8-pixel block means and the image mean agree
    within 5 standard errors (tests/replica_agreement.py)."""
    mi = mitsuba_scalar_spectral
    replicas, replica_spp, size, block = 8, 4, 32, 8
    path = _xml(tmp_path, size)
    by_mitsuba = assert_renders_like_mitsuba(mi, path, device, replicas, replica_spp, block)
    assert by_mitsuba.mean() > 0.05  # the comparison saw a lit image
