"""Textures on every reflectance-like spectrum, on roughness and on emission.

- A tint texture multiplies what the untextured material renders: with grey texels (whose uplifted spectra are
  constants c, computed here from the texture's own coefficients) each region of a textured render is c times the
  untextured render of the same paths; a mirror's coloured texels render as colour-science's XYZ of their spectra.
- A roughness texture of two constant halves renders each half as the untextured material of that α does.
- An emission texture seen head-on renders each texel's XYZ: for an RGB texel colour-science's sRGB → XYZ of the
  triple (the D65-based uplift reproduces the colour), for a spectral texel colour-science's XYZ of its spectrum; a
  flux meter around the light measures π × area × the texels' mean radiance (a Lambertian emitter).
- A white tint in a furnace returns the environment exactly.
"""

from dataclasses import replace

import colour
import numpy as np
import pytest

import spectrace
from spectrace.core.parameters import SMOOTH_ALPHA
from spectrace.engine.meters import FluxMeter, measure
from spectrace.engine.renderer import Renderer
from spectrace.engine.scene_buffers import build_scene_buffers
from spectrace.errors import SpectraceError
from spectrace.scene.model import Camera, Scene
from spectrace.spectral.rgb_texture import texture_reflectance_coefficients
from stats_toolkit import assert_within_standard_errors, mean_and_standard_error

SIDE = 16
HALF = SIDE // 2
GRID = np.arange(360.0, 831.0)
GREYS = np.array([[0.2, 0.5], [0.8, 1.0]])


def _xyz_of_spectrum(values_on_grid: np.ndarray) -> np.ndarray:
    """The film's XYZ of a radiance L(λ) on the 1 nm grid (∫ L cmf dλ / ∫ ȳ dλ, CIE 1931 2°), by colour-science."""
    shape = colour.SpectralShape(360, 830, 1)
    sd = colour.SpectralDistribution(dict(zip(GRID, values_on_grid)))
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"].copy().align(shape)
    ones = colour.SpectralDistribution(dict(zip(GRID, np.ones_like(GRID))))
    return colour.sd_to_XYZ(sd, cmfs, ones, method="Integration") / 100.0


def _sigmoid_spectrum(rgb) -> np.ndarray:
    """The spectrum of a texel of colour `rgb`, from the coefficients a texture stores for it."""
    c0, c1, c2 = texture_reflectance_coefficients(np.asarray(rgb, np.float64).reshape(1, 1, 3))[0, 0]
    x = (c0 * GRID + c1) * GRID + c2
    return 0.5 + x / (2.0 * np.sqrt(1.0 + x * x))


def _quad_scene(material=None, emitter=None, lights=None, max_depth=2, spp=32, seed=11) -> Scene:
    """A unit quad filling a 30° view from z = 3 (texel (r, c) of a 2 × 2 texture covers film quadrant (r, c))."""
    quad = spectrace.shape("rectangle", material or spectrace.diffuse(0.0), emitter=emitter)
    return Scene(
        camera=Camera(origin=(0.0, 0.0, 3.0), target=(0.0, 0.0, 0.0), fov_degrees=30.0),
        width=SIDE,
        height=SIDE,
        shapes=[quad],
        lights=[spectrace.constant_environment(1.0)] if lights is None else lights,
        max_depth=max_depth,
        spp=spp,
        seed=seed,
        sampler="independent",
    )


def _region(r: int, c: int):
    """Film pixels well inside quadrant (r, c) (2 pixels from its edges)."""
    return slice(r * HALF + 2, (r + 1) * HALF - 2), slice(c * HALF + 2, (c + 1) * HALF - 2)


def test_textured_mirror_regions_render_their_texel_spectra(device):
    """A mirror facing the camera under a uniform environment of 1 returns R(λ): each texel's region has the XYZ of
    its uplifted spectrum (the untextured unit mirror renders exactly 1)."""
    texels = np.array([[[0.8, 0.1, 0.1], [0.1, 0.7, 0.2]], [[0.15, 0.2, 0.85], [0.9, 0.85, 0.3]]])
    image = Renderer(_quad_scene(spectrace.mirror(spectrace.bitmap(texels, filter="nearest"))), device).render()
    for r in range(2):
        for c in range(2):
            expected = _xyz_of_spectrum(_sigmoid_spectrum(texels[r, c]))
            mean, error = mean_and_standard_error(image.xyz[_region(r, c)].reshape(-1, 3))
            assert_within_standard_errors(mean, expected, error, slack=2e-4, what=(r, c))


GREY_TINTED = {
    "conductor smooth": lambda tint: spectrace.conductor("Cu", specular_tint=tint),
    "conductor rough": lambda tint: spectrace.conductor("Au", roughness=0.3, specular_tint=tint),
    "dielectric": lambda tint: spectrace.dielectric(1.5, specular_tint=tint),
    "dielectric rough": lambda tint: spectrace.dielectric(1.5, roughness=0.2, specular_tint=tint),
    "retroreflector": lambda tint: spectrace.retroreflector(tint, roughness=0.2),
}


@pytest.mark.parametrize("name", list(GREY_TINTED))
def test_grey_tint_texture_scales_the_untextured_render(device, name):
    """A grey texel's spectrum is a constant c (to within its spread over the wavelengths, bounded here), so every
    path over its region carries c times the weight it carries untextured: with the same random numbers (one
    interaction, no Russian roulette) each region is c × the untextured render, pixel by pixel."""
    make = GREY_TINTED[name]
    grey = np.repeat(GREYS[..., None], 3, axis=-1)
    textured = Renderer(_quad_scene(make(spectrace.bitmap(grey, filter="nearest"))), device).render().xyz
    plain = Renderer(_quad_scene(make(1.0)), device).render().xyz
    for r in range(2):
        for c in range(2):
            spectrum = _sigmoid_spectrum(grey[r, c])
            spread = np.ptp(spectrum) / spectrum.mean()
            assert spread < 1e-3
            region = _region(r, c)
            assert plain[region].mean() > 0.02, "the untextured render must see the material"
            np.testing.assert_allclose(textured[region], spectrum.mean() * plain[region], rtol=spread + 1e-5, atol=1e-6)


def test_white_tint_furnace(device):
    """A mirror of white reflectance texture (ones, bilinear) in a uniform environment: every path returns 1."""
    white = spectrace.bitmap(np.ones((4, 4, 3)))
    image = Renderer(_quad_scene(spectrace.mirror(white), max_depth=-1, spp=16), device).render()
    mean, error = mean_and_standard_error(image.xyz.reshape(-1, 3))
    assert_within_standard_errors(mean, _xyz_of_spectrum(np.ones_like(GRID)), error, slack=2e-4)


ROUGH = {
    "conductor": lambda alpha: spectrace.conductor("Ag", roughness=alpha),
    "plastic": lambda alpha: spectrace.plastic((0.3, 0.5, 0.2), roughness=alpha),
    "dielectric": lambda alpha: spectrace.dielectric(1.5, roughness=alpha),
    "retroreflector": lambda alpha: spectrace.retroreflector(0.9, roughness=alpha),
}


@pytest.mark.parametrize("name", list(ROUGH))
@pytest.mark.parametrize("alphas", [(0.05, 0.5), (0.0, 0.3)], ids=["rough|rough", "smooth|rough"])
def test_roughness_halves_render_as_the_untextured_material(device, name, alphas):
    """A grey roughness texture α1 | α2 (nearest): the left half renders as the material with roughness α1, the
    right half as with α2, region means within 4 standard errors of the pixel differences. Lit by a small sphere
    light besides a dim environment, so the highlight's shape depends on α; with α1 = 0 the left half is a delta
    lobe on a surface whose flags say rough (next-event estimation runs and contributes nothing there)."""
    make = ROUGH[name]
    light = spectrace.shape(
        "sphere",
        spectrace.diffuse(0.0),
        emitter=spectrace.area_emitter(20.0),
        transform=[{"scale": 0.25}, {"translate": [0.5, 0.4, 2.0]}],
    )

    def render(roughness):
        scene = _quad_scene(make(roughness), lights=[spectrace.constant_environment(0.2)], max_depth=4, spp=16)
        scene = replace(scene, shapes=[*scene.shapes, light])
        return Renderer(scene, device).render().xyz

    texture = spectrace.bitmap(np.array([list(alphas)]), filter="nearest")
    assert make(texture).is_delta is False
    textured = render(texture)
    for half, alpha in enumerate(alphas):
        columns = slice(half * HALF + 1, (half + 1) * HALF - 1)
        difference = (textured[:, columns] - render(alpha)[:, columns]).reshape(-1, 3)
        mean, error = mean_and_standard_error(difference)
        assert_within_standard_errors(mean, 0.0, error, slack=1e-6, what=(name, alpha))


def test_roughness_texture_below_the_smooth_limit_is_delta_everywhere():
    """The flags come from the texture's largest α: smooth everywhere only when all of it is below the limit."""
    below = spectrace.bitmap(np.full((2, 2), 0.5 * SMOOTH_ALPHA))
    mixed = spectrace.bitmap(np.array([[0.0, 0.2]]))
    assert spectrace.conductor("Au", roughness=below).is_delta
    assert spectrace.dielectric(1.5, roughness=below).is_delta
    assert not spectrace.conductor("Au", roughness=mixed).is_delta
    assert not spectrace.retroreflector(roughness=mixed).is_delta


def test_roughness_texture_is_checked():
    with pytest.raises(SpectraceError, match="channels"):
        spectrace.conductor("Au", roughness=spectrace.bitmap(np.full((2, 2, 3), 0.2)))
    with pytest.raises(SpectraceError, match="above 1"):
        spectrace.plastic(0.5, roughness=spectrace.bitmap(np.full((2, 2), 1.5)))


# ---------------------------------------------------------------- emission

EMISSION_RGB = np.array([[[0.9, 0.2, 0.1], [0.1, 0.6, 0.3]], [[0.2, 0.25, 1.4], [0.7, 0.7, 0.7]]])


def test_rgb_emission_texture_renders_each_texels_colour(device):
    """Seen head-on (camera rays only), each texel's region has the XYZ of its linear sRGB colour × scale, as
    colour-science converts it: the illuminant uplift reproduces the colour, RGB (1, 1, 1) being D65 at Y = 1."""
    scale = 2.5
    emitter = spectrace.area_emitter(spectrace.bitmap(EMISSION_RGB, filter="nearest"), scale=scale)
    image = Renderer(_quad_scene(emitter=emitter, lights=[], max_depth=1, spp=64), device).render()
    srgb = colour.RGB_COLOURSPACES["sRGB"]
    for r in range(2):
        for c in range(2):
            expected = scale * colour.RGB_to_XYZ(EMISSION_RGB[r, c], srgb, apply_cctf_decoding=False)
            mean, error = mean_and_standard_error(image.xyz[_region(r, c)].reshape(-1, 3))
            # slack: the uplift's fit reproduces a colour to about 1e-3 of its magnitude
            assert_within_standard_errors(mean, expected, error, slack=2e-3 * scale, what=(r, c))


def _spectral_emission():
    wavelengths = np.array([400.0, 500.0, 600.0, 700.0])
    texels = np.array([[[0.2, 1.0, 0.5, 0.1], [1.5, 0.3, 0.3, 0.8]], [[0.0, 0.0, 2.0, 0.0], [0.6, 0.6, 0.6, 0.6]]])
    return wavelengths, texels


def test_spectral_emission_texture_renders_each_texels_spectrum(device):
    """Each texel emits its bands, interpolated linearly between the band centres and held beyond the ends."""
    wavelengths, texels = _spectral_emission()
    texture = spectrace.spectral_texture(texels, wavelengths, filter="nearest")
    image = Renderer(
        _quad_scene(emitter=spectrace.area_emitter(texture), lights=[], max_depth=1, spp=64), device
    ).render()
    for r in range(2):
        for c in range(2):
            expected = _xyz_of_spectrum(np.interp(GRID, wavelengths, texels[r, c]))
            mean, error = mean_and_standard_error(image.xyz[_region(r, c)].reshape(-1, 3))
            assert_within_standard_errors(mean, expected, error, slack=2e-4, what=(r, c))


def test_emission_texture_flux_is_its_mean_radiance_times_pi_times_area(device):
    """A one-sided Lambertian emitter of area A whose radiance varies over it emits Φ(λ) = π ∫ L dA = π A L̄(λ),
    L̄ the texels' mean (bilinear filtering over a repeating image keeps the mean); a flux meter around it."""
    wavelengths, texels = _spectral_emission()
    texture = spectrace.spectral_texture(texels, wavelengths)
    scene = _quad_scene(emitter=spectrace.area_emitter(texture, scale=3.0), lights=[], max_depth=1)
    measured = np.array([450.0, 550.0, 650.0])
    reading = measure(
        scene, FluxMeter((0.0, 0.0, 0.0), 2.0), measured, streams=64, samples_per_item=1280, seed=5, device=device
    )
    mean_bands = texels.reshape(-1, 4).mean(axis=0)
    expected = np.pi * 4.0 * 3.0 * np.interp(measured, wavelengths, mean_bands)
    assert_within_standard_errors(
        reading.spectral, expected, reading.spectral_standard_error, slack=1e-4 * expected, power=0.05
    )


def test_light_selection_uses_the_textures_mean_radiance():
    """Two equal quads, one of constant radiance 1, one of an emission texture of mean radiance 0.7 (a flat
    spectrum per texel): next-event estimation picks them in proportion 1 : 0.7 per triangle."""
    texels = np.repeat(np.array([[[0.4], [1.0]]]), 3, axis=-1)  # bands all equal: a flat spectrum per texel
    textured = spectrace.shape(
        "rectangle",
        spectrace.diffuse(0.0),
        emitter=spectrace.area_emitter(spectrace.spectral_texture(texels, [400, 550, 700])),
    )
    plain = spectrace.shape(
        "rectangle",
        spectrace.diffuse(0.0),
        emitter=spectrace.area_emitter(1.0),
        transform=[{"translate": [3.0, 0.0, 0.0]}],
    )
    scene = Scene(camera=Camera(origin=(0, 0, 5), target=(0, 0, 0)), width=4, height=4, shapes=[textured, plain])
    pmf = build_scene_buffers(scene).lights["pmf"][:4]
    np.testing.assert_allclose(pmf[:2] / pmf[2:], 0.7, rtol=1e-6)


def test_emission_texture_is_checked():
    with pytest.raises(SpectraceError, match="negative"):
        spectrace.area_emitter(spectrace.bitmap(np.full((2, 2, 3), -0.5)))
    with pytest.raises(SpectraceError, match="checkerboard"):
        spectrace.area_emitter(spectrace.checkerboard(spectrace.bitmap(np.ones((2, 2, 3))), 0.5))
