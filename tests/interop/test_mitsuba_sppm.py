"""Mitsuba 0.6's photon mappers (`sppm`, `photonmapper`; Mitsuba 3 has none) imported as spectrace's stochastic
progressive photon mapping (integrator 'sppm'), which converges to the same image; their photon counts and radii are
spectrace's own choice, which the import notes."""

import pytest

from spectrace.interop.mitsuba_xml import mitsuba_scene_data


def _xml(tmp_path, integrator: str) -> str:
    path = tmp_path / "scene.xml"
    path.write_text(
        f"""<scene version="3.0.0">
{integrator}
<sensor type="perspective"><float name="fov" value="60"/>
  <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/>
  <rfilter type="box"/></film></sensor>
<shape type="rectangle"><bsdf type="diffuse"/></shape>
<emitter type="point"><point name="position" x="0" y="0" z="1"/><rgb name="intensity" value="1, 1, 1"/></emitter>
</scene>
"""
    )
    return path


@pytest.mark.parametrize("kind", ["sppm", "photonmapper"])
def test_photon_mappers_import_as_sppm(tmp_path, kind):
    data, notes = mitsuba_scene_data(
        _xml(tmp_path, f'<integrator type="{kind}"><integer name="max_depth" value="5"/></integrator>')
    )
    assert not notes, notes
    assert data["integrator"]["type"] == "sppm"
    assert data["integrator"]["max_depth"] == 5


def test_their_photon_settings_are_noted(tmp_path):
    xml = (
        '<integrator type="sppm"><float name="initialRadius" value="0.01"/>'
        '<integer name="photonCount" value="9"/></integrator>'
    )
    data, notes = mitsuba_scene_data(_xml(tmp_path, xml))
    assert data["integrator"]["type"] == "sppm"
    assert any("photon counts and radii" in note for note in notes), notes
