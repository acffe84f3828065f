"""pbrt-v4's cameras and pixel filters as the importer maps them: an orthographic camera's screen window (its width,
its centre), a perspective camera with a lens radius as a thin lens, and PixelFilter (pbrt-v4's default Gaussian
when none is given). The renders of an orthographic pbrt scene are checked by size: a plane's image is its world
size in the screen window's units."""

from pathlib import Path

import numpy as np
import pytest

from spectrace.engine.renderer import Renderer
from spectrace.interop.pbrt import load_pbrt_scene, pbrt_scene_data
from spectrace.pixel_filters import PixelFilter

PLANE = 'Shape "trianglemesh" "point3 P" [-9 -9 0  9 -9 0  9 9 0  -9 9 0] "integer indices" [0 1 2 0 2 3]\n'


def _write(folder: Path, camera: str, before_world: str = "", world: str = PLANE) -> Path:
    path = folder / "scene.pbrt"
    path.write_text(
        f"""Scale -1 1 1
LookAt 0 0 5  0 0 0  0 1 0
{camera}
Film "rgb" "integer xresolution" 40 "integer yresolution" 20
{before_world}
WorldBegin
{world}"""
    )
    return path


def test_orthographic_screen_window_sets_width_and_centre(tmp_path):
    data, importer = pbrt_scene_data(_write(tmp_path, 'Camera "orthographic" "float screenwindow" [-1 3 -0.5 1.5]'))
    camera = data["camera"]
    assert camera["type"] == "orthographic" and camera["view_width"] == pytest.approx(4.0)
    # pbrt's camera +x (image right) is world −x through LookAt here, mirrored back by the leading Scale -1 1 1:
    # the window's centre (1, 0.5) in camera units lands at world (1, 0.5) in front of the eye.
    np.testing.assert_allclose(camera["origin"], [1.0, 0.5, 5.0], atol=1e-9)
    np.testing.assert_allclose(np.subtract(camera["target"], camera["origin"]), [0, 0, -1], atol=1e-9)
    assert not importer.warnings
    default, _ = pbrt_scene_data(_write(tmp_path, 'Camera "orthographic"'))
    assert default["camera"]["view_width"] == pytest.approx(4.0)  # [-aspect, aspect] for a 2:1 frame


def test_lens_radius_makes_a_thin_lens(tmp_path):
    camera = 'Camera "perspective" "float fov" 30 "float lensradius" 0.1 "float focaldistance" 4.5'
    data, importer = pbrt_scene_data(_write(tmp_path, camera))
    assert data["camera"]["type"] == "thinlens"
    assert (data["camera"]["aperture_radius"], data["camera"]["focus_distance"]) == (0.1, 4.5)
    assert not importer.warnings


@pytest.mark.parametrize(
    ("directive", "expected"),
    [
        ("", PixelFilter("gaussian", stddev=0.5, radius=1.5)),
        ('PixelFilter "box"', PixelFilter("box")),
        ('PixelFilter "triangle"', PixelFilter("tent", radius=2.0)),
        ('PixelFilter "gaussian" "float sigma" 0.3 "float xradius" 1', PixelFilter("gaussian", stddev=0.3, radius=1.0)),
        ('PixelFilter "mitchell" "float B" 0.5 "float C" 0.25', PixelFilter("mitchell", radius=2.0, b=0.5, c=0.25)),
    ],
)
def test_pixel_filters_import(tmp_path, directive, expected):
    scene = load_pbrt_scene(_write(tmp_path, 'Camera "perspective"', before_world=directive))
    assert scene.pixel_filter == expected


def test_orthographic_pbrt_scene_renders_a_square_at_its_size(tmp_path, device):
    """A 1 x 1 emitting square seen through a 4-unit-wide window on a 40-pixel-wide film: 10 x 10 pixels lit."""
    world = 'AreaLightSource "diffuse" "rgb L" [1 1 1]\nShape "trianglemesh" "point3 P" '
    world += '[-0.5 -0.5 0  0.5 -0.5 0  0.5 0.5 0  -0.5 0.5 0] "integer indices" [0 1 2 0 2 3]\n'
    path = _write(tmp_path, 'Camera "orthographic"', before_world='PixelFilter "box"', world=world)
    renderer = Renderer(load_pbrt_scene(path).with_overrides(spp=4), device)
    renderer.render(spp=4)
    lit = renderer.image().xyz[..., 1] > 0.5
    assert lit.sum() == 100 and lit[5:15, 15:25].all()


def _pbrt_equirect_direction(u: float, v: float) -> np.ndarray:
    """pbrt-v4's spherical camera, mapping "equirect" (cameras.cpp, SphericalCamera::GenerateRay): film position
    (u, v) in [0, 1]² looks along θ = π v, φ = 2π u, camera-space direction (sin θ cos φ, cos θ, sin θ sin φ)
    (SphericalDirection, then y and z swapped)."""
    theta, phi = np.pi * v, 2.0 * np.pi * u
    return np.array([np.sin(theta) * np.cos(phi), np.cos(theta), np.sin(theta) * np.sin(phi)])


@pytest.mark.parametrize(
    ("header", "camera_to_world"),
    [
        ("LookAt 0 0 0  0 0 1  0 1 0", np.eye(3)),  # pbrt's LookAt: camera +x = up × forward = world +x
        ("Scale -1 1 1\nLookAt 0 0 0  0 0 1  0 1 0", np.diag([-1.0, 1.0, 1.0])),  # the exporters' mirrored camera
    ],
    ids=["lookat", "mirrored"],
)
def test_spherical_equirect_camera_sees_each_direction_where_pbrt_does(tmp_path, device, header, camera_to_world):
    """A small emitting sphere placed along the direction pbrt's equirect mapping gives film position (u, v) is
    rendered by the imported equirectangular camera at that position: the centroid of its light lies within half a
    pixel of (u, v). The positions are off the image's centre line and its middle row, so a mirrored or flipped
    image would put them elsewhere."""
    width, height = 64, 32
    for u, v in ((0.25, 0.5), (0.5, 1.0 / 3.0), (0.625, 0.65), (0.85, 0.3)):
        position = 10.0 * camera_to_world @ _pbrt_equirect_direction(u, v)
        path = tmp_path / "spherical.pbrt"
        path.write_text(
            f"""{header}
Camera "spherical" "string mapping" "equirect"
Film "rgb" "integer xresolution" {width} "integer yresolution" {height}
PixelFilter "box"
WorldBegin
AttributeBegin
Translate {position[0]} {position[1]} {position[2]}
AreaLightSource "diffuse" "rgb L" [1 1 1]
Shape "sphere" "float radius" 0.8
AttributeEnd
"""
        )
        scene = load_pbrt_scene(path)
        assert scene.camera.type == "equirectangular"
        image = Renderer(scene.with_overrides(spp=16, max_depth=1), device).render(spp=16)
        y = image.xyz[..., 1].astype(np.float64)
        assert y.sum() > 0
        rows, columns = np.mgrid[0:height, 0:width] + 0.5
        column, row = (columns * y).sum() / y.sum(), (rows * y).sum() / y.sum()
        assert abs(column - u * width) <= 0.5 and abs(row - v * height) <= 0.5, (u, v, column, row)


@pytest.mark.parametrize("camera", ['Camera "spherical"', 'Camera "spherical" "string mapping" "equalarea"'])
def test_spherical_equal_area_camera_is_the_equalarea_camera(tmp_path, camera):
    """pbrt-v4's default mapping and "equalarea" are spectrace's equalarea camera (its mapping checked in
    tests/cameras/test_equal_area_camera.py); another mapping is refused in one line naming the two there are."""
    from spectrace.errors import SpectraceError

    assert load_pbrt_scene(_write(tmp_path, camera)).camera.type == "equalarea"
    with pytest.raises(SpectraceError) as caught:
        load_pbrt_scene(_write(tmp_path, 'Camera "spherical" "string mapping" "octahedral"'))
    message = str(caught.value)
    assert "\n" not in message and "scene.pbrt:3" in message and "equalarea" in message and "equirect" in message
