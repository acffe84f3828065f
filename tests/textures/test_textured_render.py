"""Textured surfaces rendered, against colour-science: a quad seen head-on under a uniform environment of radiance
1 reflects L(λ) = R(λ) at each point (one bounce, no other surface), so each texel's region of the film has the XYZ
of its reflectance spectrum, computed here with colour-science's sd_to_XYZ, within 4 standard errors of the pixel
estimates. The furnace: a white texture reflects all of the environment, however often the path bounces."""

import colour
import numpy as np
import OpenEXR
import pytest

import spectrace
from spectrace.engine.renderer import Renderer
from spectrace.io.exr import spectral_channel_name
from spectrace.scene.model import Camera, Scene
from spectrace.spectral.uplift import uplift_reflectance
from stats_toolkit import assert_within_standard_errors, mean_and_standard_error

SIDE = 16  # film pixels; the quad fills the film, each 2 × 2 texture quadrant a SIDE/2 square of it
GRID = np.arange(360.0, 831.0)


def _xyz_colour_science(reflectance_on_grid: np.ndarray) -> np.ndarray:
    """XYZ/100 of a reflectance under an equal-energy illuminant of 1 (the environment's radiance), CIE 1931 2°,
    integrated on the 1 nm grid: the film's ∫ L cmf dλ / ∫ ȳ dλ."""
    shape = colour.SpectralShape(360, 830, 1)
    sd = colour.SpectralDistribution(dict(zip(GRID, reflectance_on_grid)))
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"].copy().align(shape)
    illuminant = colour.SpectralDistribution(dict(zip(GRID, np.ones_like(GRID))))
    return colour.sd_to_XYZ(sd, cmfs, illuminant, method="Integration") / 100.0


def _quad_scene(material, max_depth: int = 2, spp: int = 64) -> Scene:
    # The rectangle shows its texture upright to a viewer on +z (u right, v down); a 30° view from z = 3 sees only
    # the quad, so every pixel is a point of it.
    quad = spectrace.shape("rectangle", material)
    camera = Camera(origin=(0.0, 0.0, 3.0), target=(0.0, 0.0, 0.0), fov_degrees=30.0)
    return Scene(
        camera=camera,
        width=SIDE,
        height=SIDE,
        shapes=[quad],
        lights=[spectrace.constant_environment(1.0)],
        max_depth=max_depth,
        spp=spp,
        seed=11,
        sampler="independent",
    )


def _quadrants(xyz: np.ndarray) -> dict[tuple[int, int], np.ndarray]:
    """(row, column) of the 2 × 2 texture -> the XYZ of the pixels well inside its region (2 pixels from its edges)."""
    half = SIDE // 2
    return {
        (r, c): xyz[r * half + 2 : (r + 1) * half - 2, c * half + 2 : (c + 1) * half - 2].reshape(-1, 3)
        for r in range(2)
        for c in range(2)
    }


def _sigmoid_spectrum(rgb) -> np.ndarray:
    c0, c1, c2 = uplift_reflectance(rgb)[1]
    x = (c0 * GRID + c1) * GRID + c2
    return 0.5 + x / (2.0 * np.sqrt(1.0 + x * x))


RGB_TEXELS = np.array([[[0.8, 0.1, 0.1], [0.1, 0.7, 0.2]], [[0.15, 0.2, 0.85], [0.9, 0.85, 0.3]]])


def _fresnel_dielectric(cos_i: np.ndarray, eta: float) -> np.ndarray:
    """Unpolarised Fresnel reflectance of a smooth interface of relative index eta (Born & Wolf)."""
    sin_t = np.sqrt(1.0 - cos_i**2) / eta
    cos_t = np.sqrt(1.0 - sin_t**2)
    rs = (cos_i - eta * cos_t) / (cos_i + eta * cos_t)
    rp = (eta * cos_i - cos_t) / (eta * cos_i + cos_t)
    return 0.5 * (rs**2 + rp**2)


def _view_cosines() -> np.ndarray:
    """cos θ between each pixel centre's ray and the quad's normal (+z), for the 30° camera on the axis."""
    tan_half = np.tan(np.radians(15.0))
    x = (2.0 * (np.arange(SIDE) + 0.5) / SIDE - 1.0) * tan_half
    xx, yy = np.meshgrid(x, x)
    return 1.0 / np.sqrt(1.0 + xx**2 + yy**2)


@pytest.mark.parametrize("material", ["diffuse", "plastic"])
def test_rgb_texture_regions_render_their_uplifted_spectra(device, material):
    """Each texel's region has the XYZ colour-science computes for that texel's uplifted spectrum ρ(λ). Smooth
    plastic under a uniform environment reflects F(θo) + (1 − F(θo)) ρ(λ) (its coat's Fresnel term plus the base:
    docs/materials.md), so there each pixel's expectation mixes the white and the texel's XYZ by F at its angle."""
    texture = spectrace.bitmap(RGB_TEXELS, filter="nearest")
    made = spectrace.diffuse(texture) if material == "diffuse" else spectrace.plastic(texture, ior=1.5)
    image = Renderer(_quad_scene(made), device).render()
    fresnel = _fresnel_dielectric(_view_cosines(), 1.5) if material == "plastic" else np.zeros((SIDE, SIDE))
    white = _xyz_colour_science(np.ones_like(GRID))
    half = SIDE // 2
    for r in range(2):
        for c in range(2):
            ours = _xyz_colour_science(_sigmoid_spectrum(RGB_TEXELS[r, c]))
            f = fresnel[..., None]
            expected = f * white + (1.0 - f) * ours
            region = (slice(r * half + 2, (r + 1) * half - 2), slice(c * half + 2, (c + 1) * half - 2))
            mean, error = mean_and_standard_error((image.xyz[region] - expected[region]).reshape(-1, 3))
            assert_within_standard_errors(mean, 0.0, error, slack=2e-4, what=(r, c))


@pytest.mark.parametrize("composite", ["scale", "mix"])
def test_scale_and_mix_regions_render_their_composed_spectra(device, composite):
    """A diffuse quad whose reflectance is the RGB texture scaled by a grey texture of factors (0.2, 0.9; 0.5, 1),
    or mixed with a constant 0.3 by the amount 0.25: each region's XYZ is colour-science's of tex · factor, or of
    0.75 ρ_texel + 0.25 · 0.3 (pbrt-v4's scale and mix)."""
    texture = spectrace.bitmap(RGB_TEXELS, filter="nearest")
    factors = np.array([[0.2, 0.9], [0.5, 1.0]])
    if composite == "scale":
        made = spectrace.scale_texture(texture, spectrace.bitmap(factors, raw=True, filter="nearest"))
    else:
        made = spectrace.mix_texture(texture, 0.3, 0.25)
    image = Renderer(_quad_scene(spectrace.diffuse(made)), device).render()
    half = SIDE // 2
    for r in range(2):
        for c in range(2):
            texel = _sigmoid_spectrum(RGB_TEXELS[r, c])
            spectrum = factors[r, c] * texel if composite == "scale" else 0.75 * texel + 0.25 * 0.3
            region = image.xyz[r * half + 2 : (r + 1) * half - 2, c * half + 2 : (c + 1) * half - 2].reshape(-1, 3)
            mean, error = mean_and_standard_error(region - _xyz_colour_science(spectrum))
            assert_within_standard_errors(mean, 0.0, error, slack=2e-4, what=(r, c))


@pytest.mark.parametrize("material", ["diffuse", "plastic"])
def test_white_texture_furnace(device, material):
    """A white (1, 1, 1) texture, bilinear, on diffuse or smooth white plastic: every path returns the environment's
    radiance 1 at every wavelength, so the film has the XYZ of an equal-energy spectrum of 1."""
    texture = spectrace.bitmap(np.ones((4, 4, 3)), filter="bilinear")
    made = spectrace.diffuse(texture) if material == "diffuse" else spectrace.plastic(texture, ior=1.5)
    image = Renderer(_quad_scene(made, max_depth=-1, spp=16), device).render()
    mean, error = mean_and_standard_error(image.xyz.reshape(-1, 3))
    assert_within_standard_errors(mean, _xyz_colour_science(np.ones_like(GRID)), error, slack=2e-4)


def _write_spectral_exr(path, wavelengths, texels):
    channels = {
        spectral_channel_name(nm): np.ascontiguousarray(texels[..., i], np.float32) for i, nm in enumerate(wavelengths)
    }
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    with OpenEXR.File(header, channels) as exr:
        exr.write(str(path))


def test_spectral_exr_regions_render_their_spectra(device, tmp_path):
    """A 2 × 2 spectral OpenEXR of known spectra (bands every 10 nm): each region renders the XYZ colour-science
    computes for its spectrum, linear between the band centres as docs/textures.md defines it; among them a narrow
    band no smooth RGB uplift can make."""
    wavelengths = np.arange(360.0, 831.0, 10.0)
    texels = np.empty((2, 2, len(wavelengths)))
    texels[0, 0] = 0.1 + 0.8 * (wavelengths > 600)  # a red step
    texels[0, 1] = np.exp(-0.5 * ((wavelengths - 530.0) / 20.0) ** 2)  # a narrow green band
    texels[1, 0] = np.linspace(0.9, 0.05, len(wavelengths))  # a blue ramp
    texels[1, 1] = 0.5
    path = tmp_path / "bands.exr"
    _write_spectral_exr(path, wavelengths, texels)
    texture = spectrace.spectral_texture(path, filter="nearest")
    image = Renderer(_quad_scene(spectrace.diffuse(texture)), device).render()
    for (r, c), pixels in _quadrants(image.xyz).items():
        mean, error = mean_and_standard_error(pixels)
        expected = _xyz_colour_science(np.interp(GRID, wavelengths, texels[r, c]))
        assert_within_standard_errors(mean, expected, error, slack=2e-4, what=(r, c))


def test_trilinear_filtering_follows_the_camera_footprint(device):
    """A 128 × 128 checkerboard of single black and white texels on a quad about 16 pixels wide: each pixel spans 8
    texels, so trilinear filtering reads the pyramid's levels 3 to 4, where the checker has averaged to grey 0.5
    (linear RGB); bilinear reads level 0, where each sample lands on black, white or between. Trilinear pixels
    have grey's XYZ and scatter only by the wavelength sampling; bilinear ones scatter far more (with the Sobol
    sampler's stratified wavelengths, trilinear's pixel variance measured 0.10 of bilinear's; the test allows 0.5;
    without the footprint the two renders are the same). Each pixel's samples are scrambled independently of the
    others', so the pixels are independent replicates."""
    checker = (np.indices((128, 128)).sum(axis=0) % 2).astype(float)
    camera = Camera(origin=(0.0, 0.0, 7.5), target=(0.0, 0.0, 0.0), fov_degrees=30.0)
    pixels = {}
    for filter in ("trilinear", "bilinear"):
        material = spectrace.diffuse(spectrace.bitmap(checker, filter=filter))
        scene = Scene(
            camera=camera,
            width=32,
            height=32,
            shapes=[spectrace.shape("rectangle", material)],
            lights=[spectrace.constant_environment(1.0)],
            max_depth=2,
            spp=4,
            seed=11,
        )
        pixels[filter] = Renderer(scene, device).render().xyz[10:22, 10:22].reshape(-1, 3)
    grey = _xyz_colour_science(_sigmoid_spectrum((0.5, 0.5, 0.5)))
    mean, error = mean_and_standard_error(pixels["trilinear"])
    assert_within_standard_errors(mean, grey, error, slack=2e-4)
    assert pixels["trilinear"][:, 1].var() < 0.5 * pixels["bilinear"][:, 1].var()
