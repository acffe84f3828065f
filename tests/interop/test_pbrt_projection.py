"""pbrt-v4's projection light imported as spectrace's projector (the intensity profile): its frame, its field over
the image's shorter side, and the image landing where pbrt-v4's projection puts it; the floor's irradiance under a
white image is I cos θ/d² (the closed form of a point source)."""

from pathlib import Path

import numpy as np

from spectrace.engine.renderer import Renderer
from spectrace.interop.pbrt import load_pbrt_scene, pbrt_scene_data
from spectrace.spectral.colorimetry import spectrum_to_xyz

# The camera above the floor looking down; pbrt is left-handed, so world +x shows on the image's left.
HEADER = """LookAt 0 0 5  0 0 0  0 1 0
Camera "perspective" "float fov" 50
Film "rgb" "integer xresolution" 32 "integer yresolution" 32 "string filename" "out.exr"
Sampler "independent" "integer pixelsamples" 16
Integrator "path" "integer maxdepth" 1
WorldBegin
Material "diffuse" "rgb reflectance" [0.5 0.5 0.5]
Shape "bilinearmesh" "point3 P" [-3 -3 0  3 -3 0  -3 3 0  3 3 0]
AttributeBegin
  Translate 0 0 2
  Rotate 180 1 0 0
  LightSource "projection" "string filename" "image.png" "float fov" 40 "float scale" 3
AttributeEnd
"""


def _write(folder: Path, halves) -> Path:
    """A 2:1 image, its left half (u < ½) and right half coloured `halves`."""
    from PIL import Image

    pixels = np.zeros((4, 8, 3))
    pixels[:, :4], pixels[:, 4:] = halves
    Image.fromarray(np.round(pixels * 255).astype(np.uint8)).save(folder / "image.png")
    path = folder / "scene.pbrt"
    path.write_text(HEADER)
    return path


def test_projection_maps_frame_field_and_scale(tmp_path):
    data, _ = pbrt_scene_data(_write(tmp_path, ((1, 1, 1), (1, 1, 1))))
    light = data["lights"][0]
    assert light["type"] == "projector" and light["profile"] == "intensity"
    assert (light["fov"], light["fov_axis"]) == (40.0, "shorter")  # pbrt's fov spans the shorter side
    axis = np.subtract(light["target"], light["position"])
    np.testing.assert_allclose(axis, [0, 0, -1], atol=1e-9)  # the light's +z, turned down
    assert data["textures"][light["image"]["texture"]]["filter"] == "nearest"


def test_projection_image_lands_where_pbrt_projects_it(tmp_path, device):
    """The image's left half (u < ½, light-space x < 0, pbrt world x < 0 here) is red and its right half blue: on
    the floor pbrt's world +x shows on the image's left, so the render's left half is blue and its right half red."""
    scene = load_pbrt_scene(_write(tmp_path, ((0.9, 0.05, 0.05), (0.05, 0.05, 0.9))))
    renderer = Renderer(scene, device)
    renderer.render(spp=16)
    xyz = renderer.image().xyz.astype(np.float64)
    left, right = xyz[:, :16].mean(axis=(0, 1)), xyz[:, 16:].mean(axis=(0, 1))
    # Blue light has far more Z than X; red the opposite.
    assert left[2] > 3.0 * left[0] and right[0] > 3.0 * right[2], (left, right)


def test_projection_lights_the_floor_as_a_point_source(tmp_path, device):
    """A white image: the floor's radiance is ρ/π · I cos θ/d², I the light's intensity (the intensity profile is
    flat over the field), at the floor's points seen through each pixel; film Y against that closed form."""
    scene = load_pbrt_scene(_write(tmp_path, ((1, 1, 1), (1, 1, 1))))
    light = scene.lights[0]
    renderer = Renderer(scene, device)
    renderer.render(spp=64)
    y = renderer.image().xyz[..., 1].astype(np.float64)
    # The centre pixels see the floor within 0.15 of the axis (d = 2, cos³θ > 0.99), inside the field.
    expected = 0.5 / np.pi * spectrum_to_xyz(light.intensity)[1] / 2.0**2
    centre = y[15:17, 15:17].mean()
    assert abs(centre / expected - 1.0) < 0.015, (centre, expected)
