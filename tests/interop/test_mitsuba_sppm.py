"""Mitsuba 0.6's photon mappers (`sppm`, `photonmapper`; Mitsuba 3 has none) imported as spectrace's stochastic
progressive photon mapping (integrator 'sppm'), which converges to the same image; their photon counts and radii are
spectrace's own choice, which the import notes."""

from pathlib import Path

import pytest

from spectrace.interop.mitsuba import mitsuba_scene_data


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


def test_their_settings_in_a_0x_file_are_noted_not_warned(tmp_path):
    """A version 0.5 file's camelCase names arrive upgraded (directSamples -> direct_samples): still Mitsuba 0.6's
    photon-mapper settings, noted as spectrace's own choice, not reported as unknown properties."""
    new = _xml(
        tmp_path,
        '<integrator type="photonmapper"><integer name="directSamples" value="16"/>'
        '<integer name="glossySamples" value="16"/><integer name="globalPhotons" value="9"/></integrator>',
    )
    path = tmp_path / "old.xml"
    path.write_text(Path(new).read_text().replace('version="3.0.0"', 'version="0.5.0"'))
    assert 'version="0.5.0"' in path.read_text()
    data, notes = mitsuba_scene_data(path)
    assert data["integrator"]["type"] == "sppm"
    assert any("photon counts and radii" in note for note in notes), notes
    assert not [note for note in notes if note.startswith("warning")], notes
