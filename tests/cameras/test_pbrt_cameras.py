"""pbrt-v4's cameras and pixel filters as the importer maps them: an orthographic camera's screen window (its width,
its centre), a perspective camera with a lens radius as a thin lens, and PixelFilter (pbrt-v4's default Gaussian
when none is given). The renders of an orthographic pbrt scene are checked by size: a plane's image is its world
size in the screen window's units."""

from pathlib import Path

import numpy as np
import pytest

from spectrace.engine.renderer import Renderer
from spectrace.interop.pbrt_v4 import load_pbrt_scene, pbrt_scene_data
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
