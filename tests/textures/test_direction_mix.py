"""pbrt-v4's `directionmix` texture: a · tex1 + (1 − a) · tex2, a = |n · dir| of the unit geometric normal n.

- A diffuse unit sphere whose reflectance is a directionmix of two constants, lit by a distant light only (direct
  light, max_depth 2) and seen by an orthographic camera: each pixel's value is the box-filtered closed form
  ρ(n)/π · E · max(0, n · l) over the pixel (n = the sphere's normal where the pixel's ray meets it, integrated on a
  fine grid here), within 4 of the render's own per-pixel standard errors (256 independent samples each). dir is
  chosen so that n · dir takes both signs over the visible half, and the two constants differ: the sides swapped
  or the absolute value dropped are far outside the noise.
- A smooth-shaded tent of two facets tilted 50° each way whose vertex normals all point straight up: a is each
  facet's own |n · dir|, not the shading normal's, so each facet shows its closed-form reflectance.
- The scene format and pbrt-v4's import (dir taken through the declaring transform, normalised), and the refusals.
"""

import numpy as np
import pytest

import spectrace
from scene_text import camera_film
from spectrace.engine.renderer import Renderer
from spectrace.errors import SpectraceError
from spectrace.geometry.mesh import TriangleMesh
from spectrace.interop.pbrt import load_pbrt_scene, pbrt_scene_data
from spectrace.scene.model import Camera, Scene
from stats_toolkit import assert_within_standard_errors, mean_and_standard_error

SIDE = 20
VIEW = 2.4  # scene units across the image
TEX1, TEX2 = 0.15, 0.85
DIR = np.array([0.8, 0.2, -0.6]) / np.linalg.norm([0.8, 0.2, -0.6])
LIGHT = np.array([-0.3, -0.4, -1.0]) / np.linalg.norm([-0.3, -0.4, -1.0])  # the direction the light travels
IRRADIANCE = 2.0


def _scene(seed: int) -> Scene:
    sphere = spectrace.shape("sphere", spectrace.diffuse(spectrace.directionmix_texture(TEX1, TEX2, dir=tuple(DIR))))
    return Scene(
        camera=Camera(origin=(0.0, 0.0, 5.0), target=(0.0, 0.0, 0.0), type="orthographic", view_width=VIEW),
        width=SIDE,
        height=SIDE,
        shapes=[sphere],
        lights=[spectrace.distant_light(tuple(LIGHT), IRRADIANCE)],
        max_depth=2,
        spp=256,
        seed=seed,
        sampler="independent",
        aovs=("variance",),
    )


def _expected(tex1=TEX1, tex2=TEX2, fold=np.abs, grid: int = 24) -> tuple[np.ndarray, np.ndarray]:
    """Each pixel's box-filtered Y (a = fold(n · dir)), and whether the pixel lies wholly on the lit sphere, away
    from its silhouette and terminator. The camera looks down −z with +y up, so the image's right is +x and row 0
    is the top."""
    offsets = (np.arange(grid) + 0.5) / grid
    pixel = VIEW / SIDE
    expected = np.zeros((SIDE, SIDE))
    inside = np.zeros((SIDE, SIDE), bool)
    for row in range(SIDE):
        for column in range(SIDE):
            x = -VIEW / 2 + (column + offsets[None, :]) * pixel
            y = VIEW / 2 - (row + offsets[:, None]) * pixel
            x, y = np.broadcast_arrays(x, y)
            r2 = x * x + y * y
            if r2.max() > 0.9**2:
                continue
            n = np.stack([x, y, np.sqrt(1.0 - r2)], axis=-1)
            cos_light = n @ -LIGHT
            if cos_light.min() < 0.05:
                continue
            a = fold(n @ DIR)
            rho = a * tex1 + (1.0 - a) * tex2
            expected[row, column] = np.mean(rho / np.pi * IRRADIANCE * cos_light)
            inside[row, column] = True
    return expected, inside


def test_sphere_pixels_follow_the_closed_form(device):
    expected, inside = _expected()
    assert inside.sum() > 100
    image = Renderer(_scene(3), device).render()
    mean, error = image.xyz[..., 1], image.aovs["variance"].astype(np.float64)
    assert_within_standard_errors(mean[inside], expected[inside], error[inside], slack=2e-5, what="directionmix")
    # The sides swapped, or n · dir without its absolute value, are far outside the noise: the check can fail.
    for wrong in (_expected(TEX2, TEX1)[0], _expected(fold=lambda c: np.clip(c, 0.0, None))[0]):
        assert np.max(np.abs(mean - wrong)[inside] / error[inside]) > 20.0


@pytest.mark.slow
@pytest.mark.parametrize("integrator", ["light", "bdpt"])
def test_light_tracer_and_bdpt_read_the_normal_too(device, integrator):
    """Their surface vertices (camera and light subpaths, and BDPT's densities) look textures up with the normal:
    each quadrant of the sphere's lit pixels, over 16 replicates, averages the closed form within 4 standard
    errors of the replicates."""
    expected, inside = _expected()
    renders = np.stack(
        [
            Renderer(_scene(seed).with_overrides(integrator=integrator, aovs=(), spp=16), device).render().xyz[..., 1]
            for seed in range(16)
        ]
    )
    half = SIDE // 2
    for rows in (slice(0, half), slice(half, SIDE)):
        for columns in (slice(0, half), slice(half, SIDE)):
            block = inside[rows, columns]
            means = (renders[:, rows, columns][:, block] - expected[rows, columns][block]).mean(axis=1)
            mean, error = mean_and_standard_error(means)
            assert_within_standard_errors(mean, 0.0, error, slack=2e-5, what=(integrator, rows, columns))


TILT = np.radians(50.0)
TENT_DIR = np.array([0.9, 0.0, 0.2]) / np.linalg.norm([0.9, 0.0, 0.2])


def _tent(seed: int, texture) -> Scene:
    """Two facets meeting along the y axis, each tilted TILT from the xy plane (left facing −x, right +x), their
    vertex normals all +z: shading and geometric normals differ by 50°. An orthographic camera looks straight down
    on it, lit by a distant light travelling −z; the ridge lies on a pixel boundary."""
    half = np.tan(TILT)
    vertices = np.array(
        [[-1, -1, -half], [0, -1, 0], [0, 1, 0], [-1, 1, -half], [1, -1, -half], [1, 1, -half]], np.float64
    )
    faces = np.array([[0, 1, 2], [0, 2, 3], [1, 4, 5], [1, 5, 2]])
    mesh = TriangleMesh(
        vertices, faces, uvs=(vertices[:, :2] + 1.0) / 2.0, normals=np.tile([0.0, 0.0, 1.0], (len(vertices), 1))
    )
    return Scene(
        camera=Camera(origin=(0.0, 0.0, 5.0), target=(0.0, 0.0, 0.0), type="orthographic", view_width=1.6),
        width=8,
        height=8,
        shapes=[spectrace.shape(mesh, spectrace.diffuse(texture))],
        lights=[spectrace.distant_light((0.0, 0.0, -1.0), IRRADIANCE)],
        max_depth=2,
        spp=64,
        seed=seed,
        sampler="independent",
        aovs=("variance",),
    )


def test_the_weight_is_the_geometric_normals_on_a_smooth_shaded_mesh(device):
    """pbrt-v4 looks textures up with its interaction's n, the geometric normal (TextureEvalContext), so a
    facet's weight is |n_facet · dir| wherever its shading normal points. The shading normal (+z here) shades:
    each pixel is ρ/π E with ρ = a tex1 + (1 − a) tex2 of its facet, within 4 of its own standard errors; the
    shading normal's weight, |z · dir|, is far outside them on both facets."""
    left, right = np.array([-np.sin(TILT), 0.0, np.cos(TILT)]), np.array([np.sin(TILT), 0.0, np.cos(TILT)])
    image = Renderer(_tent(5, spectrace.directionmix_texture(TEX1, TEX2, dir=tuple(TENT_DIR))), device).render()
    mean, error = image.xyz[..., 1], image.aovs["variance"].astype(np.float64)

    def expected(a_left: float, a_right: float) -> np.ndarray:
        a = np.where(np.arange(8)[None, :] < 4, a_left, a_right) * np.ones((8, 1))
        return (a * TEX1 + (1.0 - a) * TEX2) / np.pi * IRRADIANCE

    geometric = expected(abs(left @ TENT_DIR), abs(right @ TENT_DIR))
    assert abs(left @ TENT_DIR - right @ TENT_DIR) > 0.5  # the facets differ from each other too
    assert_within_standard_errors(mean, geometric, error, slack=2e-5, what="directionmix on a tent")
    shading = expected(TENT_DIR[2], TENT_DIR[2])
    for columns in (slice(0, 4), slice(4, 8)):
        assert np.min(np.abs(mean - shading)[:, columns] / error[:, columns]) > 20.0


def test_scene_file_directionmix(tmp_path):
    path = tmp_path / "scene.toml"
    path.write_text(
        camera_film(origin="[0, 0, 3]", fov="30", width="8", height="8")
        + """
[textures.facing]
type = "directionmix"
tex1 = { rgb = [0.8, 0.2, 0.1] }
tex2 = { value = 0.6 }
dir = [0, 0, 2]
[materials.paint]
type = "diffuse"
reflectance = { texture = "facing" }
[[shapes]]
type = "sphere"
material = "paint"
[[lights]]
type = "constant"
radiance = { value = 1.0 }
"""
    )
    texture = spectrace.load_scene(path).shapes[0].material.reflectance
    assert texture.dir == (0.0, 0.0, 1.0)
    path.write_text(path.read_text().replace("dir = [0, 0, 2]", "dir = [0, 0, 0]"))
    with pytest.raises(SpectraceError, match=r"textures\.facing\.dir.*zero|zero.*textures\.facing\.dir"):
        spectrace.load_scene(path)


def test_directionmix_is_checked():
    with pytest.raises(SpectraceError, match="zero"):
        spectrace.directionmix_texture(0.1, 0.2, dir=(0.0, 0.0, 0.0))
    with pytest.raises(SpectraceError, match="above 1"):
        spectrace.diffuse(spectrace.directionmix_texture(0.1, 1.5))
    with pytest.raises(SpectraceError, match="directionmix"):
        spectrace.mix([spectrace.diffuse(0.5), spectrace.diffuse(0.2)], amount=spectrace.directionmix_texture(0.1, 0.2))


PBRT_HEADER = """LookAt 0 0 5  0 0 0  0 1 0
Camera "perspective" "float fov" 20
Film "rgb" "integer xresolution" 8 "integer yresolution" 8
WorldBegin
LightSource "infinite" "rgb L" [1 1 1]
"""


def test_pbrt_directionmix_imports_with_its_direction_in_world_space(tmp_path):
    """`dir` is given in the transform in effect where the texture is declared (here a 90° turn about z, which takes
    +x to +y), normalised; tex1 and tex2 keep their sides and pbrt's defaults."""
    from PIL import Image

    Image.fromarray(np.full((2, 2, 3), 128, np.uint8)).save(tmp_path / "grey.png")
    path = tmp_path / "scene.pbrt"
    path.write_text(
        PBRT_HEADER + 'Texture "grey" "spectrum" "imagemap" "string filename" "grey.png"\n'
        "AttributeBegin\nRotate 90 0 0 1\n"
        'Texture "facing" "spectrum" "directionmix" "rgb tex1" [0.9 0.5 0.1] "texture tex2" "grey" '
        '"vector3 dir" [2 0 0]\n'
        "AttributeEnd\n"
        'Material "diffuse" "texture reflectance" "facing"\nShape "sphere"\n'
    )
    data, _ = pbrt_scene_data(path)
    (material,) = data["materials"].values()
    table = data["textures"][material["reflectance"]["texture"]]
    assert table["type"] == "directionmix"
    assert table["tex1"] == {"rgb": [0.9, 0.5, 0.1]}
    assert data["textures"][table["tex2"]["texture"]]["type"] == "bitmap"
    # pbrt's world is mirrored into spectrace's by the importer's handedness flip, which acts on x alone.
    assert np.allclose(np.abs(table["dir"]), [0.0, 1.0, 0.0], atol=1e-9)
    texture = load_pbrt_scene(path).shapes[0].material.reflectance
    assert isinstance(texture, type(spectrace.directionmix_texture())) and np.allclose(np.abs(texture.dir), [0, 1, 0])
    path.write_text(
        PBRT_HEADER
        + 'Texture "d" "spectrum" "directionmix"\nMaterial "diffuse" "texture reflectance" "d"\nShape "sphere"\n'
    )
    data, _ = pbrt_scene_data(path)
    (only,) = data["textures"].values()
    assert only == {"type": "directionmix", "tex1": {"value": 0.0}, "tex2": {"value": 1.0}, "dir": [0.0, 1.0, 0.0]}
