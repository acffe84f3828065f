"""pbrt-v4's `cloud` medium imported as a tabulated density grid: the host's Perlin noise against a reference written
here from Perlin's 2002 paper and the book (tests/textures/test_procedural_textures.py) and against the device's
noise; pbrt-v4's cloud density (Pharr, Jakob & Humphreys, 4th ed., 11.4.2, restated here) at the grid's voxel
centres; the device's transmittance through the imported grid against a quadrature of the formula; and the import
of the medium block of pbrt-v4's `clouds` scene."""

from pathlib import Path

import numpy as np
import pytest
from scipy import ndimage
from tests.media.test_grid_media import LANES_NM, _device_medium
from tests.textures.lookup import HARNESS, TextureHarness
from tests.textures.test_procedural_textures import GRADIENTS, PERMUTATION
from tests.textures.test_procedural_textures import noise as reference_noise

import spectrace
from spectrace.errors import SpectraceError
from spectrace.interop.pbrt import cloud, pbrt_scene_data
from spectrace.interop.pbrt.importer import load_pbrt_scene
from spectrace.scene.model import Medium
from spectrace.spectral.spectrum import Spectrum
from spectrace.textures.perlin import noise, noise_gradient
from stats_toolkit import assert_within_standard_errors, mean_and_standard_error


def reference_density(p, density=1.0, wispiness=1.0, frequency=5.0):
    """pbrt-v4's CloudMedium::Density, restated from the book over the reference noise: the lookup point frequency·p
    moved twice along the noise's forward-difference gradient (step 0.01) at 10 and 19.9 times it, by 0.05·w and
    0.025·w; five octaves of noise of weights ½, ¼, … at lacunarity 1.99; then the fall-off with height."""
    p = np.atleast_2d(np.asarray(p, float))
    pp = frequency * p
    if wispiness > 0:
        for weight, scale in ((0.05 * wispiness, 10.0), (0.025 * wispiness, 19.9)):
            q = scale * pp
            n0 = reference_noise(q)
            grad = np.stack([(reference_noise(q + 0.01 * e) - n0) / 0.01 for e in np.eye(3)], axis=1)
            pp = pp + weight * grad
    d = sum(0.5 ** (i + 1) * reference_noise(1.99**i * pp) for i in range(5))
    y = p[:, 1]
    d = np.clip((1 - y) * 4.5 * density * d, 0, 1) + 2 * np.maximum(0, 0.5 - y)
    return np.clip(d, 0, 1)


def test_the_host_noise_is_perlins():
    """The host's noise equals the reference at random points (negative ones too: the lattice wraps at 256), and
    its finite-difference gradient at a lattice point is that point's hashed gradient (the noise is g·d there, the
    fade's correction to the difference quotient
    10h² · |g'| ≤ 2·10⁻³ at h = 0.01)."""
    rng = np.random.default_rng(3)
    points = rng.uniform(-600.0, 600.0, (20_000, 3))
    np.testing.assert_allclose(noise(points), reference_noise(points), rtol=0, atol=1e-12)
    lattice = rng.integers(-300, 300, (50, 3))
    x, y, z = (lattice & 255).T
    codes = PERMUTATION[(PERMUTATION[(PERMUTATION[x] + y) & 255] + z) & 255] & 15
    np.testing.assert_allclose(noise_gradient(lattice.astype(float)), GRADIENTS[codes], atol=2e-3)


def test_the_host_noise_is_the_devices(kernel_runner):
    """An fbm texture of one octave is the device's Perlin noise at the point: the host's noise there, within the
    device's float32 rounding (points as float32 holds them, near the origin and past the lattice's wrap at 256)."""
    harness = TextureHarness(kernel_runner(HARNESS), [(spectrace.fbm_texture(octaves=1), "float")])
    rng = np.random.default_rng(8)
    points = np.concatenate([rng.uniform(-4, 4, (500, 3)), rng.uniform(200, 300, (100, 3))])
    points = points.astype(np.float32).astype(np.float64)
    on_device = harness.lookup_points(0, points)
    tolerance = np.where(np.arange(len(points)) < 500, 5e-6, 1e-4)[:, None]
    assert np.all(np.abs(on_device - noise(points)[:, None]) <= tolerance)


def test_the_cloud_density_is_pbrts_formula():
    """At random points the host's density is the restated formula; below y = 0 it is 1 (the 2·(½ − y) floor) and
    at y = 1 it is 0 (the height fall-off), whatever the noise."""
    rng = np.random.default_rng(4)
    points = rng.uniform(-0.2, 1.2, (4000, 3))
    for params in ({}, {"density": 2.0}, {"density": 0.7, "wispiness": 0.0, "frequency": 3.0}):
        np.testing.assert_allclose(
            cloud.cloud_density(points, **params), reference_density(points, **params), rtol=0, atol=1e-12
        )
    values = cloud.cloud_density(points, density=2.0)
    assert 0.2 < np.mean((values > 0) & (values < 1)) < 0.9  # the clamps leave a cloud, not a block
    low = points.copy()
    low[:, 1] = rng.uniform(-0.5, 0.0, len(points))
    assert np.all(cloud.cloud_density(low, density=2.0) == 1.0)
    high = points.copy()
    high[:, 1] = 1.0
    assert np.all(cloud.cloud_density(high, density=2.0) == 0.0)


def test_the_resolution_resolves_the_finest_noise_or_is_capped():
    """4 samples a lattice cell of the finest noise: with wispiness the warp's at 10 · 1.99 = 19.9 times the
    frequency, without it the fifth octave's at 1.99⁴; a grid past the cap shrinks evenly under it."""
    resolution, capped = cloud.cloud_resolution([0, 0, 0], [1, 0.5, 2], wispiness=1.0, frequency=1.0)
    assert (resolution, capped) == ([80, 40, 160], False)  # ceil(4 · 19.9 · extent)
    resolution, capped = cloud.cloud_resolution([0, 0, 0], [1, 1, 1], wispiness=0.0, frequency=1.0)
    assert (resolution, capped) == ([63, 63, 63], False)  # ceil(4 · 1.99⁴) = ceil(62.7)
    resolution, capped = cloud.cloud_resolution([0, 0, 0], [1, 1, 1], wispiness=1.0, frequency=5.0)
    assert capped and np.prod(resolution) <= cloud.MAX_CLOUD_VOXELS and len(set(resolution)) == 1
    assert resolution[0] >= 0.99 * round(cloud.MAX_CLOUD_VOXELS ** (1 / 3))


# The medium block of pbrt-v4's `clouds` scene (pbrt-v4-scenes, clouds/clouds.pbrt), with a plain sky for its
# sky.exr, moved by a CTM so that the placement shows.
CLOUDS = """LookAt .5 .8 -.5       .5 .7 .5       0 1 0
Camera "perspective" "float fov" 35
Film "rgb" "integer xresolution" 8 "integer yresolution" 6
WorldBegin
LightSource "infinite" "rgb L" [1 1 1]
AttributeBegin
Translate 0.25 -0.5 0.125
MakeNamedMedium "c" "string type" "cloud"
   "spectrum sigma_s" [200 10 900 10] "spectrum sigma_a" [200 .01 900 .01]
   "float density" 2 {extra}
AttributeEnd
MediumInterface "c" ""
Material ""
Translate .5 .5 .5
Shape "sphere" "float radius" 2
"""
MEDIUM_FROM_WORLD = np.array([[1, 0, 0, -0.25], [0, 1, 0, 0.5], [0, 0, 1, -0.125], [0, 0, 0, 1.0]])


def _write(tmp_path: Path, extra: str = "") -> Path:
    path = tmp_path / "clouds.pbrt"
    path.write_text(CLOUDS.format(extra=extra))
    return path


def test_the_clouds_scenes_medium_imports_as_a_grid_of_the_formula(tmp_path, monkeypatch):
    """The cloud's spectra, its box, a warning that it was tabulated (and capped, at pbrt's default frequency 5),
    and a volume file whose every voxel is the formula at the voxel's centre in the medium's space (float32)."""
    monkeypatch.setattr(cloud, "MAX_CLOUD_VOXELS", 20**3)
    path = _write(tmp_path)
    data, importer = pbrt_scene_data(path, tmp_path / "clouds.toml")
    interior = data["shapes"][0]["interior"]
    assert interior["sigma_s"] == {"values": [[200.0, 10.0], [900.0, 10.0]]}
    assert interior["sigma_a"] == {"values": [[200.0, 0.01], [900.0, 0.01]]}
    assert interior["density"]["box"] == [[0.0, 0.0, 0.0], [1.0, 1.0, 1.0]]
    (warning,) = [w for w in importer.warnings if "cloud" in w]
    assert "tabulated as a 20×20×20 density grid" in warning and "capped" in warning and "clouds.pbrt:8" in warning
    name = Path(interior["density"]["file"]).name
    values = importer.files[name]
    centres = (np.arange(20) + 0.5) / 20
    z, y, x = np.meshgrid(centres, centres, centres, indexing="ij")
    expected = reference_density(np.stack([x, y, z], -1).reshape(-1, 3), density=2.0).reshape(20, 20, 20)
    np.testing.assert_allclose(values, expected.astype(np.float32), rtol=0, atol=1e-6)

    scene = load_pbrt_scene(path)  # written, read back from its volume file and placed
    grid = scene.shapes[0].interior.density
    np.testing.assert_array_equal(grid.density, values)
    unit_to_medium = MEDIUM_FROM_WORLD @ np.linalg.inv(importer.world) @ grid.to_world
    np.testing.assert_allclose(unit_to_medium, np.eye(4), atol=1e-12)


def test_a_wispless_clouds_box_and_frequency_are_read(tmp_path):
    """p0, p1, frequency and wispiness (0: no warp) set the grid's box and resolution; g the phase function; a
    scale or emission, which pbrt-v4's cloud does not read, is reported as not imported."""
    path = _write(tmp_path, '"float wispiness" 0 "float frequency" 0.5 "point3 p0" [0 0 0] "point3 p1" [1 .5 2]'
                            ' "float g" 0.3 "float scale" 4 "rgb Le" [1 1 1]')  # fmt: skip
    data, importer = pbrt_scene_data(path, tmp_path / "clouds.toml")
    interior = data["shapes"][0]["interior"]
    assert interior["g"] == 0.3 and interior["density"]["box"] == [[0.0, 0.0, 0.0], [1.0, 0.5, 2.0]]
    values = importer.files[Path(interior["density"]["file"]).name]
    assert values.shape == (63, 16, 32)  # ceil(4 · 0.5 · 1.99⁴ · extent): 32, 16, 63 along x, y, z
    assert not any("capped" in w for w in importer.warnings)
    assert any('"float scale" not imported' in w for w in importer.warnings)
    assert any('"rgb Le" not imported' in w for w in importer.warnings)


@pytest.mark.parametrize("kind", ["cloud", "uniformgrid"])
def test_a_box_given_from_other_corners_is_the_same_box(tmp_path, kind):
    """pbrt-v4 makes a medium's box of p0 and p1's smallest and largest coordinates: corners given the other way
    round give the same grid, not a mirrored one (a cloud's values and a uniformgrid's box alike)."""
    grid = ' "float density" [0 1 2 3 4 5 6 7] "integer nx" 2 "integer ny" 2 "integer nz" 2' if kind != "cloud" else ""
    tables, values = [], []
    for corners in ('"point3 p0" [0 0 0] "point3 p1" [1 0.5 2]', '"point3 p0" [1 0.5 0] "point3 p1" [0 0 2]'):
        text = CLOUDS.format(extra=f'{corners} "float frequency" 0.5{grid}')
        if kind != "cloud":
            text = text.replace('"cloud"', f'"{kind}"').replace('"float density" 2', "")
        (tmp_path / "box.pbrt").write_text(text)
        data, importer = pbrt_scene_data(tmp_path / "box.pbrt", tmp_path / "box.toml")
        density = data["shapes"][0]["interior"]["density"]
        tables.append(density)
        values.append(importer.files.get(Path(density.get("file", "none")).name))
    assert tables[0]["box"] == tables[1]["box"] == [[0.0, 0.0, 0.0], [1.0, 0.5, 2.0]]
    if kind == "cloud":
        np.testing.assert_array_equal(values[0], values[1])


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        ('"point3 p0" [0 0 0] "point3 p1" [1 1 0]', "box p0 [0.0, 0.0, 0.0] – p1 [1.0, 1.0, 0.0] is empty"),
    ],
)
def test_a_bad_cloud_is_one_line_naming_the_file(tmp_path, extra, message):
    path = _write(tmp_path, extra)
    with pytest.raises(SpectraceError) as caught:
        pbrt_scene_data(path, tmp_path / "clouds.toml")
    assert message in caught.value.message and "clouds.pbrt:8" in str(caught.value.where)
    assert "\n" not in str(caught.value)


def _trilinear(grid_values, unit):
    """scipy's linear interpolation of voxel centres, clamped at the faces (the grids' lookup), 0 outside."""
    nz, ny, nx = grid_values.shape
    coords = np.stack([unit[:, 2] * nz - 0.5, unit[:, 1] * ny - 0.5, unit[:, 0] * nx - 0.5])
    values = ndimage.map_coordinates(grid_values.astype(np.float64), coords, order=1, mode="nearest")
    return np.where(np.all((unit >= 0) & (unit <= 1), axis=1), values, 0.0)


# Rays in the medium's space (origin, direction): along x low in the cloud, diagonally through it, and up through
# the fall-off with height.
RAYS = [
    ((-0.5, 0.55, 0.5), (1.0, 0.0, 0.0)),
    ((-0.2, -0.1, -0.3), (1.0, 0.9, 1.1)),
    ((0.3, -0.5, 0.6), (0.1, 1.0, -0.2)),
]


@pytest.mark.slow
def test_transmittance_through_the_imported_cloud_is_the_formulas(tmp_path, kernel_runner):
    """Ratio tracking through the imported grid on the device gives exp(−σt ∫ρ dt) of the formula ρ (a quadrature
    of 20001 points a ray), within 4 standard errors plus what the tabulation changes: the quadrature of
    |ρ − trilinear(grid)|, itself bounded: at 4 samples a cell of the finest noise (the warp's, 9.95 cells a unit
    here) the grid is within 2.5% of the full density on average along each chord (0.5% to 1.6% measured; the
    clamps' kinks and the height terms' do not scale with the noise)."""
    path = _write(tmp_path, '"float frequency" 0.5 "float wispiness" 0.5')
    scene = load_pbrt_scene(path)
    _, importer = pbrt_scene_data(path, tmp_path / "clouds.toml")
    grid = scene.shapes[0].interior.density
    world_from_medium = importer.world @ np.linalg.inv(MEDIUM_FROM_WORLD)
    scale = 0.2  # 0.2 × the scene's σt of about 10 a unit keeps the transmittance well away from 0
    sigma_a, sigma_s = Spectrum.constant(0.01 * scale), Spectrum.constant(10.0 * scale)
    spectra, medium = _device_medium(Medium(sigma_a, sigma_s, density=grid))
    runner = kernel_runner("testing/medium_grid_sampling.cl")
    sigma_t = 10.01 * scale
    for index, (origin, direction) in enumerate(RAYS):
        origin, direction = np.asarray(origin, float), np.asarray(direction, float) / np.linalg.norm(direction)
        length = 3.0
        t = np.linspace(0.0, length, 20_001)
        points = origin + t[:, None] * direction
        inside = np.all((points >= 0) & (points <= 1), axis=1)
        formula = np.where(inside, reference_density(points, density=2.0, wispiness=0.5, frequency=0.5), 0.0)
        unit = (np.c_[points, np.ones(len(t))] @ (np.linalg.inv(grid.to_world) @ world_from_medium).T)[:, :3]
        tabulated = _trilinear(grid.density, unit)
        depth = np.trapezoid(formula, t)
        tabulation = np.trapezoid(np.abs(formula - tabulated), t)
        chord = np.count_nonzero(inside) * (t[1] - t[0])
        assert depth > 0.1 and tabulation < 0.025 * chord, (index, depth, tabulation, chord)
        world_origin = (world_from_medium @ [*origin, 1.0])[:3]
        world_direction = world_from_medium[:3, :3] @ direction
        n = 40_000
        out = np.empty((n, 4), np.float32)
        args = [
            runner.buffer(spectra),
            runner.buffer(medium),
            LANES_NM.astype(np.float32),
            np.array([*world_origin, 0.0], np.float32),
            np.array([*world_direction, 0.0], np.float32),
            np.float32(length),
            np.uint32(21 + index),
            runner.buffer(out, True),
        ]
        runner.run("grid_transmittances", n, args, {7: out})
        expected = np.exp(-sigma_t * depth)
        mean, se = mean_and_standard_error(out)
        slack = expected * (np.exp(sigma_t * tabulation) - 1.0)
        assert_within_standard_errors(mean, np.full(4, expected), se, slack=slack, what=f"ray {index}")
