"""Mitsuba 3's projector imported as spectrace's projector (the irradiance profile): placed by to_world as its
perspective camera is, its image's orientation and extent, π·scale·irradiance on the plane at unit distance, rendered
like Mitsuba 3 renders the same XML over a diffuse floor."""

from pathlib import Path

import numpy as np
import pytest

from replica_agreement import assert_renders_like_mitsuba
from spectrace.interop.mitsuba import mitsuba_scene_data

# A projector 1 unit above a floor, tilted so the field's rows are foreshortened unequally, its image's top toward +y.
PROJECTOR = """<emitter type="projector">
  <transform name="to_world"><lookat origin="0, 0, 1" target="0.2, 0, 0" up="0, 1, 0"/></transform>
  <float name="fov" value="50"/><float name="scale" value="0.8"/>
  <texture name="irradiance" type="bitmap"><string name="filename" value="image.png"/></texture>
</emitter>"""
# Mitsuba's field for a focal length on the 3:2 image's aspect (the film diagonal's field, on the image's width).
FOCAL_PROJECTOR = PROJECTOR.replace('<float name="fov" value="50"/>', '<string name="focal_length" value="35mm"/>')
WHITE_PROJECTOR = """<emitter type="projector">
  <transform name="to_world"><lookat origin="0, 0, 1" target="0, 0, 0" up="0, 1, 0"/></transform>
  <float name="fov" value="60"/><rgb name="irradiance" value="0.5"/>
</emitter>"""


def _xml(folder: Path, size: int, emitter: str = PROJECTOR, integrator: str = "path") -> Path:
    path = folder / "projector.xml"
    path.write_text(
        f"""<scene version="3.0.0">
<integrator type="{integrator}"><integer name="max_depth" value="3"/></integrator>
<sensor type="perspective"><float name="fov" value="70"/>
  <transform name="to_world"><lookat origin="0, 0, 2" target="0, 0, 0" up="0, 1, 0"/></transform>
  <film type="hdrfilm"><integer name="width" value="{size}"/><integer name="height" value="{size}"/>
  <rfilter type="box"/></film></sensor>
{emitter}
<shape type="rectangle"><transform name="to_world"><scale value="2"/></transform>
  <bsdf type="diffuse"><rgb name="reflectance" value="0.6, 0.5, 0.4"/></bsdf></shape>
</scene>
"""
    )
    return path


def _image(folder: Path) -> None:
    """A 3:2 image of four coloured quadrants (no symmetry, so a turned or mirrored projection shows)."""
    from PIL import Image

    quadrants = np.zeros((8, 12, 3))
    quadrants[:4, :6], quadrants[:4, 6:] = (0.9, 0.1, 0.1), (0.1, 0.9, 0.1)
    quadrants[4:, :6], quadrants[4:, 6:] = (0.1, 0.1, 0.9), (0.9, 0.9, 0.9)
    Image.fromarray(np.round(quadrants * 255).astype(np.uint8)).save(folder / "image.png")


def test_projector_maps_frame_field_and_intensity(tmp_path):
    _image(tmp_path)
    data, notes = mitsuba_scene_data(_xml(tmp_path, 8))
    assert not notes, notes  # every property understood
    light = data["lights"][0]
    assert light["type"] == "projector" and light["fov"] == 50.0
    assert light["image"]["texture"] in data["textures"]
    assert light["intensity"]["value"] == pytest.approx(0.8 * np.pi)  # a bitmap under a flat scale, no illuminant
    np.testing.assert_allclose(light["up"], [0, 1, 0], atol=1e-9)
    white = mitsuba_scene_data(_xml(tmp_path, 8, WHITE_PROJECTOR))[0]["lights"][0]
    assert "image" not in white  # a constant irradiance is a factor of the intensity
    np.testing.assert_allclose(white["intensity"]["rgb"], [0.5 * np.pi] * 3, rtol=1e-12)


@pytest.mark.parametrize(("focal", "expected"), [(None, 34.0220566), ("35mm", 47.2163162)])
def test_a_projector_without_fov_takes_mitsubas_focal_length_field(tmp_path, focal, expected):
    """Mitsuba 3 gives a focal length (default 50mm) the field of a 36 x 24 mm film's diagonal on the image's aspect
    (a constant irradiance: square); the expected degrees are Mitsuba 3.9's perspective sensor's x_fov on a square
    film at those focal lengths."""
    extra = "" if focal is None else f'<string name="focal_length" value="{focal}"/>'
    emitter = WHITE_PROJECTOR.replace('<float name="fov" value="60"/>', extra)
    light = mitsuba_scene_data(_xml(tmp_path, 8, emitter))[0]["lights"][0]
    assert light["fov"] == pytest.approx(expected, rel=1e-6)


@pytest.mark.peer
def test_an_image_projectors_focal_length_field_is_mitsubas_on_the_images_aspect(tmp_path, mitsuba_scalar_spectral):
    """The field across the 3:2 image's width for 35mm is the x_fov Mitsuba's perspective sensor gives a 3:2 film."""
    mi = mitsuba_scalar_spectral
    _image(tmp_path)
    light = mitsuba_scene_data(_xml(tmp_path, 8, FOCAL_PROJECTOR))[0]["lights"][0]
    film = {"type": "hdrfilm", "width": 12, "height": 8}
    sensor = mi.load_dict({"type": "perspective", "focal_length": "35mm", "film": film})
    assert light["fov"] == pytest.approx(float(mi.traverse(sensor)["x_fov"]), rel=1e-5)


@pytest.mark.peer
@pytest.mark.parametrize(
    "emitter", [WHITE_PROJECTOR, PROJECTOR, FOCAL_PROJECTOR], ids=["white", "image", "image, focal length"]
)
def test_projector_over_a_floor_renders_like_mitsuba(tmp_path, device, mitsuba_scalar_spectral, emitter):
    """Both renderers, spectral, independent replicas; 8 x 8-pixel block means and the image mean agree within 5
    standard errors (tests/replica_agreement.py): the field's edges, the image's colours and orientation."""
    mi = mitsuba_scalar_spectral
    _image(tmp_path)
    replicas, replica_spp, size, block = 8, 16, 32, 8
    by_mitsuba = assert_renders_like_mitsuba(mi, _xml(tmp_path, size, emitter), device, replicas, replica_spp, block)
    assert by_mitsuba[..., 0].mean() > 0.01 and by_mitsuba[..., 2].mean() > 0.005  # a lit image


@pytest.mark.peer
@pytest.mark.slow
def test_projector_light_traces_like_mitsuba(tmp_path, device, mitsuba_scalar_spectral):
    """The light tracer starts its paths through the image: Mitsuba's ptracer against spectrace's light tracer."""
    mi = mitsuba_scalar_spectral
    _image(tmp_path)
    replicas, replica_spp, size, block = 8, 4, 32, 8
    path = _xml(tmp_path, size, PROJECTOR, integrator="ptracer")
    by_mitsuba = assert_renders_like_mitsuba(mi, path, device, replicas, replica_spp, block)
    assert by_mitsuba[..., 0].mean() > 0.01
