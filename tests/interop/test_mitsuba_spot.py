"""Mitsuba 3's spot emitter imported as spectrace's spot with linear_falloff: placed by to_world (along local +z),
with Mitsuba's profile (linear in the angle from beam_width to cutoff_angle), rendered like Mitsuba 3 renders the
same XML over a diffuse floor; and its irradiance on the axis is I/h²."""

from pathlib import Path

import numpy as np
import pytest

from replica_agreement import assert_renders_like_mitsuba
from spectrace.interop.mitsuba import mitsuba_scene_data

# The spot 1 unit above a floor, tilted 20° so both edges of the transition (10° to 35°) land on the floor.
SPOT = """<emitter type="spot">
  <transform name="to_world"><lookat origin="0, 0, 1" target="0.36, 0, 0" up="0, 1, 0"/></transform>
  <float name="cutoff_angle" value="35"/><float name="beam_width" value="10"/>
  <rgb name="intensity" value="3, 2.5, 2"/>
</emitter>"""


def _xml(folder: Path, size: int, spot: str = SPOT) -> Path:
    path = folder / "spot.xml"
    path.write_text(
        f"""<scene version="3.0.0">
<integrator type="path"><integer name="max_depth" value="3"/></integrator>
<sensor type="perspective"><float name="fov" value="70"/>
  <transform name="to_world"><lookat origin="0, 0, 2" target="0, 0, 0" up="0, 1, 0"/></transform>
  <film type="hdrfilm"><integer name="width" value="{size}"/><integer name="height" value="{size}"/>
  <rfilter type="box"/></film></sensor>
{spot}
<shape type="rectangle"><transform name="to_world"><scale value="2"/></transform>
  <bsdf type="diffuse"><rgb name="reflectance" value="0.6, 0.5, 0.4"/></bsdf></shape>
</scene>
"""
    )
    return path


def test_spot_maps_position_axis_and_cone(tmp_path):
    data, notes = mitsuba_scene_data(_xml(tmp_path, 8))
    assert not notes, notes  # every property of the spot understood
    light = data["lights"][0]
    assert light["type"] == "spot" and light["linear_falloff"] is True
    np.testing.assert_allclose(light["position"], [0, 0, 1], atol=1e-12)
    axis = np.subtract(light["target"], light["position"])
    np.testing.assert_allclose(axis / np.linalg.norm(axis), np.array([0.36, 0, -1]) / np.hypot(0.36, 1), atol=1e-9)
    assert (light["cutoff_angle"], light["falloff_start"]) == (35.0, 10.0)
    defaults = mitsuba_scene_data(_xml(tmp_path, 8, '<emitter type="spot"/>'))[0]["lights"][0]
    assert (defaults["cutoff_angle"], defaults["falloff_start"]) == (20.0, 15.0)  # Mitsuba's defaults


@pytest.mark.peer
def test_spot_over_a_floor_renders_like_mitsuba(tmp_path, device, mitsuba_scalar_spectral):
    """Both renderers, spectral, REPLICAS independent images each; 8 x 8-pixel block means and the image mean agree
    within 5 standard errors (tests/replica_agreement.py)."""
    mi = mitsuba_scalar_spectral
    replicas, replica_spp, size, block = 8, 4, 32, 8
    path = _xml(tmp_path, size)
    by_mitsuba = assert_renders_like_mitsuba(mi, path, device, replicas, replica_spp, block)
    assert by_mitsuba.mean() > 0.02  # the comparison saw a lit image


# A slide of four coloured quadrants (no symmetry, so a turned or mirrored projection shows) through a spot
# pointing down at the floor, its image's top toward +x.
SLIDE_SPOT = """<emitter type="spot">
  <transform name="to_world"><lookat origin="0, 0, 1" target="0, 0, 0" up="1, 0, 0"/></transform>
  <float name="cutoff_angle" value="40"/><float name="beam_width" value="38"/>
  <rgb name="intensity" value="3"/>
  <texture name="texture" type="bitmap"><string name="filename" value="slide.png"/></texture>
</emitter>"""


def _slide(folder: Path) -> None:
    from PIL import Image

    quadrants = np.zeros((8, 8, 3))
    quadrants[:4, :4], quadrants[:4, 4:] = (0.9, 0.1, 0.1), (0.1, 0.9, 0.1)
    quadrants[4:, :4], quadrants[4:, 4:] = (0.1, 0.1, 0.9), (0.9, 0.9, 0.9)
    Image.fromarray(np.round(quadrants * 255).astype(np.uint8)).save(folder / "slide.png")


def test_spot_texture_becomes_a_slide_in_its_frame(tmp_path):
    _slide(tmp_path)
    data, notes = mitsuba_scene_data(_xml(tmp_path, 8, SLIDE_SPOT))
    assert not notes, notes
    light = data["lights"][0]
    assert light["slide"] == {"texture": "texture_texture"} and data["textures"]["texture_texture"]["type"] == "bitmap"
    np.testing.assert_allclose(light["slide_up"], [-1, 0, 0], atol=1e-12)  # Mitsuba's y runs down the image


@pytest.mark.peer
def test_spot_with_a_slide_renders_like_mitsuba(tmp_path, device, mitsuba_scalar_spectral):
    """The projected image's colours, orientation and extent: 8 x 8-pixel blocks within 5 standard errors."""
    mi = mitsuba_scalar_spectral
    _slide(tmp_path)
    replicas, replica_spp, size, block = 8, 4, 32, 8
    path = _xml(tmp_path, size, SLIDE_SPOT)
    by_mitsuba = assert_renders_like_mitsuba(mi, path, device, replicas, replica_spp, block)
    # The quadrants differ in colour: a lost or constant slide would not pass the block test either.
    assert by_mitsuba[..., 0].mean() > 0.02 and by_mitsuba[..., 1].mean() > 0.02


@pytest.mark.peer
@pytest.mark.slow
def test_spot_with_a_slide_light_traces_like_mitsuba(tmp_path, device, mitsuba_scalar_spectral):
    """The light tracer starts its paths through the slide: Mitsuba's ptracer against spectrace's, as above."""
    mi = mitsuba_scalar_spectral
    _slide(tmp_path)
    replicas, replica_spp, size, block = 8, 4, 32, 8
    path = _xml(tmp_path, size, SLIDE_SPOT)
    path.write_text(path.read_text().replace('<integrator type="path">', '<integrator type="ptracer">'))
    by_mitsuba = assert_renders_like_mitsuba(mi, path, device, replicas, replica_spp, block)
    assert by_mitsuba[..., 0].mean() > 0.02 and by_mitsuba[..., 1].mean() > 0.02
