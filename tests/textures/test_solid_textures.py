"""pbrt-v4's solid textures (kernels/texture_solid.cl): fbm, wrinkled, windy and marble looked up on the device at
world-space points against a numpy reference written here from the book's definitions (Pharr, Jakob & Humphreys,
4th ed., 10.6.3 "Noise Idioms and Spectral Synthesis", 10.6.5 "Marble") on the Perlin noise reference of
test_procedural_textures (itself from Perlin 2002); a render whose pixels take the reference's values; the scene
format, the Python API and the pbrt-v4 import."""

import numpy as np
import pytest
from tests.textures.lookup import HARNESS, SIDE, TextureHarness, render_quad
from tests.textures.test_procedural_textures import noise

import spectrace
from spectrace.errors import SpectraceError
from spectrace.interop.pbrt import import_pbrt, pbrt_scene_data

LAMBDAS = (400.0, 500.0, 600.0, 700.0)
# The book's marble colours and their 1.5 scale ("to increase variation among colors").
MARBLE_RGB = np.array(
    [[0.58, 0.58, 0.6], [0.58, 0.58, 0.6], [0.58, 0.58, 0.6], [0.5, 0.5, 0.5], [0.6, 0.59, 0.58],
     [0.58, 0.58, 0.6], [0.58, 0.58, 0.6], [0.2, 0.2, 0.33], [0.58, 0.58, 0.6]]
)  # fmt: skip


def fbm(p: np.ndarray, omega: float, octaves: int) -> np.ndarray:
    """Σ_{i<octaves} ω^i N(λ_i p), λ_i = 1.99^i: all octaves, as at a lookup without a footprint."""
    return sum(omega**i * noise(1.99**i * p) for i in range(octaves))


def turbulence(p: np.ndarray, omega: float, octaves: int) -> np.ndarray:
    """Σ_{i<octaves} ω^i |N(λ_i p)|, plus pbrt-v4's 0.2 ω^octaves for the (partial) octave after the last."""
    return sum(omega**i * np.abs(noise(1.99**i * p)) for i in range(octaves)) + 0.2 * omega**octaves


def windy(p: np.ndarray) -> np.ndarray:
    return np.abs(fbm(0.1 * p, 0.5, 3)) * fbm(p, 0.5, 6)


def marble(p: np.ndarray, omega: float, octaves: int, scale: float, variation: float, colours: np.ndarray):
    """The spline value at each point and how far its segment choice is from a boundary: `colours` (9, 4) the
    colours' values at the four wavelengths; the cubic Bézier segment `first` of the six at t."""
    q = scale * p
    t = 0.5 + 0.5 * np.sin(q[:, 1] + variation * fbm(q, omega, octaves))
    first = np.minimum(np.floor(t * 6).astype(int), 5)
    s = (t * 6 - first)[:, None]
    c = [colours[first + k] for k in range(4)]
    b = (1 - s) ** 3 * c[0] + 3 * (1 - s) ** 2 * s * c[1] + 3 * (1 - s) * s**2 * c[2] + s**3 * c[3]
    return b, np.abs(t * 6 - np.round(t * 6))


@pytest.fixture(scope="module")
def runner(kernel_runner):
    return kernel_runner(HARNESS)


def _points(seed: int) -> np.ndarray:
    """3000 points near the origin, then 500 far from it (the lattice wraps at 256), as float32 holds them."""
    rng = np.random.default_rng(seed)
    p = np.concatenate([rng.uniform(-4, 4, (3000, 3)), rng.uniform(200, 300, (500, 3))])
    return p.astype(np.float32).astype(np.float64)


def _tolerance(n: int) -> np.ndarray:
    """Per point: float32's rounding of the octaves' points (up to 1.99⁷ × 300 ≈ 4·10⁴, a step of 4·10⁻³ there)
    moves a value by up to a few 10⁻⁴ far from the origin; near it, by a few 10⁻⁶."""
    return np.where(np.arange(n) < 3000, 5e-5, 5e-4)[:, None]


@pytest.mark.parametrize("octaves, roughness", [(8, 0.5), (3, 0.8), (1, 0.5)])
def test_fbm_and_wrinkled_match_the_reference(runner, octaves, roughness):
    """fbm and wrinkled (turbulence) at 3500 points, near the origin and far from it (the lattice wraps at 256),
    the same value at every wavelength; the sum of fbm's octaves spreads its values wider than one octave's."""
    textures = [
        spectrace.fbm_texture(octaves=octaves, roughness=roughness),
        spectrace.wrinkled_texture(octaves=octaves, roughness=roughness),
    ]
    harness = TextureHarness(runner, [(texture, "float") for texture in textures])
    p = _points(2)
    for which, reference in ((0, fbm), (1, turbulence)):
        got = harness.lookup_points(which, p)
        expected = reference(p, roughness, octaves)
        assert np.all(np.abs(got - expected[:, None]) <= _tolerance(len(p))), np.abs(got - expected[:, None]).max()
    assert np.std(fbm(p, roughness, octaves)) > 0.15


def test_windy_matches_the_reference(runner):
    p = _points(3)
    got = TextureHarness(runner, [(spectrace.windy_texture(), "float")]).lookup_points(0, p)
    assert np.all(np.abs(got - windy(p)[:, None]) <= _tolerance(len(p)))


def test_a_transform_places_the_texture(runner):
    """The texture moves with its transform: at a point of the scene it takes the value the reference has at the
    point taken back through the transform (scaled by 2, turned 30° about z, moved by (1, −2, 0.5))."""
    steps = [{"scale": 2.0}, {"rotate": {"axis": [0, 0, 1], "angle": 30.0}}, {"translate": [1.0, -2.0, 0.5]}]
    texture = spectrace.fbm_texture(octaves=5, transform=steps)
    p = _points(4)[:2000]
    got = TextureHarness(runner, [(texture, "float")]).lookup_points(0, p)[:, 0]
    angle = np.radians(30.0)
    turn = np.array([[np.cos(angle), -np.sin(angle), 0], [np.sin(angle), np.cos(angle), 0], [0, 0, 1]])
    back = ((p - [1.0, -2.0, 0.5]) @ turn) / 2.0  # (turnᵀ (p − t)) / 2, row vectors
    np.testing.assert_allclose(got, fbm(back, 0.5, 5), atol=1e-4)


@pytest.mark.parametrize("scale, variation", [(1.0, 0.2), (3.0, 1.5)])
def test_marble_matches_the_reference(runner, scale, variation):
    """Marble's spline of the book's nine colours × 1.5, each uplifted as any sRGB reflectance is, at four
    wavelengths; points within 1e-4 of a segment boundary (where the spline jumps between segments) left out."""
    from spectrace.spectral.spectrum_input import reflectance

    texture = spectrace.marble_texture(octaves=6, scale=scale, variation=variation)
    p = _points(5)
    got = TextureHarness(runner, [(texture, "spectrum")]).lookup_points(0, p, LAMBDAS)
    at = np.array(LAMBDAS, int) - 360  # the spectra's 1 nm grid from 360 nm
    colours = np.array([reflectance(tuple(1.5 * c), "colour").values[at] for c in MARBLE_RGB])
    expected, margin = marble(p, 0.5, 6, scale, variation, colours)
    # float32's rounding (relative 6·10⁻⁸ per product, a few products deep) moves the point by about 10⁻⁶ of itself,
    # which the steep spline of a large variation turns into up to 10⁻³: the tolerance is the reference's own change
    # for such a move, three times over.
    moved = [np.abs(marble(p * (1 + e), 0.5, 6, scale, variation, colours)[0] - expected) for e in (1e-6, -1e-6)]
    tolerance = 1e-5 + 3 * np.maximum(*moved)
    clear = margin > 1e-4
    assert clear.mean() > 0.99 and np.median(tolerance) < 1e-4
    assert np.all(np.abs(got - expected)[clear] <= tolerance[clear])
    assert got.min() >= 0.0 and got.max() <= 1.0 and np.ptp(got[:, 0]) > 0.2


def test_a_mix_holds_a_noise_amount_to_zero_and_one(runner):
    """A mix texture whose amount is fbm (often below 0) or wrinkled of ω 0.8 (often above 1) blends by the amount
    held to [0, 1], as pbrt-v4's mix material holds it."""
    amounts = [
        (spectrace.fbm_texture(octaves=4), fbm(_points(6), 0.5, 4)),
        (spectrace.wrinkled_texture(octaves=4, roughness=0.8), turbulence(_points(6), 0.8, 4)),
    ]
    harness = TextureHarness(runner, [(spectrace.mix_texture(0.2, 0.8, a), "spectrum") for a, _ in amounts])
    for which, (_, values) in enumerate(amounts):
        assert (values < 0).mean() > 0.1 or (values > 1).mean() > 0.1
        got = harness.lookup_points(which, _points(6))
        expected = 0.2 + 0.6 * np.clip(values, 0.0, 1.0)
        assert np.all(np.abs(got - expected[:, None]) <= _tolerance(len(values)))


def test_scene_file_api_and_refusals(tmp_path):
    """The docs' scene keys resolve to the textures; an fbm as a reflectance (negative values) and a marble as a
    roughness are refused in one line naming the key; the API checks its numbers."""
    from scene_text import camera_film
    from spectrace.scene import load_scene
    from spectrace.textures.fbm import FbmTexture
    from spectrace.textures.marble import MarbleTexture

    body = """
[textures.veins]
type = "marble"
scale = 4.0
variation = 0.5
transform = [{{ translate = [0, 1, 0] }}]
[materials.stone]
type = "diffuse"
reflectance = {{ texture = "veins" }}
[materials.blend]
type = "diffuse"
reflectance = {reflectance}
[[shapes]]
type = "rectangle"
material = "stone"
[[shapes]]
type = "rectangle"
material = "blend"
"""
    path = tmp_path / "scene.toml"
    mixed = '{ texture = "mix", tex1 = { value = 0.1 }, tex2 = { value = 0.9 }, '
    mixed += 'amount = { texture = "fbm", octaves = 3 } }'
    path.write_text(camera_film() + body.format(reflectance=mixed))
    scene = load_scene(path)
    stone, blend = (shape.material.reflectance for shape in scene.shapes)
    assert isinstance(stone, MarbleTexture) and stone.scale == 4.0 and stone.variation == 0.5
    np.testing.assert_allclose(stone.to_texture[:3, 3], [0.0, -4.0, 0.0])  # 4 (p − (0, 1, 0))
    assert isinstance(blend.amount, FbmTexture) and blend.amount.octaves == 3
    path.write_text(camera_film() + body.format(reflectance='{ texture = "fbm" }'))
    with pytest.raises(SpectraceError) as refused:
        load_scene(path)
    assert "materials.blend.reflectance" in str(refused.value) and "\n" not in str(refused.value)
    with pytest.raises(SpectraceError):
        spectrace.diffuse(spectrace.fbm_texture())
    with pytest.raises(SpectraceError):
        spectrace.marble_texture(scale=0.0)
    with pytest.raises(SpectraceError):
        spectrace.fbm_texture(octaves=0)


def test_pbrt_solid_textures_import(tmp_path):
    """pbrt-v4's marble (a spectrum texture) with its parameters and the transform in effect where it was
    declared; a mix material whose amount is a wrinkled float texture; windy's defaults."""
    header = 'LookAt 0 0 5  0 0 0  0 1 0\nCamera "perspective" "float fov" 30\nFilm "rgb" "integer xresolution" 8'
    header += ' "integer yresolution" 6\nWorldBegin\n'
    body = "AttributeBegin\nTranslate 0 2 0\nScale 3 3 3\n"
    body += 'Texture "m" "spectrum" "marble" "float scale" 2 "float variation" 0.4 "integer octaves" 5\n'
    body += "AttributeEnd\n"
    body += 'Texture "w" "float" "wrinkled" "float roughness" 0.6\n'
    body += 'MakeNamedMaterial "a" "string type" "diffuse" "texture reflectance" "m"\n'
    body += 'MakeNamedMaterial "b" "string type" "conductor"\n'
    body += 'Material "mix" "string materials" ["a" "b"] "texture amount" "w"\n'
    body += 'Shape "trianglemesh" "point3 P" [-1 -1 0  1 -1 0  1 1 0  -1 1 0] "integer indices" [0 1 2 0 2 3]\n'
    (tmp_path / "scene.pbrt").write_text(header + body)
    toml = tmp_path / "out" / "scene.toml"
    import_pbrt(tmp_path / "scene.pbrt", toml)
    data, _ = pbrt_scene_data(tmp_path / "scene.pbrt", toml)
    (veins,) = data["textures"].values()
    assert (veins["scale"], veins["variation"], veins["octaves"], veins["roughness"]) == (2.0, 0.4, 5, 0.5)
    placed = [[3, 0, 0, 0], [0, 3, 0, 2], [0, 0, 3, 0], [0, 0, 0, 1]]  # Translate 0 2 0, then Scale 3
    np.testing.assert_allclose(veins["transform"][0]["matrix"], placed)
    (mix,) = [m for m in data["materials"].values() if m["type"] == "mix"]
    assert mix["amount"]["texture"] == "wrinkled" and mix["amount"]["roughness"] == 0.6
    assert "transform" not in mix["amount"]
    from spectrace.scene import load_scene

    load_scene(toml)  # the table resolves


def _pixel_reference(value) -> np.ndarray:
    """`value` at the quad's points (N, 3) averaged over 8 × 8 points of each pixel."""
    half = 3.0 * np.tan(np.radians(15.0))  # the view's half width at z = 0
    sub = (np.arange(SIDE * 8) + 0.5) / (SIDE * 8)
    x, y = np.meshgrid((2 * sub - 1) * half, (1 - 2 * sub) * half)
    p = np.stack([x.ravel(), y.ravel(), np.zeros(x.size)], axis=1)
    return value(p).reshape(SIDE, 8, SIDE, 8).mean(axis=(1, 3))


def _assert_image_is(y: np.ndarray, expected: np.ndarray, correlation: float = 0.9) -> None:
    """The image minus the reference has mean 0 within 4 standard errors and follows the reference's pattern (a
    texture misplaced or mirrored would correlate about 0)."""
    from stats_toolkit import assert_within_standard_errors, mean_and_standard_error

    assert np.ptp(expected) > 0.1  # the texture varies across the view
    mean, error = mean_and_standard_error((y - expected).ravel())
    assert_within_standard_errors(mean, 0.0, error, slack=2e-3, what="image")
    assert np.corrcoef(y.ravel(), expected.ravel())[0, 1] > correlation


@pytest.mark.slow  # builds the scene's own kernels
def test_a_wrinkled_mix_renders_where_the_reference_puts_it(device):
    """A quad of reflectance 0.2 + 0.6 · clamp(wrinkled(p / 0.25)) (a texture scaled up 4 times)."""
    wrinkled = spectrace.wrinkled_texture(octaves=4, transform=[{"scale": 0.25}])
    y = render_quad(spectrace.mix_texture(0.2, 0.8, wrinkled), device)
    _assert_image_is(y, _pixel_reference(lambda p: 0.2 + 0.6 * np.clip(turbulence(p / 0.25, 0.5, 4), 0.0, 1.0)))


@pytest.mark.slow  # builds the scene's own kernels
def test_marble_renders_the_luminance_of_its_spline(device):
    """A quad of marble (scale 1.5, variation 0.5): Y at a point is the spline of the nine colours' Y (Y is linear in
    the spectrum), each colour's Y its uplifted spectrum weighed by CIE 1931 ȳ from colour-science."""
    colour = pytest.importorskip("colour")
    from spectrace.spectral.spectrum_input import reflectance

    ybar = (
        colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
        .copy()
        .align(colour.SpectralShape(360, 830, 1))
        .values[:, 1]
    )
    luminance = np.array([reflectance(tuple(1.5 * c), "colour").values @ ybar / ybar.sum() for c in MARBLE_RGB])
    assert len(ybar) == 471  # the spectra's 360-830 nm grid
    y = render_quad(spectrace.marble_texture(scale=1.5, variation=0.5), device)
    expected = _pixel_reference(lambda p: marble(p, 0.5, 8, 1.5, 0.5, luminance[:, None])[0][:, 0])
    # 16 samples leave a pixel's Y a noise of about 0.05 (the wavelengths drawn) against the pattern's 0.085: a
    # correlation of about 0.85 is expected.
    _assert_image_is(y, expected, correlation=0.7)
