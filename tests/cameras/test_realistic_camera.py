"""The `realistic` camera (a thick lens system, pbrt-v4's lens files) against optics worked out here:

- focal lengths: the published double Gauss (50 mm, Tronnier's patent as Smith's Modern Lens Design tabulates it)
  and a single thick lens against the paraxial (ABCD) matrices of their prescriptions and the lensmaker's equation;
- focus: a small light at the focus distance images to a spot far smaller than the same light's image with the
  lens focused elsewhere, where the image of a film point is;
- energy: the image of a uniform environment of radiance 1 is each pixel's irradiance factor ∫ cos⁴θ / z² dA over
  the rays that pass the lens, counted here by a ray trace of the prescription of this file's own (float64), within
  the Monte Carlo error of the render (the camera draws its rays over the exit pupil's bounds: any part of the
  pupil they missed would be missing light here);
- orientation, the pbrt import, the refusals (light tracer, BDPT) and one-line errors naming the key."""

import math
import shutil
from pathlib import Path

import numpy as np
import pytest

import spectrace
from spectrace.engine.renderer import Renderer
from spectrace.errors import SpectraceError
from spectrace.interop.pbrt import load_pbrt_scene, pbrt_scene_data
from spectrace.resources import scenes_dir

DGAUSS = scenes_dir() / "lenses" / "dgauss.50mm.dat"
# A biconvex singlet: R1 = 60 mm, R2 = -60 mm, 4 mm of n = 1.5 glass, 16 mm across, its stop 2 mm behind.
SINGLET = "60 4 1.5 16\n-60 2 1 16\n0 0 0 10\n"


def _rows(path: Path) -> np.ndarray:
    values = [float(v) for line in path.read_text().splitlines() for v in line.split("#")[0].split()]
    return np.array(values).reshape(-1, 4)


def _paraxial_focal_length(rows: np.ndarray) -> float:
    """The effective focal length (mm) of a prescription from its paraxial ray-transfer matrix (refraction
    −(n₂ − n₁)/R, transfer t/n on the reduced angle)."""
    matrix, n1 = np.eye(2), 1.0
    for i, (radius, thickness, eta, _) in enumerate(rows):
        n2 = eta if eta != 0 else 1.0
        power = 0.0 if radius == 0 else (n2 - n1) / radius
        matrix = np.array([[1.0, 0.0], [-power, 1.0]]) @ matrix
        if i < len(rows) - 1:
            matrix = np.array([[1.0, thickness / n2], [0.0, 1.0]]) @ matrix
        n1 = n2
    return -1.0 / matrix[1, 0]


def test_the_double_gauss_has_its_published_focal_length():
    from spectrace.cameras.realistic import lens_system

    rows = _rows(DGAUSS)
    paraxial = _paraxial_focal_length(rows)
    focal = lens_system(rows, aperture_diameter=17.1, focus_distance=10.0).effective_focal_length / 1e-3
    assert focal == pytest.approx(paraxial, rel=1e-4)
    assert focal == pytest.approx(50.0, rel=0.01)  # "scaled to 50 mm": the table's rounding leaves 50.36


def test_a_single_lens_has_the_lensmakers_focal_length(tmp_path):
    from spectrace.cameras.realistic import lens_system

    r1, r2, d, n = 60.0, -60.0, 4.0, 1.5
    lensmaker = 1.0 / ((n - 1.0) * (1.0 / r1 - 1.0 / r2 + (n - 1.0) * d / (n * r1 * r2)))
    rows = np.array([[float(v) for v in line.split()] for line in SINGLET.splitlines()])
    focal = lens_system(rows, aperture_diameter=10.0, focus_distance=10.0).effective_focal_length / 1e-3
    assert focal == pytest.approx(lensmaker, rel=1e-4)
    assert focal == pytest.approx(_paraxial_focal_length(rows), rel=1e-4)


CAMERA = """[camera]
type = "realistic"
origin = [0, 0, 0]
target = [0, 0, 1]
lens_file = "{lens}"
aperture_diameter = {aperture}
focus_distance = {focus}
film_diagonal = {diagonal}

[film]
width = {width}
height = {height}
filter = {{ type = "box" }}

[integrator]
type = "path"
max_depth = {depth}

[sampler]
type = "independent"
spp = {spp}

[materials.black]
type = "diffuse"
reflectance = {{ value = 0.0 }}
"""


def _scene(tmp_path: Path, rest: str, lens: str = "dgauss.50mm.dat", **keys):
    values = dict(aperture=8, focus=1.0, diagonal=35, width=24, height=16, depth=1, spp=16) | keys
    path = tmp_path / "camera.toml"
    path.write_text(CAMERA.format(lens=lens, **values) + rest)
    return spectrace.load_scene(path)


SKY = '[[lights]]\ntype = "constant"\nradiance = { value = 1.0 }\n'
LIGHT = """
[[shapes]]
type = "sphere"
transform = [{{ scale = {radius} }}, {{ translate = [{x}, {y}, {z}] }}]
material = "black"
emitter = {{ radiance = {{ value = 1000 }} }}
"""


def _spot(image: np.ndarray) -> tuple[np.ndarray, float]:
    """The light's centroid (x, y in pixels) and rms radius."""
    y = image[..., 1].astype(np.float64)
    rows, cols = np.indices(y.shape) + 0.5
    total = y.sum()
    cx, cy = (y * cols).sum() / total, (y * rows).sum() / total
    return np.array([cx, cy]), math.sqrt((y * ((cols - cx) ** 2 + (rows - cy) ** 2)).sum() / total)


@pytest.mark.slow
def test_a_point_at_the_focus_distance_images_sharply(tmp_path, device):
    (tmp_path / "singlet.dat").write_text(SINGLET)
    light = LIGHT.format(radius=0.0005, x=0, y=0, z=1.0)
    keys = dict(lens="singlet.dat", aperture=10, diagonal=4, width=32, height=32, spp=64)
    sharp = Renderer(_scene(tmp_path, light, focus=1.0, **keys), device).render().xyz
    blurred = Renderer(_scene(tmp_path, light, focus=0.6, **keys), device).render().xyz
    (centre, radius), (_, blurred_radius) = _spot(sharp), _spot(blurred)
    np.testing.assert_allclose(centre, [16, 16], atol=0.25)  # on the axis: the film's centre
    assert radius < 1.0  # pixels (0.09 mm): the light's own image is 0.03 mm across
    # Focused at 0.6 m the film sits 2.8 mm behind the light's image, a blur 0.47 mm across: about 3 pixels rms.
    assert blurred_radius > 3.0 * radius and blurred_radius > 2.0


def test_the_image_keeps_the_scenes_orientation(tmp_path, device):
    """A light up and to the right of the view (camera_right = forward × up: −x here) appears up and right."""
    light = LIGHT.format(radius=0.02, x=-0.2, y=0.15, z=2.0)
    image = Renderer(_scene(tmp_path, light, focus=2.0, spp=16), device).render().xyz
    (cx, cy), _ = _spot(image)
    assert cx > 12 + 3 and cy < 8 - 2


def _irradiance_factor(rows_mm: np.ndarray, rear_mm: float, film_xy_mm: np.ndarray, count: int = 40000) -> float:
    """∫ cos⁴θ / z² dA over the rear element's disk for the rays from the film point that pass every surface
    (mm, lens axis +z toward the scene, film at 0), by stratified points on the disk."""
    rows = rows_mm.copy()
    rows[-1, 1] = rear_mm
    z_vertex = np.cumsum(rows[::-1, 1])[::-1]
    side = int(math.sqrt(count))
    u, v = (np.indices((side, side)).reshape(2, -1) + 0.5) / side
    rear_radius = rows[-1, 3] / 2.0
    disk = rear_radius * np.sqrt(u)[:, None] * np.stack([np.cos(2 * np.pi * v), np.sin(2 * np.pi * v)], axis=1)
    o = np.zeros((len(disk), 3))
    o[:, :2] = film_xy_mm
    d = np.column_stack([disk - film_xy_mm, np.full(len(disk), z_vertex[-1])])
    cos_theta = d[:, 2] / np.linalg.norm(d, axis=1)
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    alive = np.ones(len(o), bool)
    for i in range(len(rows) - 1, -1, -1):
        radius, _, eta, aperture = rows[i]
        n_film = eta if eta != 0 else 1.0
        n_scene = (rows[i - 1, 2] or 1.0) if i > 0 else 1.0
        if radius == 0:
            t = (z_vertex[i] - o[:, 2]) / d[:, 2]
        else:
            centre = np.array([0.0, 0.0, z_vertex[i] - radius])
            oc = o - centre
            b = (oc * d).sum(1)
            disc = b * b - ((oc * oc).sum(1) - radius * radius)
            alive &= disc >= 0
            t = -b + np.sign(radius) * np.sqrt(np.maximum(disc, 0))
        o = o + t[:, None] * d
        alive &= (o[:, :2] ** 2).sum(1) <= (aperture / 2) ** 2
        if radius != 0:
            normal = (o - centre) / abs(radius)
            normal *= -np.sign((normal * d).sum(1))[:, None]  # toward the incoming ray
            ratio = n_film / n_scene
            cos_i = -(normal * d).sum(1)
            k = 1 - ratio**2 * (1 - cos_i**2)
            alive &= k > 0
            d = ratio * d + (ratio * cos_i - np.sqrt(np.maximum(k, 0)))[:, None] * normal
    area = math.pi * rear_radius**2
    return float(np.mean(np.where(alive, cos_theta**4, 0.0)) * area / z_vertex[-1] ** 2)


@pytest.mark.slow
def test_a_uniform_sky_images_as_the_lens_passes_light(tmp_path, device):
    scene = _scene(tmp_path, SKY, aperture=12, focus=3.0, width=12, height=8, spp=256)
    image = Renderer(scene, device).render().xyz[..., 1].astype(np.float64)
    rear = scene.camera.lens_system.rear_distance / 1e-3
    width = 35.0 / math.sqrt(1 + (8 / 12) ** 2)
    height, pixel = width * 8 / 12, width / 12
    rows = _rows(DGAUSS)
    rows[rows[:, 0] == 0, 3] = 12.0
    # The factor depends on the film point's distance from the axis only: traced at 48 distances, interpolated.
    radii = np.linspace(0.0, 18.0, 48)
    factor = [_irradiance_factor(rows, rear, np.array([r, 0.0]), 10000) for r in radii]
    expected = np.zeros_like(image)
    for row in range(8):
        for col in range(12):
            # The pixel's average over a 3 × 3 grid of film points (a box filter).
            grid = np.array([1 / 6, 1 / 2, 5 / 6])
            x, y = (col + grid[:, None]) * pixel - width / 2, (row + grid[None, :]) * pixel - height / 2
            expected[row, col] = np.mean(np.interp(np.hypot(x, y), radii, factor))
    # Each sample is 0 or at most A / z², A the largest area the camera draws its rear points over (the exit
    # pupil's bounds); its variance is at most E (A/z² − E).
    largest = max((x1 - x0) * (y1 - y0) for x0, y0, x1, y1 in scene.camera.lens_system.pupils) / 1e-6
    ceiling = largest / rear**2
    sigma = np.sqrt(expected * (ceiling - expected) / 256)
    assert expected[0, 0] < 0.75 * expected[4, 6]  # vignetting and cos⁴ darken the corners
    assert np.all(np.abs(image - expected) < 5 * sigma + 2e-3 * expected), (image / expected).round(3)


@pytest.mark.slow
def test_light_tracing_and_bdpt_refuse_the_lens_in_one_line(tmp_path, device):
    for integrator in ("light", "bdpt"):
        scene = _scene(tmp_path, SKY).with_overrides(integrator=integrator)
        with pytest.raises(SpectraceError, match="not 'realistic'") as failure:
            Renderer(scene, device).render()
        assert "\n" not in str(failure.value)


@pytest.mark.parametrize(
    ("lens", "keys", "message", "key"),
    [
        ("missing.dat", {}, "cannot read lens file", "camera.lens_file"),
        ("bad.dat", {}, "4 numbers a surface", "camera.lens_file"),
        ("dgauss.50mm.dat", {"focus": 0.1}, "cannot focus at 0.1", "camera.focus_distance"),
    ],
)
def test_bad_lens_input_names_the_key(tmp_path, lens, keys, message, key):
    (tmp_path / "bad.dat").write_text("# two numbers too few\n10 2 1.5\n")
    with pytest.raises(SpectraceError, match=message) as failure:
        _scene(tmp_path, SKY, lens=lens, **keys)
    assert failure.value.where == f"{tmp_path / 'camera.toml'}: {key}"


PBRT = """LookAt 0 0 0  0 0 1  0 1 0
Camera "realistic" "string lensfile" "lenses/dgauss.50mm.dat" "float aperturediameter" 8 "float focusdistance" 2
Film "rgb" "integer xresolution" 12 "integer yresolution" 8 "float diagonal" 30
Sampler "independent" "integer pixelsamples" 16
Integrator "path" "integer maxdepth" 1
WorldBegin
LightSource "infinite" "rgb L" [1 1 1]
"""


@pytest.mark.slow
def test_pbrt_realistic_camera_imports_and_renders_as_its_toml(tmp_path, device):
    (tmp_path / "lenses").mkdir()
    shutil.copy(DGAUSS, tmp_path / "lenses" / "dgauss.50mm.dat")
    path = tmp_path / "lens.pbrt"
    path.write_text(PBRT)
    data, _ = pbrt_scene_data(path, tmp_path / "lens.toml")
    camera = data["camera"]
    assert camera["type"] == "realistic" and camera["lens_file"] == "lenses/dgauss.50mm.dat"
    assert (camera["aperture_diameter"], camera["focus_distance"], camera["film_diagonal"]) == (8, 2, 30)
    imported = load_pbrt_scene(path)
    twin = _scene(
        tmp_path,
        '[[lights]]\ntype = "constant"\nradiance = { rgb = [1.0, 1.0, 1.0] }\n',
        lens="lenses/dgauss.50mm.dat",
        aperture=8,
        focus=2,
        diagonal=30,
        width=12,
        height=8,
    )
    assert imported.camera.lens_system == twin.camera.lens_system
    assert imported.camera.lens_system.film_diagonal == pytest.approx(0.030)
    image = Renderer(imported, device).render().xyz
    assert image[..., 1].mean() > 0.01


def test_a_lens_made_in_python_renders_and_is_not_saved_without_its_file(tmp_path, device):
    from spectrace.cameras.realistic import lens_system, read_lens_file

    lens = lens_system(read_lens_file(DGAUSS, "lens"), aperture_diameter=8.0, focus_distance=2.0)
    camera = spectrace.Camera(origin=(0, 0, 0), target=(0, 0, 1), type="realistic", lens_system=lens)
    scene = spectrace.Scene(camera=camera, width=6, height=4, shapes=[], spp=4, max_depth=1)
    scene = scene.with_overrides(lights=[spectrace.constant_environment(1.0)])
    assert Renderer(scene, device).render().xyz[..., 1].mean() > 0.01
    with pytest.raises(SpectraceError, match="lens_file") as failure:
        spectrace.save_scene(scene, tmp_path / "lens.toml")
    assert "\n" not in str(failure.value) and not (tmp_path / "lens.toml").exists()
