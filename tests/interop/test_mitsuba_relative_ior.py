"""Mitsuba 3's dielectrics whose inside is the rarer medium (int_ior < ext_ior: an air bubble in water) or index
matched (int_ior = ext_ior) imported as they are: spectrace's ior is Mitsuba's relative η = int_ior / ext_ior, below
1 or equal to 1, and the kernel's Fresnel term and Snell refraction hold on either side of the surface (total
internal reflection then happens on the outside). A bubble of η = 1/1.33 must render as a water sphere of η = 1.33
whose normals are flipped (the same interface seen from the other side), and both as Mitsuba 3 renders them."""

import pytest

from replica_agreement import assert_renders_like_mitsuba
from spectrace.interop.mitsuba import load_mitsuba_scene, mitsuba_scene_data

# (bsdf type, int_ior, ext_ior, the sphere's flip_normals, the ior spectrace must import)
CASES = {
    "bubble": ("dielectric", 1.0, 1.33, False, 1.0 / 1.33),
    "water_flipped": ("dielectric", 1.33, 1.0, True, 1.33),
    "matched": ("dielectric", 1.33, 1.33, False, 1.0),
    "thin_bubble": ("thindielectric", 1.0, 1.33, False, 1.0 / 1.33),
}


def _xml(folder, case: str, size: int):
    kind, int_ior, ext_ior, flip, _ = CASES[case]
    path = folder / f"{case}.xml"
    path.write_text(
        f"""<scene version="3.0.0">
<integrator type="path"><integer name="max_depth" value="8"/></integrator>
<sensor type="perspective"><float name="fov" value="35"/>
  <transform name="to_world"><lookat origin="0, 0, 4" target="0, 0, 0" up="0, 1, 0"/></transform>
  <film type="hdrfilm"><integer name="width" value="{size}"/><integer name="height" value="{size}"/>
  <rfilter type="box"/></film></sensor>
<emitter type="constant"><rgb name="radiance" value="0.2, 0.4, 0.8"/></emitter>
<shape type="rectangle"><transform name="to_world"><scale value="0.8"/><rotate x="1" angle="30"/>
  <translate value="0, 0.8, -1.5"/></transform>
  <emitter type="area"><rgb name="radiance" value="6, 5, 4"/></emitter></shape>
<shape type="sphere"><boolean name="flip_normals" value="{str(flip).lower()}"/>
  <bsdf type="{kind}"><float name="int_ior" value="{int_ior}"/><float name="ext_ior" value="{ext_ior}"/></bsdf></shape>
</scene>
"""
    )
    return path


@pytest.mark.parametrize("case", sorted(CASES))
def test_relative_index_is_imported_as_mitsubas_eta(tmp_path, case):
    kind, _, _, _, ior = CASES[case]
    data, notes = mitsuba_scene_data(_xml(tmp_path, case, 8))
    assert not notes, notes
    (material,) = [table for table in data["materials"].values() if table["type"] == kind]
    assert material["ior"] == pytest.approx(ior, rel=1e-5)
    load_mitsuba_scene(_xml(tmp_path, case, 8))  # a valid spectrace scene


@pytest.mark.peer
@pytest.mark.parametrize("case", sorted(CASES))
def test_relative_index_renders_like_mitsuba(tmp_path, device, mitsuba_scalar_spectral, case):
    """Both renderers, spectral, REPLICAS independent images each; 8 x 8-pixel block means and the image mean agree
    within 5 standard errors (tests/replica_agreement.py)."""
    mi = mitsuba_scalar_spectral
    replicas, replica_spp, size, block = 8, 4, 32, 8
    path = _xml(tmp_path, case, size)
    by_mitsuba = assert_renders_like_mitsuba(mi, path, device, replicas, replica_spp, block)
    assert by_mitsuba.mean() > 0.05  # the comparison saw a lit image
