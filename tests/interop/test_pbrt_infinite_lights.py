"""Several pbrt-v4 `infinite` lights in one scene (pbrt adds them) and pbrt-v4's portals, against renders of the
lights one at a time and pbrt-v4's own formulas (PortalImageInfiniteLight in its lights.h/.cpp) in numpy."""

import math
from pathlib import Path

import numpy as np
import pytest

from replica_agreement import assert_replicas_agree, spectrace_replicas
from spectrace.interop.pbrt import load_pbrt_scene, pbrt_scene_data
from spectrace.spectral import spectrum_to_xyz

HEADER = """LookAt 0 0 5  0 0 0  0 1 0
Camera "perspective" "float fov" 30
Film "rgb" "integer xresolution" 16 "integer yresolution" 16
Integrator "path" "integer maxdepth" 2
WorldBegin
"""
SPHERE = 'Material "diffuse" "rgb reflectance" [0.7 0.7 0.7]\nShape "sphere" "float radius" 1\n'


def _write(folder: Path, body: str, name: str) -> Path:
    path = folder / name
    path.write_text(HEADER + body)
    return path


def _smooth_square(path: Path, side: int = 64) -> None:
    """An equal-area map (pbrt-v4's square) that varies smoothly with the light-space direction (x, y, z):
    RGB (1 + x/2, 1 + y/2, 1 + z/2) · (1.5 + z), never zero, brightest towards +z."""
    from spectrace.interop.pbrt.envmap import square_to_sphere
    from spectrace.io.exr import write_exr

    grid = (np.stack(np.meshgrid(np.arange(side), np.arange(side)), -1).reshape(-1, 2) + 0.5) / side
    w = square_to_sphere(grid)
    rgb = (1.0 + 0.5 * w) * (1.5 + w[:, 2:3])
    write_exr(path, rgb.reshape(side, side, 3).astype(np.float32), None, {})


def _images(scene, device, replicas: int = 8, spp: int = 16) -> np.ndarray:
    from spectrace.engine.renderer import Renderer

    return spectrace_replicas(Renderer(scene.with_overrides(seed=11), device), replicas, spp)


def test_two_constant_infinite_lights_render_as_one_of_the_summed_radiance(tmp_path, device):
    """pbrt adds its lights: L₁ + L₂ of one spectrum is one constant light of L₁ + L₂, the same image bit for bit."""
    from spectrace.engine.renderer import Renderer

    two = 'LightSource "infinite" "rgb L" [0.2 0.4 0.6] "float scale" 1\n'
    two += 'LightSource "infinite" "rgb L" [0.2 0.4 0.6] "float scale" 3\n'
    one = 'LightSource "infinite" "rgb L" [0.2 0.4 0.6] "float scale" 4\n'
    images = []
    for name, lights in (("two", two), ("one", one)):
        scene = load_pbrt_scene(_write(tmp_path, lights + SPHERE, f"{name}.pbrt")).with_overrides(seed=3)
        renderer = Renderer(scene, device)
        renderer.render(spp=4)
        images.append(renderer.image().xyz)
    assert images[0].mean() > 0
    np.testing.assert_array_equal(images[0], images[1])


def test_constant_lights_of_different_spectra_sum_their_spectra(tmp_path):
    """A blackbody and an RGB light: the combined constant light's spectrum is the sum of the two lights' own
    spectra, each imported alone (on the 1 nm grid), so its colour is the sum of their colours too."""
    lights = {
        "a": 'LightSource "infinite" "blackbody L" [3000] "float scale" 2\n',
        "b": 'LightSource "infinite" "rgb L" [0.1 0.3 0.9]\n',
    }

    def radiance(name: str, body: str) -> np.ndarray:
        (light,) = load_pbrt_scene(_write(tmp_path, body + SPHERE, f"{name}.pbrt")).lights
        return light.radiance.values

    both = radiance("both", lights["a"] + lights["b"])
    separate = radiance("a", lights["a"]) + radiance("b", lights["b"])
    np.testing.assert_allclose(both, separate, rtol=1e-6, atol=1e-9 * separate.max())
    np.testing.assert_allclose(spectrum_to_xyz(both), spectrum_to_xyz(separate), rtol=1e-6)


@pytest.mark.slow
@pytest.mark.parametrize(
    "second",
    [
        'LightSource "infinite" "rgb L" [0.3 0.3 0.3] "float scale" 2\n',
        'AttributeBegin\nRotate 90 1 0 0\nLightSource "infinite" "string filename" "sky.exr" "float scale" 0.5\n'
        "AttributeEnd\n",
    ],
    ids=["image plus constant", "image plus rotated image"],
)
def test_summed_lights_render_as_the_sum_of_their_separate_renders(tmp_path, device, second):
    """A diffuse sphere under an image light (its sky towards the camera) and a second light, summed into one map
    at import, against the sum of the two lights rendered alone: block means within 4 standard errors."""
    _smooth_square(tmp_path / "sky.exr")
    first = 'LightSource "infinite" "string filename" "sky.exr" "float scale" 1.5\n'
    combined = _images(load_pbrt_scene(_write(tmp_path, first + second + SPHERE, "both.pbrt")), device)
    alone = [
        _images(load_pbrt_scene(_write(tmp_path, light + SPHERE, f"{name}.pbrt")), device)
        for name, light in (("first", first), ("second", second))
    ]
    assert_replicas_agree(combined, alone[0] + alone[1], block=4, sigmas=4.0, what=second.strip())


def _pbrt_portal_radiance(
    square: np.ndarray, light_from_world: np.ndarray, portal: np.ndarray, w: np.ndarray
) -> np.ndarray:
    """pbrt-v4's PortalImageInfiniteLight radiance (RGB, before its scale) for world directions w (n, 3) of rays
    that pass through the portal: its constructor's rectified image (each pixel the equal-area map, bilinear, at
    the direction RenderFromImage gives its centre, turned into light space), looked up nearest at ImageFromRender's
    (u, v); zero where w is on the portal frame's −z side. The frame is Frame::FromXY(p03, p01)."""
    from spectrace.interop.pbrt.envmap import bilinear, sphere_to_square

    x = portal[3] - portal[0]
    x /= np.linalg.norm(x)
    y = portal[1] - portal[0]
    y /= np.linalg.norm(y)
    z = np.cross(x, y)
    side = square.shape[0]
    # The rectified image: pixel (i, j) at u = (i + ½)/side, v = (j + ½)/side, direction (tan α, tan β, 1) in the
    # portal's frame with α = −π/2 + u π, β = −π/2 + v π.
    u = (np.arange(side) + 0.5) / side
    alpha, beta = np.meshgrid(-np.pi / 2 + u * np.pi, -np.pi / 2 + u * np.pi)  # rows: v (β), columns: u (α)
    local = np.stack([np.tan(alpha), np.tan(beta), np.ones_like(alpha)], -1).reshape(-1, 3)
    local /= np.linalg.norm(local, axis=1, keepdims=True)
    world = local @ np.stack([x, y, z])  # FromLocal: x·lx + y·ly + z·lz
    in_light = world @ light_from_world.T
    in_light /= np.linalg.norm(in_light, axis=1, keepdims=True)
    rectified = bilinear(square, sphere_to_square(in_light)).reshape(side, side, 3)
    frame = np.stack([w @ x, w @ y, w @ z], -1)
    lit = frame[:, 2] > 0
    uu = np.clip((np.arctan2(frame[:, 0], frame[:, 2]) + np.pi / 2) / np.pi, 0, 1)
    vv = np.clip((np.arctan2(frame[:, 1], frame[:, 2]) + np.pi / 2) / np.pi, 0, 1)
    column = np.minimum((uu * side).astype(int), side - 1)
    row = np.minimum((vv * side).astype(int), side - 1)
    return np.where(lit[:, None], rectified[row, column], 0.0)


@pytest.mark.parametrize("constant", ["", 'LightSource "infinite" "rgb L" [0.3 0.2 0.1]\n'], ids=["alone", "summed"])
def test_image_lights_import_with_pbrt_s_texel_spectra(tmp_path, constant):
    """pbrt-v4 reads an image light's texels as RGBIlluminantSpectrum (the smooth uplift of the colour times the
    colour space's illuminant): an image light alone, and the map of a sum with one, import as smooth texels."""
    _smooth_square(tmp_path / "sky.exr", 16)
    light = 'LightSource "infinite" "string filename" "sky.exr"\n'
    (table,) = pbrt_scene_data(_write(tmp_path, light + constant + SPHERE, "sky.pbrt"), tmp_path / "out.toml")[0][
        "lights"
    ]
    assert table["type"] == "envmap" and table["texel_spectra"] == "smooth"


def test_portal_lights_import_as_pbrt_s_radiance_on_their_side(tmp_path):
    """Two portal lights of one map (as pbrt-v4's watercolor scene has), under a light transform (pbrt reads the
    portal's points in world space, the map through the light's transform): for directions leaving through either
    portal, the imported map equals pbrt's portal radiance, once (a ray crosses one portal), and is zero where
    neither portal's side holds the direction. Directions within 3° of a portal's plane are left out: the imported
    mask is drawn at texel centres."""
    from spectrace.io.images import read_environment_map

    _smooth_square(tmp_path / "sky.exr", 128)
    portals = np.array(
        [
            [[-1, 2, -1], [-1, 1, -2], [1, 1, -2], [1, 2, -1]],  # tilted, facing up and towards −z
            [[1, 2, 1], [1, 1, 2], [-1, 1, 2], [-1, 2, 1]],  # tilted, facing up and towards +z
        ],
        float,
    )
    body = "AttributeBegin\nRotate 30 0 1 0\nRotate -90 1 0 0\n"
    for portal in portals:
        points = " ".join(f"{v:g}" for v in portal.ravel())
        body += f'LightSource "infinite" "string filename" "sky.exr" "float scale" 2 "point3 portal" [{points}]\n'
    body += "AttributeEnd\n" + SPHERE
    data, importer = pbrt_scene_data(_write(tmp_path, body, "portal.pbrt"), tmp_path / "out.toml")
    (light,) = data["lights"]
    assert light["type"] == "envmap" and light["scale"] == 2.0
    assert any('"portal"' in warning for warning in importer.warnings)
    image = importer.files[Path(light["file"]).name].astype(np.float64)
    height, width = image.shape[:2]

    # pbrt's light space from its world: the inverse of Rotate 30 about y then Rotate −90 about x.
    def rotation(axis: int, degrees: float) -> np.ndarray:
        c, s = math.cos(math.radians(degrees)), math.sin(math.radians(degrees))
        i, j = [k for k in range(3) if k != axis]
        m = np.eye(3)
        m[i, i], m[i, j], m[j, i], m[j, j] = c, -s, s, c
        return m if axis != 1 else m.T

    world_from_light = rotation(1, 30) @ rotation(0, -90)
    square = read_environment_map(tmp_path / "sky.exr", "sky.exr")
    rng = np.random.default_rng(5)
    w = rng.normal(size=(4000, 3))
    w /= np.linalg.norm(w, axis=1, keepdims=True)
    normals = [np.cross(p[3] - p[0], p[1] - p[0]) for p in portals]
    normals = [n / np.linalg.norm(n) for n in normals]
    cosines = np.stack([w @ n for n in normals], 1)
    w = w[np.all(np.abs(cosines) > math.sin(math.radians(3)), axis=1)]
    cosines = np.stack([w @ n for n in normals], 1)
    # Each direction's radiance in pbrt for a ray leaving through the first portal whose side holds it.
    expected = np.zeros((len(w), 3))
    for k, portal in enumerate(portals):
        through = (cosines[:, k] > 0) & ~np.any(cosines[:, :k] > 0, axis=1)
        expected[through] = _pbrt_portal_radiance(square, world_from_light.T, portal, w[through])
    # The imported map, nearest texel, at the same directions in spectrace's world (rows θ = acos y from the
    # zenith, columns φ = atan2(x, −z) from −π: kernels/light_environment_map.cl).
    d = w @ importer.world[:3, :3].T
    row = np.minimum((np.arccos(np.clip(d[:, 1], -1, 1)) / np.pi * height).astype(int), height - 1)
    column = np.minimum(((np.arctan2(d[:, 0], -d[:, 2]) + np.pi) / (2 * np.pi) * width).astype(int), width - 1)
    imported = image[row, column]
    dark = ~np.any(cosines > 0, axis=1)
    assert dark.sum() > 100 and (~dark).sum() > 1000
    assert np.all(imported[dark] == 0.0)
    # Both are resamplings of a smooth map looked up at the nearest texel (pbrt's rectified texels stretch towards
    # the portal's plane, as tan does): they agree to the map's change over a texel, most of them far closer.
    relative = np.abs(imported[~dark] / expected[~dark] - 1.0)
    assert np.median(relative) < 0.01 and relative.max() < 0.1, (np.median(relative), relative.max())
