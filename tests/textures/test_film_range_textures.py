"""Textures under a film range of its own (docs/colour.md, "Wavelength range"): RGB texels are sigmoids of λ, so a
range inside the visible sees them as the default range does, cut to that band; beyond the visible they follow the
rule of RGB spectra (refused in one line unless film.extend_rgb continues them). The reference is colour-science's
integration of the uplifted spectrum over the film's band, as tests/textures/test_textured_render.py does over the
whole grid."""

import colour
import numpy as np
import pytest

import spectrace
from spectrace.engine.renderer import Renderer
from spectrace.errors import SpectraceError
from spectrace.film.response import FilmResponse
from stats_toolkit import assert_within_standard_errors, mean_and_standard_error
from textures.test_textured_render import GRID, RGB_TEXELS, SIDE, _quad_scene, _sigmoid_spectrum


def _band_xyz(reflectance_on_grid: np.ndarray, lo: float, hi: float) -> np.ndarray:
    """Film XYZ under an environment of radiance 1 with the film's range [lo, hi]: the CIE 1931 CMFs (divided by
    ∫ȳ over 360-830 nm, as the film's observer rows are) seen only within the band."""
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"].copy().align(colour.SpectralShape(360, 830, 1))
    inside = (lo <= GRID) & (hi >= GRID)
    weights = np.where(inside, 1.0, 0.0)
    weights[np.flatnonzero(inside)[[0, -1]]] = 0.5  # the trapezoid rule on the band's 1 nm grid
    all_weights = np.r_[0.5, np.ones(GRID.size - 2), 0.5]
    return (reflectance_on_grid[:, None] * cmfs.values * weights[:, None]).sum(axis=0) / (
        cmfs.values[:, 1] * all_weights
    ).sum()


def _with_range(scene, lo, hi, extend_rgb=False):
    return scene.with_overrides(film_response=FilmResponse(wavelengths=(lo, hi), extend_rgb=extend_rgb))


@pytest.mark.parametrize(("lo", "hi", "extend_rgb"), [(450, 620, False), (360, 900, True)])
def test_rgb_texture_regions_under_a_film_range_of_its_own(device, lo, hi, extend_rgb):
    """Each texel's region has the XYZ of its uplifted spectrum seen through the film's band (beyond 830 nm the
    CMFs are zero, so a continued sigmoid adds nothing to X, Y, Z)."""
    scene = _with_range(
        _quad_scene(spectrace.diffuse(spectrace.bitmap(RGB_TEXELS, filter="nearest"))), lo, hi, extend_rgb
    )
    image = Renderer(scene, device).render()
    half = SIDE // 2
    for r in range(2):
        for c in range(2):
            expected = _band_xyz(_sigmoid_spectrum(RGB_TEXELS[r, c]), lo, hi)
            region = image.xyz[r * half + 2 : (r + 1) * half - 2, c * half + 2 : (c + 1) * half - 2]
            mean, error = mean_and_standard_error(region.reshape(-1, 3))
            assert_within_standard_errors(mean, expected, error, slack=2e-4, what=(r, c))
            if lo > 360:  # the check tells the band from the whole range
                whole = _band_xyz(_sigmoid_spectrum(RGB_TEXELS[r, c]), 360, 830)
                assert np.any(np.abs(mean - whole) > 5 * error + 2e-4), (r, c)


def test_rgb_textures_beyond_the_visible_need_extend_rgb(device):
    scene = _with_range(_quad_scene(spectrace.diffuse(spectrace.bitmap(RGB_TEXELS))), 360, 900)
    with pytest.raises(SpectraceError, match=r"film\.wavelengths 360-900 nm: textures .*film\.extend_rgb") as caught:
        Renderer(scene, device)
    assert "\n" not in str(caught.value)


def test_a_textured_emitter_under_a_film_range_of_its_own_matches_its_plain_emission(device):
    """An emitter picture of one colour is the RGB emission of that colour (both D65-based: docs/textures.md), so
    under the film's band [420, 680] nm the two quads give the same image, within the noise of their difference."""
    rgb = (0.7, 0.4, 0.2)
    pictured = spectrace.area_emitter(spectrace.bitmap(np.broadcast_to(rgb, (2, 2, 3)).copy()))
    plain = spectrace.area_emitter(rgb)
    images = []
    for emitter in (pictured, plain):
        quad = spectrace.shape("rectangle", spectrace.diffuse(0.0), emitter=emitter)
        scene = _with_range(_quad_scene(spectrace.diffuse(0.0)), 420, 680).with_overrides(shapes=[quad], lights=[])
        images.append(Renderer(scene, device).render(spp=16).xyz.reshape(-1, 3).astype(np.float64))
    mean, error = mean_and_standard_error(images[0] - images[1])
    assert_within_standard_errors(mean, 0.0, error, slack=1e-4 * images[1].mean())
    assert images[1].mean() > 0.05
