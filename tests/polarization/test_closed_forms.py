"""Polarised transport against closed forms: sheets in front of an unpolarised emitter of radiance 1 (Malus's law,
an imperfect polariser, a quarter-wave plate, a sequence of retarders, the camera's polariser) and reflections of an
unpolarised sky (Brewster's angle for BK7, a dielectric's and a conductor's Fresnel Mueller matrices), each
measured as Stokes images and compared with Mueller matrices computed here (stokes_scenes). The sheets' paths
are delta paths through spectrally flat elements, so their estimates have no noise beyond float rounding: their
tolerance is a small floor above 4 standard errors of the pixels' spread."""

import numpy as np
import pytest
from tests.polarization.stokes_scenes import (
    UNPOLARIZED,
    fresnel_reflection,
    header,
    measure,
    polarizer,
    retarder,
    sheets,
)

FLOOR = 2e-5


def assert_stokes(measured, expected, floor: float = FLOOR) -> None:
    tolerance = 4 * measured.stderr + floor
    assert np.all(np.abs(measured.stokes - expected) <= tolerance), (measured.stokes, expected, tolerance)


@pytest.mark.parametrize("angle", [0, 30, 45, 60, 90])
def test_malus_law_through_two_polarizers(tmp_path, angle):
    measured = measure(tmp_path, sheets('type = "polarizer"', f'type = "polarizer"\nangle = {angle}'))
    theta = np.radians(angle)
    s0 = 0.5 * np.cos(theta) ** 2
    assert_stokes(measured, [s0, s0 * np.cos(2 * theta), s0 * np.sin(2 * theta), 0.0])


def test_polarizers_with_extinction_and_transmittance(tmp_path):
    """Partial polarisers (extinction 0.1, transmittance 0.8) against the diattenuator's matrix product."""
    first = 'type = "polarizer"\nangle = 10\nextinction = 0.1\ntransmittance = { value = 0.8 }'
    second = 'type = "polarizer"\nangle = 70\nextinction = 0.1\ntransmittance = { value = 0.8 }'
    measured = measure(tmp_path, sheets(first, second))
    expected = polarizer(np.radians(70), 0.8, 0.08) @ polarizer(np.radians(10), 0.8, 0.08) @ UNPOLARIZED
    assert_stokes(measured, expected)


@pytest.mark.parametrize("fast_axis", [45, -45])
def test_quarter_wave_plate_turns_linear_into_circular(tmp_path, fast_axis):
    measured = measure(tmp_path, sheets('type = "polarizer"', f'type = "retarder"\nangle = {fast_axis}'))
    expected = retarder(np.radians(fast_axis), np.pi / 2) @ polarizer(0.0) @ UNPOLARIZED
    assert_stokes(measured, expected)
    # Horizontal light through a fast axis at +45° leaves right-circular (S3 = S0, Collett's convention), at -45°
    # left-circular.
    s0, s3 = measured.stokes[0], measured.stokes[3]
    assert s3 == pytest.approx(np.sign(fast_axis) * s0, abs=FLOOR)


def test_retarder_sequence_against_matrix_product(tmp_path):
    tables = (
        'type = "polarizer"\nangle = 15',
        'type = "retarder"\nangle = 30\nretardance = 60',
        'type = "retarder"\nangle = -20\nretardance = 90',
        'type = "retarder"\nangle = 80\nretardance = 180\ntransmittance = { value = 0.9 }',
    )
    measured = measure(tmp_path, sheets(*tables))
    expected = 0.9 * (
        retarder(np.radians(80), np.pi)
        @ retarder(np.radians(-20), np.pi / 2)
        @ retarder(np.radians(30), np.pi / 3)
        @ polarizer(np.radians(15))
        @ UNPOLARIZED
    )
    assert_stokes(measured, expected)


@pytest.mark.parametrize("filter_angle", [0, 30, 90, 135])
def test_camera_polarizer_follows_malus_law(tmp_path, filter_angle):
    """A sheet polariser at 0° seen through camera.polarizer_angle: the image holds ½ cos²φ of the sheet's ½; the
    Stokes images stay those of the light reaching the filter."""
    camera = f"origin = [0, 0, 3]\ntarget = [0, 0, 0]\nfov = 10\npolarizer_angle = {filter_angle}"
    measured = measure(tmp_path, sheets('type = "polarizer"', camera=camera))
    expected = 0.5 * np.cos(np.radians(filter_angle)) ** 2
    assert abs(measured.image_y - expected) <= 4 * measured.image_stderr + FLOOR
    assert_stokes(measured, [0.5, 0.5, 0.0, 0.0])


def reflection_scene(incidence_degrees: float, material: str, above: str = "", fov: float = 4.0) -> str:
    """An unpolarised sky of radiance 1 reflected into the camera by a plate in z = 0 at the given incidence, the
    plane of incidence xz (so s is ±y, the image's right); a black floor under the plate hides the sky below.
    `above`: more shapes; `fov` the view's width in degrees (the incidence varies by as much across it)."""
    theta = np.radians(incidence_degrees)
    origin = f"[{3 * np.sin(theta):.9f}, 0, {3 * np.cos(theta):.9f}]"
    camera = f"origin = {origin}\ntarget = [0, 0, 0]\nup = [0, 0, 1]\nfov = {fov}"
    return (
        header(camera, spp=16)
        + f"""
[materials.plate]
{material}

[[shapes]]
type = "rectangle"
material = "plate"

[[shapes]]
type = "rectangle"
material = "black"
transform = [{{ scale = [20, 20, 1] }}, {{ translate = [0, 0, -0.5] }}]

[[lights]]
type = "constant"
radiance = {{ value = 1 }}
{above}"""
    )


def test_brewster_reflection_from_bk7_is_s_polarized(tmp_path):
    """At BK7's Brewster angle for 550 nm (tan θB = n), the reflection is s-polarised, along the image's right:
    DoLP above 0.9999 over the visible, where θB moves by 0.3°, and above 0.9995 over a view 0.5° wide, whose edges
    are 0.25° off Brewster (2° off, the p part is back: DoLP 0.994)."""
    n_550 = 1.51852  # SCHOTT N-BK7 at 550 nm
    brewster = np.degrees(np.arctan(n_550))
    measured = measure(tmp_path, reflection_scene(brewster, 'type = "dielectric"\nior = "BK7"', fov=0.5))
    s0, s1, s2, s3 = measured.stokes
    assert s0 > 0.05
    assert np.all(measured.dolp > 0.9995)
    assert s1 / s0 > 0.9995
    assert abs(s2) < 1e-3 * s0 and abs(s3) < 1e-3 * s0


@pytest.mark.parametrize("incidence", [30, 70])
def test_dielectric_reflection_against_fresnel(tmp_path, incidence):
    measured = measure(tmp_path, reflection_scene(incidence, 'type = "dielectric"\nior = 1.5'))
    expected = fresnel_reflection(np.cos(np.radians(incidence)), 1.5) @ UNPOLARIZED
    assert_stokes(measured, expected, floor=1e-4 * expected[0])


@pytest.mark.parametrize("incidence", [30, 70])
def test_smooth_plastic_coat_reflection_against_fresnel(tmp_path, incidence):
    """A black smooth plastic reflects by its coat alone: the dielectric's Fresnel reflection."""
    plastic = 'type = "plastic"\nreflectance = { value = 0 }\nior = 1.5'
    measured = measure(tmp_path, reflection_scene(incidence, plastic))
    expected = fresnel_reflection(np.cos(np.radians(incidence)), 1.5) @ UNPOLARIZED
    assert_stokes(measured, expected, floor=1e-4 * expected[0])


def test_conductor_mueller_matrix_against_fresnel(tmp_path):
    """Light polarised at 45° to the plane of incidence (a polariser across the reflected beam) reflected by a
    smooth conductor of index 0.2 + 3.5i at 45°: all four Stokes parameters follow the Fresnel Mueller matrix
    computed here, the retardance between s and p turning some of it circular."""
    incidence = np.radians(45)
    toward_sky = np.array([-np.sin(incidence), 0.0, np.cos(incidence)])
    # A polariser 1.5 up the reflected beam, normal to it: the rectangle's +z turned about y onto toward_sky; its
    # dp/du is the rotated +x.
    turn = -45.0
    centre = 1.5 * toward_sky
    sheet = f"""
[materials.filter]
type = "polarizer"
angle = 45

[[shapes]]
type = "rectangle"
material = "filter"
transform = [{{ rotate = {{ axis = [0, 1, 0], angle = {turn} }} }},
             {{ translate = [{centre[0]:.9f}, 0, {centre[2]:.9f}] }}]
"""
    measured = measure(
        tmp_path, reflection_scene(45, 'type = "conductor"\neta = { value = 0.2 }\nk = { value = 3.5 }', sheet)
    )
    # The polariser's axis in the s/p basis of the beam travelling from it to the plate (k = -toward_sky,
    # x = s = the image's right, which for this camera is +y).
    du = np.array([np.cos(np.radians(turn)), 0.0, -np.sin(np.radians(turn))])
    axis = np.cos(np.radians(45)) * du + np.sin(np.radians(45)) * np.array([0.0, 1.0, 0.0])
    k = -toward_sky
    s = np.array([0.0, 1.0, 0.0])
    psi = np.arctan2(np.dot(np.cross(k, s), axis), np.dot(s, axis))
    expected = fresnel_reflection(np.cos(incidence), complex(0.2, 3.5)) @ polarizer(psi) @ UNPOLARIZED
    assert abs(expected[3]) > 0.1 * expected[0]  # the case tests the retardance
    assert_stokes(measured, expected, floor=1e-4 * expected[0])
