"""Mitsuba 3's homogeneous medium inside a shape imported as spectrace's interior medium: σs = scale·albedo·σt,
σa = scale·(1 − albedo)·σt, Henyey–Greenstein g, a `null` bsdf as the index-matched boundary; a cube of it in a
uniform environment renders like Mitsuba 3's volpath renders the same XML."""

from pathlib import Path

import numpy as np
import pytest

from replica_agreement import assert_renders_like_mitsuba
from spectrace.errors import SpectraceError
from spectrace.interop.mitsuba import mitsuba_scene_data

MEDIUM = """<medium type="homogeneous" name="interior">
    <float name="sigma_t" value="2"/><float name="albedo" value="0.8"/><float name="scale" value="1.5"/>
    <phase type="hg"><float name="g" value="0.5"/></phase>
  </medium>"""


def _xml(folder: Path, size: int, medium: str = MEDIUM, bsdf: str = '<bsdf type="null"/>') -> Path:
    path = folder / "medium.xml"
    path.write_text(
        f"""<scene version="3.0.0">
<integrator type="volpath"><integer name="max_depth" value="16"/></integrator>
<sensor type="perspective"><float name="fov" value="40"/>
  <transform name="to_world"><lookat origin="0, -4, 1" target="0, 0, 0" up="0, 0, 1"/></transform>
  <film type="hdrfilm"><integer name="width" value="{size}"/><integer name="height" value="{size}"/>
  <rfilter type="box"/></film></sensor>
<emitter type="constant"><spectrum name="radiance" value="1"/></emitter>
<shape type="cube">{bsdf}{medium}</shape>
</scene>
"""
    )
    return path


def test_homogeneous_medium_maps_to_an_index_matched_interior(tmp_path):
    data, _ = mitsuba_scene_data(_xml(tmp_path, 8))
    shape = data["shapes"][0]
    assert "material" not in shape
    interior = shape["interior"]
    assert interior["sigma_s"]["value"] == pytest.approx(2 * 0.8 * 1.5)
    assert interior["sigma_a"]["value"] == pytest.approx(2 * 0.2 * 1.5)
    assert interior["g"] == 0.5
    defaults, _ = mitsuba_scene_data(_xml(tmp_path, 8, '<medium type="homogeneous" name="interior"/>'))
    # Mitsuba's defaults: sigma_t 1, albedo 0.75, isotropic phase.
    assert defaults["shapes"][0]["interior"] == {"sigma_a": {"value": 0.25}, "sigma_s": {"value": 0.75}, "g": 0.0}


def test_medium_declared_at_the_top_and_referenced_is_the_same_interior(tmp_path):
    """Mitsuba's test and documentation scenes declare the medium once, `<medium id>` at the top, and give it to
    shapes by `<ref name="interior">`: the same import as the medium written inside the shape."""
    inline, _ = mitsuba_scene_data(_xml(tmp_path, 8))
    declared = MEDIUM.replace('name="interior"', 'id="m1"')
    path = _xml(tmp_path, 8, '<ref id="m1" name="interior"/>')
    path.write_text(path.read_text().replace("<shape", declared + "\n<shape", 1))
    data, notes = mitsuba_scene_data(path)
    assert data["shapes"][0]["interior"] == inline["shapes"][0]["interior"]
    assert not [note for note in notes if "medium" in note], notes


COLOURED = MEDIUM.replace('<float name="albedo" value="0.8"/>', '<rgb name="albedo" value="0.95, 0.6, 0.3"/>')


RGB_EXTINCTION = COLOURED.replace('<float name="sigma_t" value="2"/>', '<rgb name="sigma_t" value="0.9, 0.5, 0.2"/>')


def test_spectral_extinction_and_exterior_media_are_reported(tmp_path):
    spectral = MEDIUM.replace('<float name="sigma_t" value="2"/>', '<spectrum name="sigma_t" value="400:1, 700:2"/>')
    with pytest.raises(SpectraceError, match="coloured sigma_t"):
        mitsuba_scene_data(_xml(tmp_path, 8, spectral))
    # Mitsuba's spectral variants refuse an rgb coefficient outside [0, 1] (a reflectance uplift): so does spectrace.
    bright = MEDIUM.replace('<float name="sigma_t" value="2"/>', '<rgb name="sigma_t" value="2, 1, 0.5"/>')
    with pytest.raises(SpectraceError, match=r"rgb sigma_t must lie in \[0, 1\]"):
        mitsuba_scene_data(_xml(tmp_path, 8, bright))
    exterior = MEDIUM.replace('name="interior"', 'name="exterior"')
    with pytest.raises(SpectraceError, match="exterior medium"):
        mitsuba_scene_data(_xml(tmp_path, 8, exterior))


@pytest.mark.peer
def test_rgb_extinction_and_albedo_are_mitsubas_coefficients(tmp_path, mitsuba_scalar_spectral):
    """σt(λ) and σs(λ) of an rgb sigma_t and albedo (and a scale) as Mitsuba's homogeneous medium gives them, at
    wavelengths across the range, within 0.5 % (its uplift table is interpolated, spectrace's fit is its own)."""
    mi = mitsuba_scalar_spectral
    interior = mitsuba_scene_data(_xml(tmp_path, 8, RGB_EXTINCTION))[0]["shapes"][0]["interior"]
    table = {key: dict((w, v) for w, v in interior[key]["values"]) for key in ("sigma_a", "sigma_s")}
    theirs = mi.load_string(RGB_EXTINCTION.replace('name="interior"', 'version="3.0.0"'))
    record = mi.MediumInteraction3f()
    for wavelength in (400.0, 450.0, 500.0, 550.0, 600.0, 650.0, 700.0):
        record.wavelengths = [wavelength] * 4
        sigma_s, _, sigma_t = theirs.get_scattering_coefficients(record)
        ours_t = table["sigma_a"][wavelength] + table["sigma_s"][wavelength]
        assert ours_t == pytest.approx(np.array(sigma_t)[0], rel=5e-3), wavelength
        assert table["sigma_s"][wavelength] == pytest.approx(np.array(sigma_s)[0], rel=5e-3), wavelength


@pytest.mark.peer
@pytest.mark.parametrize("medium", [MEDIUM, COLOURED, RGB_EXTINCTION], ids=["grey", "rgb_albedo", "rgb_sigma_t"])
def test_medium_cube_renders_like_mitsuba_volpath(tmp_path, device, mitsuba_scalar_spectral, medium):
    """Both renderers, spectral, REPLICAS independent images each; 8 x 8-pixel block means and the image mean agree
    within 5 standard errors (tests/replica_agreement.py). rgb_albedo: the albedo uplifted as a reflectance;
    rgb_sigma_t: sigma_t too."""
    mi = mitsuba_scalar_spectral
    replicas, replica_spp, size, block = 16, 8, 32, 8
    path = _xml(tmp_path, size, medium)
    by_mitsuba = assert_renders_like_mitsuba(mi, path, device, replicas, replica_spp, block)
    # The medium is seen: the cube's centre is darker than the open environment around it.
    centre = by_mitsuba[:, 12:20, 12:20].mean()
    assert centre < 0.8 * by_mitsuba[:, :4, :4].mean()


# A sphere of fog behind a thin dielectric sheet (Mitsuba's documentation and test scenes enclose media so) over a
# grey floor: lit from outside by a square lamp, with a diffuse cube inside the fog, or by a lamp inside the fog.
# max_depth 6 makes the depth rules matter: volpath counts no pass through the sheet (its null lobe).
FOG_SPHERE = """<scene version="3.0.0">
<integrator type="volpath"><integer name="max_depth" value="6"/></integrator>
<sensor type="perspective"><float name="fov" value="35"/>
  <transform name="to_world"><lookat origin="0, -5, 0.5" target="0, 0, 0" up="0, 0, 1"/></transform>
  <film type="hdrfilm"><integer name="width" value="16"/><integer name="height" value="16"/>
  <rfilter type="box"/></film></sensor>
<medium type="homogeneous" id="fog">
  <float name="sigma_t" value="3"/><float name="albedo" value="0.9"/>
  <phase type="hg"><float name="g" value="0.3"/></phase>
</medium>
<shape type="sphere"><bsdf type="thindielectric"/><ref id="fog" name="interior"/></shape>
<shape type="rectangle"><transform name="to_world"><scale value="3"/><translate value="0, 0, -1.2"/></transform>
  <bsdf type="diffuse"><rgb name="reflectance" value="0.5, 0.5, 0.5"/></bsdf></shape>
{inside}
</scene>
"""
LAMP_OUTSIDE = """<shape type="rectangle"><transform name="to_world"><scale value="0.8"/><rotate x="1" angle="180"/>
  <translate value="0.5, -0.5, 2.5"/></transform><emitter type="area"><rgb name="radiance" value="6, 6, 6"/></emitter>
</shape>"""
CUBE_INSIDE = """<shape type="cube">
  <transform name="to_world"><scale value="0.35"/><rotate z="1" angle="30"/></transform>
  <bsdf type="diffuse"><rgb name="reflectance" value="0.7, 0.3, 0.2"/></bsdf></shape>"""
LAMP_INSIDE = """<shape type="sphere"><float name="radius" value="0.25"/>
  <emitter type="area"><rgb name="radiance" value="8, 8, 8"/></emitter></shape>"""


@pytest.mark.peer
@pytest.mark.parametrize(
    "inside",
    [LAMP_OUTSIDE, LAMP_OUTSIDE + CUBE_INSIDE, LAMP_INSIDE],
    ids=["lamp_outside", "cube_in_fog", "lamp_in_fog"],
)
@pytest.mark.slow
def test_fog_behind_a_thin_sheet_renders_like_mitsuba_volpath(tmp_path, device, mitsuba_scalar_spectral, inside):
    """Shapes without media inside the fog keep rays in it, shadow rays start in the path's medium, and passes
    through the sheet do not count toward max_depth: 16 replicas each, 4 x 4-pixel blocks and the image mean within
    5 standard errors (before: 0.85, 0.88 and 2.5 times Mitsuba's mean, 9 to 12 standard errors off)."""
    mi = mitsuba_scalar_spectral
    replicas, replica_spp, block = 16, 320, 4
    path = tmp_path / "fog.xml"
    path.write_text(FOG_SPHERE.format(inside=inside))
    assert_renders_like_mitsuba(mi, path, device, replicas, replica_spp, block)
