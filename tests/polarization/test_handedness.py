"""The sense of circular polarisation (S3's sign) against Maxwell's equations, with no Fresnel sign convention in
between: unpolarised sky light reflected by two conductor plates whose planes of incidence are turned 45° about the
beam between them (the first plate's s-polarisation reaches the second at 45° to its own s, whose retardance turns
part of it elliptical). The reference solves the boundary conditions of a plane wave at each plate here (tangential
E and H continuous, fields exp(i(k·r − ωt)), the metal's index n + iκ absorbing), follows the two real field
vectors of the unpolarised light's halves, and reads their Stokes vectors in the camera's basis (x the image's
right, y its up) in Collett's convention, which mueller.cl states: S3 > 0 when the field turns from y toward x,
clockwise to one looking into the beam. Linear elements cannot tell the handedness apart; a retarder's sense is
Collett's matrix (test_closed_forms)."""

import numpy as np
from tests.polarization.stokes_scenes import measure
from tests.polarization.test_closed_forms import assert_stokes, reflection_scene

INDEX = complex(0.2, 3.5)


def reflect(field: np.ndarray, direction: np.ndarray, normal: np.ndarray, index: complex) -> np.ndarray:
    """The complex field vector reflected by a plane interface of a medium of complex `index` under vacuum, of the
    plane wave of complex field `field` travelling along the unit `direction`, from Maxwell's boundary conditions."""
    z = normal if direction @ normal < 0 else -normal
    cos_i = -(direction @ z)
    tangent = direction + cos_i * z
    sin_i = np.linalg.norm(tangent)
    x = tangent / sin_i
    y = np.cross(z, x)
    local = np.array([field @ x, field @ y, field @ z])
    k_in, k_out = np.array([sin_i, 0.0, -cos_i]), np.array([sin_i, 0.0, cos_i])
    w = np.sqrt(index**2 - sin_i**2 + 0j)
    w = w if w.imag >= 0 else -w  # the transmitted wave decays into the metal (z < 0)
    k_t = np.array([sin_i, 0.0, -w])
    # Unknowns: reflected field r1 ŷ + r2 (cos, 0, −sin), transmitted t1 ŷ + t2 (w, 0, sin), each normal to its k.
    columns = [
        (np.array([0.0, 1.0, 0.0]), k_out, 1.0),
        (np.array([cos_i, 0.0, -sin_i]), k_out, 1.0),
        (np.array([0.0, 1.0, 0.0]), k_t, -1.0),
        (np.array([w, 0.0, sin_i]), k_t, -1.0),
    ]
    system = np.array([sign * np.r_[v[:2], np.cross(k, v)[:2]] for v, k, sign in columns]).T
    h_in = np.cross(k_in, local)
    r1, r2, _, _ = np.linalg.solve(system, -np.r_[local[:2], h_in[:2]])
    reflected = r1 * np.array([0.0, 1.0, 0.0]) + r2 * columns[1][0]
    return reflected[0] * x + reflected[1] * y + reflected[2] * z


def stokes_collett(field: np.ndarray, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """The Stokes vector of the field exp(−iωt) in the basis (x, y): S3 = −2 Im(Ex* Ey) (Collett's sense)."""
    ex, ey = field @ x, field @ y
    cross = np.conj(ex) * ey
    return np.array([abs(ex) ** 2 + abs(ey) ** 2, abs(ex) ** 2 - abs(ey) ** 2, 2 * cross.real, -2 * cross.imag])


def test_reflection_solver_gives_the_fresnel_reflectances():
    """The solver's reflected power of s and p light at 60° against the Fresnel reflectances (which need no sign
    convention) for the complex index."""
    cos_i, sin_i = 0.5, np.sqrt(0.75)
    direction = np.array([sin_i, 0.0, -cos_i])
    w = np.sqrt(INDEX**2 - sin_i**2)
    r_s = abs((cos_i - w) / (cos_i + w)) ** 2
    r_p = abs((INDEX**2 * cos_i - w) / (INDEX**2 * cos_i + w)) ** 2
    for field, expected in ((np.array([0.0, 1.0, 0.0j]), r_s), (np.array([cos_i, 0.0, sin_i + 0j]), r_p)):
        reflected = reflect(field, direction, np.array([0.0, 0.0, 1.0]), INDEX)
        assert np.isclose(np.vdot(reflected, reflected).real, expected, rtol=1e-12)


def test_two_conductors_circular_sense_against_maxwell(tmp_path):
    incidence = np.radians(70.0)
    toward_second = np.array([-np.sin(incidence), 0.0, np.cos(incidence)])  # the camera ray after the first plate
    in_plane = np.array([np.cos(incidence), 0.0, np.sin(incidence)])
    across = (in_plane + np.array([0.0, 1.0, 0.0])) / np.sqrt(2.0)  # the second plane, turned 45° about the beam
    normal = np.cos(incidence) * -toward_second + np.sin(incidence) * across
    axis = np.cross([0.0, 0.0, 1.0], normal)
    turn = np.degrees(np.arccos(normal[2]))
    centre = 1.5 * toward_second
    metal = 'type = "conductor"\neta = { value = 0.2 }\nk = { value = 3.5 }'
    rotate = f"{{ rotate = {{ axis = [{axis[0]:.9f}, {axis[1]:.9f}, {axis[2]:.9f}], angle = {turn:.9f} }} }}"
    translate = f"{{ translate = [{centre[0]:.9f}, {centre[1]:.9f}, {centre[2]:.9f}] }}"
    second = f"""
[materials.second]
{metal}

[[shapes]]
type = "rectangle"
material = "second"
transform = [{{ scale = [0.5, 0.5, 1] }}, {rotate}, {translate}]
"""
    measured = measure(tmp_path, reflection_scene(70.0, metal, second, fov=1.0))

    to_sky = toward_second - 2 * (toward_second @ normal) * normal
    to_camera = np.array([np.sin(incidence), 0.0, np.cos(incidence)])
    right = np.array([0.0, 1.0, 0.0])
    up = np.cross(to_camera, right)
    arriving = -to_sky
    first = np.cross(arriving, [0.0, 0.0, 1.0])
    first /= np.linalg.norm(first)
    expected = np.zeros(4)
    for half in (first, np.cross(arriving, first)):  # unpolarised: two incoherent orthogonal halves
        field = reflect(half.astype(complex), arriving, normal, INDEX)
        field = reflect(field, -toward_second, np.array([0.0, 0.0, 1.0]), INDEX)
        expected += stokes_collett(field, right, up)
    expected /= 2.0  # the two halves of the sky's unpolarised radiance 1
    assert expected[3] < -0.04 * expected[0]  # the case tests the sense: S3 clearly non-zero
    assert_stokes(measured, expected, floor=2e-3 * expected[0])
