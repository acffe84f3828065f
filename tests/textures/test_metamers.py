"""A metameric pair in a spectral texture, rendered under two lights, against colour-science. Two reflectances whose
difference is a metameric black under D65 (orthogonal to the CIE 1931 colour-matching functions weighted by D65)
have one colour under D65 and two under illuminant A: a spectral renderer must show both, where an RGB one (or a
texture uplifted from RGB) cannot. A diffuse quad seen head-on under a uniform environment of radiance L(λ) reflects
L(λ) R(λ) at each point (one bounce, no other surface), so each region's film XYZ is ∫ L R cmf dλ / ∫ ȳ dλ."""

import colour
import numpy as np
import pytest

import spectrace
from spectrace.engine.renderer import Renderer
from spectrace.scene.model import Camera, Scene
from stats_toolkit import SIGMAS, assert_within_standard_errors, mean_and_standard_error

SIDE = 32  # film pixels; the quad fills the film, each of the texture's two texels the left or right half
GRID = np.arange(360.0, 831.0)  # the renderer's range; the texture has a band at each nanometre of it
SHAPE = colour.SpectralShape(360, 830, 1)
CMFS = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"].copy().align(SHAPE)


def _illuminant(name: str) -> np.ndarray:
    """colour-science's illuminant on the 1 nm grid: A from its Planck formula; D65 from its 5 nm table, linear in
    between (as CIE 15 recommends for the D series) and its last value held beyond 780 nm."""
    if name == "A":
        return np.asarray(colour.sd_CIE_standard_illuminant_A(SHAPE).values)
    sd = colour.SDS_ILLUMINANTS[name].copy().align(SHAPE, interpolator=colour.LinearInterpolator)
    return np.asarray(sd.values)


def _metameric_pair() -> tuple[np.ndarray, np.ndarray]:
    """ColorChecker's neutral 6.5 (N. Ohta's measurement, held constant beyond its 380..780 nm) and the same plus a
    smooth metameric black: a cosine with its component in the span of D65 · x̄, ȳ, z̄ removed (least squares),
    scaled so that the sum stays within [0, 1]."""
    sd = colour.SDS_COLOURCHECKERS["ColorChecker N Ohta"]["neutral 6.5 (.44 D)"]
    base = np.interp(GRID, sd.wavelengths, sd.values)
    weighted_cmfs = _illuminant("D65")[:, None] * CMFS.values
    wave = np.cos(2.0 * np.pi * (GRID - 380.0) / 400.0)
    black = wave - weighted_cmfs @ np.linalg.lstsq(weighted_cmfs, wave, rcond=None)[0]
    room = np.where(black > 0, (0.95 - base) / np.maximum(black, 1e-12), (base - 0.05) / np.maximum(-black, 1e-12))
    return base, base + room.min() * black


def _film_xyz(reflectance: np.ndarray, illuminant: np.ndarray) -> np.ndarray:
    """The film's XYZ of the light reflected, L(λ) R(λ) (the illuminant in its relative scale, 100 at 560 nm, as the
    light's radiance): colour-science's XYZ of that stimulus under an equal-energy illuminant of 1, over 100."""
    stimulus = colour.SpectralDistribution(dict(zip(GRID, reflectance * illuminant)))
    equal_energy = colour.SpectralDistribution(dict(zip(GRID, np.ones_like(GRID))))
    return colour.sd_to_XYZ(stimulus, CMFS, equal_energy, method="Integration") / 100.0


def _object_xyz(reflectance: np.ndarray, illuminant: np.ndarray) -> np.ndarray:
    """colour-science's object colour (white Y = 100) of the reflectance under the illuminant."""
    sd = colour.SpectralDistribution(dict(zip(GRID, reflectance)))
    light = colour.SpectralDistribution(dict(zip(GRID, illuminant)))
    return colour.sd_to_XYZ(sd, CMFS, light, method="Integration")


def _delta_e_2000(xyz_a: np.ndarray, xyz_b: np.ndarray, white_xyz: np.ndarray) -> float:
    white_xy = colour.XYZ_to_xy(white_xyz)
    lab_a = colour.XYZ_to_Lab(xyz_a / white_xyz[1], white_xy)
    lab_b = colour.XYZ_to_Lab(xyz_b / white_xyz[1], white_xy)
    return float(colour.delta_E(lab_a, lab_b, method="CIE 2000"))


def _render_halves(texels: np.ndarray, light: str, device) -> tuple[np.ndarray, np.ndarray]:
    """Per-pixel XYZ of the left and right texels' regions (2 pixels inside their edges), as (pixels, 3) arrays."""
    texture = spectrace.spectral_texture(texels, GRID, filter="nearest")
    quad = spectrace.shape("rectangle", spectrace.diffuse(texture))
    scene = Scene(
        camera=Camera(origin=(0.0, 0.0, 3.0), target=(0.0, 0.0, 0.0), fov_degrees=30.0),
        width=SIDE,
        height=SIDE,
        shapes=[quad],
        lights=[spectrace.constant_environment(f"cie:{light}")],
        max_depth=2,
        spp=512,
        seed=5,
        sampler="independent",
    )
    xyz = Renderer(scene, device).render().xyz
    half = SIDE // 2
    left = xyz[2:-2, 2 : half - 2].reshape(-1, 3)
    right = xyz[2:-2, half + 2 : SIDE - 2].reshape(-1, 3)
    return left, right


@pytest.fixture(scope="module")
def pair():
    return _metameric_pair()


def test_the_pair_is_metameric_under_d65_only(pair):
    """The construction itself, by colour-science: the same colour under D65, a visible difference under A."""
    base, metamer = pair
    assert metamer.min() >= 0.0 and metamer.max() <= 1.0
    assert np.max(np.abs(metamer - base)) > 0.3
    d65, a = _illuminant("D65"), _illuminant("A")
    np.testing.assert_allclose(_object_xyz(base, d65), _object_xyz(metamer, d65), rtol=1e-9)
    white_a = _object_xyz(np.ones_like(GRID), a)
    assert _delta_e_2000(_object_xyz(base, a), _object_xyz(metamer, a), white_a) > 5.0


def test_metamers_match_under_d65(device, pair):
    """Rendered under D65, the two regions' mean XYZ agree within 4 standard errors of their difference, and each
    has the XYZ colour-science computes."""
    base, metamer = pair
    left, right = _render_halves(np.stack([base, metamer])[None], "D65", device)
    (mean_l, se_l), (mean_r, se_r) = mean_and_standard_error(left), mean_and_standard_error(right)
    expected = _film_xyz(base, _illuminant("D65"))
    slack = 2e-4 * expected  # float32 texels and accumulation
    assert_within_standard_errors(mean_l - mean_r, 0.0, np.hypot(se_l, se_r), slack=slack, what="difference")
    assert_within_standard_errors(mean_l, expected, se_l, slack=slack, what="left")
    assert_within_standard_errors(mean_r, expected, se_r, slack=slack, what="right")


def test_metamers_differ_under_illuminant_a_by_colour_science_delta_e(device, pair):
    """Rendered under A, the regions' CIEDE2000 difference (A's white) is the one colour-science computes from the
    two spectra, within 4 standard errors propagated from the regions' XYZ (central differences at ± σ)."""
    base, metamer = pair
    a = _illuminant("A")
    left, right = _render_halves(np.stack([base, metamer])[None], "A", device)
    (mean_l, se_l), (mean_r, se_r) = mean_and_standard_error(left), mean_and_standard_error(right)
    expected = _delta_e_2000(_object_xyz(base, a), _object_xyz(metamer, a), _object_xyz(np.ones_like(GRID), a))
    white = _film_xyz(np.ones_like(GRID), a)  # the light itself, as the film sees it
    rendered = _delta_e_2000(mean_l, mean_r, white)
    variance = 0.0
    for i in range(6):
        step = np.zeros(6)
        step[i] = np.concatenate([se_l, se_r])[i]
        plus = _delta_e_2000(mean_l + step[:3], mean_r + step[3:], white)
        minus = _delta_e_2000(mean_l - step[:3], mean_r - step[3:], white)
        variance += ((plus - minus) / 2.0) ** 2
    sigma = float(np.sqrt(variance))
    assert rendered > SIGMAS * sigma + 1.0, f"the regions should differ: ΔE {rendered:.3f} ± {sigma:.3f}"
    assert abs(rendered - expected) <= SIGMAS * sigma + 0.01, (
        f"ΔE2000 rendered {rendered:.4f} ± {sigma:.4f}, colour-science {expected:.4f}"
    )
