"""pbrt-v4's procedural textures (kernels/noise.cl): Perlin noise and the polka dots built on it, looked up on the
device against a numpy reference written here from the book's description (Pharr, Jakob & Humphreys, 4th ed.,
10.6.1 "Perlin Noise", 10.6.4 "Polka Dots") and Perlin's 2002 paper, not from spectrace's kernel; the dots' covered
area against its closed form; and the pbrt-v4 import of a `dots` texture."""

import numpy as np
import pytest
from tests.textures.lookup import HARNESS, SIDE, TextureHarness, render_quad

from spectrace.interop.pbrt import import_pbrt, pbrt_scene_data
from spectrace.spectral.spectrum import Spectrum
from spectrace.textures import dots

# Ken Perlin's permutation of 0..255, from "Improving Noise" (2002).
PERMUTATION = np.array(
    [151, 160, 137, 91, 90, 15, 131, 13, 201, 95, 96, 53, 194, 233, 7, 225, 140, 36, 103, 30, 69, 142, 8, 99, 37,
     240, 21, 10, 23, 190, 6, 148, 247, 120, 234, 75, 0, 26, 197, 62, 94, 252, 219, 203, 117, 35, 11, 32, 57, 177,
     33, 88, 237, 149, 56, 87, 174, 20, 125, 136, 171, 168, 68, 175, 74, 165, 71, 134, 139, 48, 27, 166, 77, 146,
     158, 231, 83, 111, 229, 122, 60, 211, 133, 230, 220, 105, 92, 41, 55, 46, 245, 40, 244, 102, 143, 54, 65, 25,
     63, 161, 1, 216, 80, 73, 209, 76, 132, 187, 208, 89, 18, 169, 200, 196, 135, 130, 116, 188, 159, 86, 164, 100,
     109, 198, 173, 186, 3, 64, 52, 217, 226, 250, 124, 123, 5, 202, 38, 147, 118, 126, 255, 82, 85, 212, 207, 206,
     59, 227, 47, 16, 58, 17, 182, 189, 28, 42, 223, 183, 170, 213, 119, 248, 152, 2, 44, 154, 163, 70, 221, 153,
     101, 155, 167, 43, 172, 9, 129, 22, 39, 253, 19, 98, 108, 110, 79, 113, 224, 232, 178, 185, 112, 104, 218, 246,
     97, 228, 251, 34, 242, 193, 238, 210, 144, 12, 191, 179, 162, 241, 81, 51, 145, 235, 249, 14, 239, 107, 49,
     192, 214, 31, 181, 199, 106, 157, 184, 84, 204, 176, 115, 121, 50, 45, 127, 4, 150, 254, 138, 236, 205, 93,
     222, 114, 67, 29, 24, 72, 243, 141, 128, 195, 78, 66, 215, 61, 156, 180]
)  # fmt: skip
# The twelve directions to the midpoints of a cube's edges (Perlin 2002), and to fill 16 codes pbrt-v4's four
# repeats: codes 12 and 13 again (1, 1, 0) and (−1, 1, 0), 14 and 15 again (0, 1, −1) and (0, −1, −1).
GRADIENTS = np.array(
    [[1, 1, 0], [-1, 1, 0], [1, -1, 0], [-1, -1, 0], [1, 0, 1], [-1, 0, 1], [1, 0, -1], [-1, 0, -1],
     [0, 1, 1], [0, -1, 1], [0, 1, -1], [0, -1, -1], [1, 1, 0], [-1, 1, 0], [0, 1, -1], [0, -1, -1]],
    float,
)  # fmt: skip
RADIUS, MAX_SHIFT = 0.35, 0.15


def noise(p: np.ndarray) -> np.ndarray:
    """Perlin noise at points p (N, 3): the lattice corners' gradients (a hash through the permutation, coordinates
    wrapped to 256) dotted with the offsets to p, blended trilinearly with the fade 6t⁵ − 15t⁴ + 10t³."""
    cell = np.floor(p)
    d = p - cell
    i = cell.astype(np.int64)
    fade = d * d * d * (d * (d * 6 - 15) + 10)
    total = np.zeros(len(p))
    for corner in np.ndindex(2, 2, 2):
        c = np.array(corner)
        x, y, z = ((i + c) & 255).T
        code = PERMUTATION[(PERMUTATION[(PERMUTATION[x] + y) & 255] + z) & 255] & 15
        ramp = np.sum(GRADIENTS[code] * (d - c), axis=1)
        total += ramp * np.prod(np.where(c == 1, fade, 1 - fade), axis=1)
    return total


def noise2(x, y) -> np.ndarray:
    x, y = np.broadcast_arrays(np.asarray(x, float), np.asarray(y, float))
    return noise(np.stack([x, y, np.full(x.shape, 0.5)], axis=1))


def dots_reference(st: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Whether each point lies on a dot, and how far it is from deciding otherwise (from a cell's edge, the squared
    distance's margin to r²): unit cells centred on the integers, a dot where the noise at the centre + ½ is > 0,
    its centre shifted by 0.15 × the noise at two other points of the cell."""
    cell = np.floor(st + 0.5)
    gate = noise2(cell[:, 0] + 0.5, cell[:, 1] + 0.5)
    centre = cell + MAX_SHIFT * np.stack(
        [noise2(cell[:, 0] + 1.5, cell[:, 1] + 2.8), noise2(cell[:, 0] + 4.5, cell[:, 1] + 9.8)], axis=1
    )
    distance2 = np.sum((st - centre) ** 2, axis=1)
    on = (gate > 0) & (distance2 < RADIUS**2)
    # At a cell's centre + ½ every corner's offset is ±½, so the gate is a multiple of 1/8, exact in float32 too
    # (and often exactly 0: no dot): only the cell's edges and the dot's rim are uncertain.
    edge = np.min(np.abs(st + 0.5 - np.round(st + 0.5)), axis=1)
    return on, np.where(gate > 0, np.minimum(edge, np.abs(distance2 - RADIUS**2)), edge)


@pytest.fixture(scope="module")
def runner(kernel_runner):
    return kernel_runner(HARNESS)


def test_the_reference_noise_has_perlins_properties():
    """Zero at every lattice point, within [-1, 1], continuous across cell faces, and at a cell's centre the mean of
    its corners' ±½ ramps (the fade is ½ there)."""
    rng = np.random.default_rng(1)
    lattice = rng.integers(-300, 300, (500, 3)).astype(float)
    np.testing.assert_allclose(noise(lattice), 0.0, atol=1e-12)
    p = rng.uniform(-50, 50, (20000, 3))
    values = noise(p)
    assert np.all(np.abs(values) <= 1.0) and values.std() > 0.1
    face = p.copy()
    face[:, 0] = np.floor(p[:, 0])
    np.testing.assert_allclose(noise(face - [1e-9, 0, 0]), noise(face + [1e-9, 0, 0]), atol=1e-7)
    centres = noise(lattice + 0.5)
    np.testing.assert_array_equal(centres * 8, np.round(centres * 8))


@pytest.mark.parametrize("uv_scale, uv_offset", [(1.0, (0.0, 0.0)), (3.0, (0.25, -7.5))])
def test_dots_match_the_reference(runner, uv_scale, uv_offset):
    """Side `inside` exactly where the reference puts a dot, at points far from the origin too (the lattice wraps
    at 256): a spectrum on the dots, an RGB-free constant elsewhere, at four wavelengths."""
    texture = dots.make(Spectrum.constant(0.75), Spectrum.constant(0.25), uv_scale=uv_scale, uv_offset=uv_offset)
    rng = np.random.default_rng(5)
    uv = np.concatenate([rng.uniform(-6, 6, (4000, 2)), rng.uniform(200, 330, (1000, 2))])
    got = TextureHarness(runner, [(texture, "spectrum")]).lookup(0, uv)
    st = uv * uv_scale + np.asarray(uv_offset)
    on, margin = dots_reference(st)
    clear = margin > 1e-4  # float32 on the device: a point this close to an edge may land either side
    assert clear.mean() > 0.99 and 0.05 < on.mean() < 0.6
    np.testing.assert_array_equal(got[clear], np.where(on[clear], 0.75, 0.25)[:, None] * np.ones(4))


def test_dots_cover_their_closed_form_area(runner):
    """A cell with a dot is covered over π 0.35² of its unit area (the dot, shifted by at most 0.15, stays inside):
    the fraction of random points on dots is that times the fraction of cells the noise gives a dot (counted from
    the noise here), within 4 standard errors."""
    texture = dots.make(1.0, 0.0)
    rng = np.random.default_rng(11)
    cells = 40
    uv = rng.uniform(-0.5, cells - 0.5, (40000, 2))
    got = TextureHarness(runner, [(texture, "float")]).lookup(0, uv)[:, 0]
    i, j = np.meshgrid(np.arange(cells), np.arange(cells))
    with_dot = np.mean(noise2(i.ravel() + 0.5, j.ravel() + 0.5) > 0)
    expected = with_dot * np.pi * RADIUS**2
    error = np.sqrt(expected * (1 - expected) / len(uv))
    assert abs(got.mean() - expected) < 4 * error, (got.mean(), expected, error)


def test_pbrt_dots_import(tmp_path):
    """pbrt-v4's `dots` with its inside and outside spectra and uscale/vscale: a dots texture whose st is pbrt's
    (s = us u, t = vs v with the file's v up: t = vs (1 − v) in spectrace's v down)."""
    header = 'LookAt 0 0 5  0 0 0  0 1 0\nCamera "perspective" "float fov" 30\nFilm "rgb" "integer xresolution" 8'
    header += ' "integer yresolution" 6\nWorldBegin\n'
    body = 'Texture "d" "spectrum" "dots" "float uscale" 4 "float vscale" 2 "rgb inside" [0.8 0.1 0.1]\n'
    body += 'Material "diffuse" "texture reflectance" "d"\n'
    body += 'Shape "trianglemesh" "point3 P" [-1 -1 0  1 -1 0  1 1 0  -1 1 0] "integer indices" [0 1 2 0 2 3]\n'
    body += '  "point2 uv" [0 0  1 0  1 1  0 1]\n'
    (tmp_path / "scene.pbrt").write_text(header + body)
    toml = tmp_path / "out" / "scene.toml"
    import_pbrt(tmp_path / "scene.pbrt", toml)
    data, _ = pbrt_scene_data(tmp_path / "scene.pbrt", toml)
    (texture,) = data["textures"].values()
    assert texture["type"] == "dots"
    assert texture["uv_scale"] == [4.0, -2.0] and texture["uv_offset"] == [0.0, 2.0]
    assert texture["outside"] == {"value": 0.0} and "rgb" in str(texture["inside"])


def test_dots_in_a_scene_file(tmp_path):
    """The docs' inline dots, and a named one whose inside is an image texture, resolve to dots textures with their
    placement; a dots side that is a composite is refused in one line naming the key."""
    from scene_text import camera_film
    from spectrace.errors import SpectraceError
    from spectrace.scene import load_scene
    from spectrace.textures.bitmap import BitmapTexture

    (tmp_path / "grey.pfm").write_bytes(b"Pf\n1 1\n-1.0\n" + np.float32(0.5).tobytes())
    body = """
[textures.spots]
type = "dots"
inside = {{ texture = "bitmap", file = "grey.pfm" }}
[materials.polka]
type = "diffuse"
reflectance = {{ texture = "dots", inside = {{ rgb = [0.8, 0.1, 0.1] }}, outside = {{ value = 0.8 }}, uv_scale = 8 }}
[materials.named]
type = "diffuse"
reflectance = {reflectance}
[[shapes]]
type = "rectangle"
material = "polka"
[[shapes]]
type = "rectangle"
material = "named"
"""
    path = tmp_path / "scene.toml"
    path.write_text(camera_film() + body.format(reflectance='{ texture = "spots" }'))
    scene = load_scene(path)
    polka, named = (shape.material.reflectance for shape in scene.shapes)
    assert isinstance(polka, dots.DotsTexture) and polka.placement.uv_scale == (8.0, 8.0)
    np.testing.assert_allclose(polka.outside.values, 0.8)
    assert isinstance(named.inside, BitmapTexture) and named.outside.values.max() == 0.0
    nested = '{ texture = "dots", inside = { texture = "checkerboard" } }'
    path.write_text(camera_film() + body.format(reflectance=nested))
    with pytest.raises(SpectraceError) as refused:
        load_scene(path)
    assert "materials.named.reflectance.inside" in str(refused.value) and "\n" not in str(refused.value)


@pytest.mark.slow  # builds the scene's own kernels
def test_dots_render_where_the_reference_puts_them(device):
    """A diffuse quad of reflectance 0.75 on the dots and 0.25 elsewhere, seen head-on under a uniform environment
    of radiance 1 (one bounce: each point reflects its reflectance, so Y = ρ), box filter: pixels the reference puts
    wholly on a dot average 0.75, wholly off one 0.25, and the image's mean is 0.25 + 0.5 × the covered fraction of
    the view, each within 4 standard errors. The scene's own kernels build the noise in (the feature define)."""
    import spectrace
    from stats_toolkit import assert_within_standard_errors, mean_and_standard_error

    side, scale = SIDE, 10.0
    y = render_quad(spectrace.dots_texture(0.75, 0.25, uv_scale=scale), device)
    # The rectangle's uv: u = (x + 1)/2, v = (1 − y)/2; the view's half width at z = 0 is 3 tan 15°. 8 × 8 points
    # per pixel give each pixel's covered fraction.
    half = 3.0 * np.tan(np.radians(15.0))
    sub = (np.arange(side * 8) + 0.5) / (side * 8)
    x, y_world = np.meshgrid((2 * sub - 1) * half, (1 - 2 * sub) * half)
    st = np.stack([(x.ravel() + 1) / 2, (1 - y_world.ravel()) / 2], axis=1) * scale
    covered = dots_reference(st)[0].reshape(side, 8, side, 8).mean(axis=(1, 3))
    for fraction, value in ((1.0, 0.75), (0.0, 0.25)):
        pixels = y[covered == fraction]
        assert len(pixels) > 50
        mean, error = mean_and_standard_error(pixels)
        assert_within_standard_errors(mean, value, error, slack=1e-4, what=value)
    mean, error = mean_and_standard_error((y - (0.25 + 0.5 * covered)).ravel())
    assert_within_standard_errors(mean, 0.0, error, slack=2e-3, what="image")
