"""The [camera] table's keys per type (spectrace.cameras' tables): the aperture given as a radius or as f-number
and focal length, the thin lens's focus defaulting to the target's distance, and one-line errors naming the key."""

import pytest

import spectrace
from spectrace.errors import SpectraceError

REST = """[film]
width = 8
height = 6
[materials.grey]
type = "diffuse"
reflectance = { value = 0.5 }
[[shapes]]
type = "sphere"
material = "grey"
"""


def _load(tmp_path, camera: str):
    path = tmp_path / "scene.toml"
    path.write_text(f"[camera]\norigin = [0, 0, 5]\ntarget = [0, 0, 1]\n{camera}\n{REST}")
    return spectrace.load_scene(path)


def test_f_number_and_focal_length_give_the_aperture_radius(tmp_path):
    camera = _load(tmp_path, 'type = "thinlens"\nfov = 30\nf_number = 2.0\nfocal_length = 0.05').camera
    assert camera.aperture_radius == pytest.approx(0.0125)  # f / 2N
    assert camera.focus_distance == pytest.approx(4.0)  # the distance to target
    camera = _load(tmp_path, 'type = "thinlens"\nfov = 30\naperture_radius = 0.1\nfocus_distance = 2').camera
    assert (camera.aperture_radius, camera.focus_distance) == (0.1, 2.0)


@pytest.mark.parametrize(
    ("camera", "message"),
    [
        ('type = "thinlens"\nfov = 30', "give exactly one of aperture_radius, f_number"),
        ('type = "thinlens"\nfov = 30\naperture_radius = 0.1\nf_number = 2', "give exactly one"),
        ('type = "thinlens"\nfov = 30\nf_number = 2', "f_number and focal_length go together"),
        ('type = "thinlens"\nfov = 30\naperture_radius = -1', "camera.aperture_radius"),
        ('type = "orthographic"', "camera.view_width"),
        ('type = "orthographic"\nview_width = 2\nfov = 30', "camera.fov"),
        ('type = "equirectangular"\nfov = 30', "camera.fov"),
        ('type = "fisheye"\nfov = 30', "camera"),
        ("fov = 190", "fov must lie in (0, 180) degrees"),
    ],
)
def test_bad_camera_keys_are_one_line(tmp_path, camera, message):
    with pytest.raises(SpectraceError) as error:
        _load(tmp_path, camera)
    assert message in str(error.value) and "\n" not in str(error.value)


def test_the_api_checks_the_camera(device):
    sphere = spectrace.shape("sphere", spectrace.diffuse(0.5), emitter=spectrace.area_emitter(1.0))
    for camera, key in [
        (spectrace.Camera((0, 0, 5), (0, 0, 0), type="orthographic", view_width=0.0), "camera.view_width"),
        (spectrace.Camera((0, 0, 5), (0, 0, 0), type="thinlens", focus_distance=-1.0), "camera.focus_distance"),
        (spectrace.Camera((0, 0, 5), (0, 0, 0), type="pinhole"), "camera.type"),  # type: ignore[arg-type]
    ]:
        with pytest.raises(SpectraceError) as error:
            spectrace.render(spectrace.Scene(camera=camera, width=4, height=4, shapes=[sphere]), device=device)
        assert error.value.where == key
