"""Rough conductors and dielectrics in polarised transport: the microfacet event's Mueller matrix is the smooth
interface's Fresnel matrix on the microfacet normal h linking the two directions, in the plane of incidence through
h (Walter et al. 2007; Mitsuba 3's polarised rough conductor). A point light seen in a rough plate reaches each
pixel by next-event estimation alone along one direction, so the light's Stokes vector over its S0 is that Fresnel
matrix's first column, turned from h's plane into the image's basis: computed here per pixel from the geometry
(stokes_scenes' Fresnel equations), independently of the kernels. Its spread within a pixel (the view is 2° wide)
bounds the tolerance. A scene whose polarising events are never consecutive renders the unpolarised S0."""

import numpy as np
import pytest
from tests.polarization.stokes_scenes import SIZE, fresnel_reflection, header
from tests.polarization.test_transport import BOX

import spectrace
from spectrace.scene.loader import load_scene

FOV = 2.0
CAMERA = 3.0 * np.array([np.sin(np.radians(70)), 0.0, np.cos(np.radians(70))])


# The light out of the camera's plane of incidence, so that h's plane is turned against the image's basis (S2).
def _toward(incidence: float, azimuth: float) -> np.ndarray:
    """The unit direction `incidence` degrees from +z, `azimuth` degrees from -x toward +y."""
    theta, phi = np.radians(incidence), np.radians(azimuth)
    return np.array([-np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)])


LIGHT = 2.5 * _toward(60, 25)
CONDUCTOR = 'type = "conductor"\neta = { value = 1.2 }\nk = { value = 2.0 }\nroughness = 0.15'
GLASS = 'type = "dielectric"\nior = 1.5\nroughness = 0.15'
PPLASTIC = 'type = "pplastic"\nreflectance = { value = 0.5 }\nior = 1.5\nroughness = 0.15'
# Stretched along the plate's dp/du: the Fresnel matrix is the microfacet's at h whatever the distribution of h.
ANISOTROPIC_CONDUCTOR = CONDUCTOR.replace("roughness = 0.15", "roughness = 0.05\nroughness_v = 0.3")


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def _scene(material: str, light: np.ndarray, more: str = "", spp: int = 16) -> str:
    camera = "origin = [{:.9f}, {:.9f}, {:.9f}]\ntarget = [0, 0, 0]\nup = [0, 0, 1]\nfov = {}".format(*CAMERA, FOV)
    return (
        header(camera, spp=spp, more=more)
        + f"""
[materials.plate]
{material}

[[shapes]]
type = "rectangle"
material = "plate"
transform = [{{ scale = [5, 5, 1] }}]

[[lights]]
type = "point"
position = [{light[0]:.9f}, {light[1]:.9f}, {light[2]:.9f}]
intensity = {{ value = 10 }}
"""
    )


def _render(tmp_path, text: str, name: str = "scene"):
    path = tmp_path / f"{name}.toml"
    path.write_text(text)
    image = spectrace.render(load_scene(path), progress=False, colour_space="xyz")
    stokes = image.aovs["stokes"].reshape(SIZE, SIZE, 4, 3)[..., 1].astype(np.float64)
    return stokes, np.asarray(image.xyz, np.float64)[..., 1]


def _pixel_geometry() -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Per pixel centre: the plate point seen, the direction back to the camera (wo, the light's way) and the
    image's basis (x = the image's right, y = wo × x, its up)."""
    d = _unit(-CAMERA)
    right = _unit(np.cross(d, [0.0, 0.0, 1.0]))
    up = np.cross(right, d)
    t = np.tan(np.radians(FOV) / 2) * ((np.arange(SIZE) + 0.5) * 2 / SIZE - 1)
    rays = _unit(d + t[None, :, None] * right + -t[:, None, None] * up)
    points = CAMERA - rays * (CAMERA[2] / rays[..., 2:3])
    wo = -rays
    # The camera's basis for a ray along r: r × the camera's up, normal to its view axis (polarized_path.cl).
    x = _unit(np.cross(rays, up))
    return points, wo, x, np.cross(wo, x)


def _expected_linear(shape_of, light: np.ndarray, transmitted: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """S1/S0 and S2/S0 per pixel of unpolarised light from `light` leaving the plate toward the camera through the
    microfacet that links the two directions: partially polarised along h's plane normal s by b = M10 / M00 of
    shape_of(cos on the microfacet from the light's side, per pixel), at angle ψ of s in the image's basis."""
    points, wo, x, y = _pixel_geometry()
    wi = _unit(light - points)
    # Refraction's h ∝ n_o ωo + n_i ωi (Walter et al. eq. 16), the camera outside (1) and the light inside (1.5).
    h = _unit(wo + wi) if not transmitted else _unit(wo + 1.5 * wi)
    cos_light = np.abs(np.sum(wi * h, axis=-1))
    b = np.vectorize(shape_of)(cos_light)
    s = _unit(np.cross(h, wo))
    psi = np.arctan2(np.sum(s * y, axis=-1), np.sum(s * x, axis=-1))
    return b * np.cos(2 * psi), b * np.sin(2 * psi)


def _reflection_b(eta: complex):
    def b(cos_i: float) -> float:
        m = fresnel_reflection(cos_i, eta)
        return m[1, 0] / m[0, 0]

    return b


def _transmission_b(eta: float):
    """Light from inside glass (index eta relative to the outside, < 1 from the light's side) refracted out."""

    def b(cos_i: float) -> float:
        cos_t = np.sqrt(1 - (1 - cos_i**2) / eta**2)
        t_s = 2 * cos_i / (cos_i + eta * cos_t)
        t_p = 2 * cos_i / (eta * cos_i + cos_t)
        return (t_s**2 - t_p**2) / (t_s**2 + t_p**2)

    return b


def _assert_linear(stokes: np.ndarray, expected: tuple[np.ndarray, np.ndarray]) -> None:
    s0 = stokes[..., 0]
    assert np.all(s0 > 0), "every pixel sees the light's highlight"
    for measured, wanted in zip((stokes[..., 1] / s0, stokes[..., 2] / s0), expected, strict=True):
        # Within a pixel (1/4° of view) the ratio moves by less than 1 % of its size.
        assert np.all(np.abs(measured - wanted) <= 0.01 * np.abs(wanted) + 2e-4), (measured, wanted)
    assert np.all(np.abs(stokes[..., 3]) <= 1e-6 * s0)  # unpolarised light in: no circular part out


@pytest.mark.parametrize(
    "conductor, filter_angle",
    [(CONDUCTOR, 0), (CONDUCTOR, 60), (CONDUCTOR, 120), (ANISOTROPIC_CONDUCTOR, 60)],
    ids=["0", "60", "120", "anisotropic-60"],
)
def test_rough_conductor_through_the_camera_polarizer_follows_fresnel_on_the_microfacet(
    tmp_path, conductor, filter_angle
):
    """The image through a camera polariser at φ is ½ (S0 + cos 2φ S1 + sin 2φ S2) of the Fresnel matrix at h."""
    more = f"polarizer_angle = {filter_angle}"
    stokes, image = _render(tmp_path, _scene(conductor, LIGHT).replace("fov = 2", f"fov = 2\n{more}"))
    s1, s2 = _expected_linear(_reflection_b(complex(1.2, 2.0)), LIGHT)
    assert np.abs(s2).mean() > 0.05 and np.abs(s1).mean() > 0.05  # the case turns h's plane off the image's axes
    _assert_linear(stokes, (s1, s2))
    phi = np.radians(filter_angle)
    wanted = 0.5 * (1 + np.cos(2 * phi) * s1 + np.sin(2 * phi) * s2)
    assert np.all(np.abs(image / stokes[..., 0] - wanted) <= 0.01 * np.abs(wanted - 0.5) + 2e-4)


def test_rough_dielectric_reflection_follows_fresnel_on_the_microfacet(tmp_path):
    stokes, _ = _render(tmp_path, _scene(GLASS, LIGHT))
    _assert_linear(stokes, _expected_linear(_reflection_b(complex(1.5, 0.0)), LIGHT))


def test_rough_dielectric_refraction_follows_fresnel_on_the_microfacet(tmp_path):
    """The light below the plate, inside the glass: its light refracts out, partially p-polarised."""
    below = 2.5 * _toward(35, 30) * np.array([1.0, 1.0, -1.0])
    stokes, _ = _render(tmp_path, _scene(GLASS, below))
    s1, s2 = _expected_linear(_transmission_b(1 / 1.5), below, transmitted=True)
    assert np.all(np.hypot(s1, s2) > 0.01)
    _assert_linear(stokes, (s1, s2))


@pytest.mark.parametrize(
    "material",
    [CONDUCTOR, GLASS, PPLASTIC, ANISOTROPIC_CONDUCTOR],
    ids=["conductor", "glass", "pplastic", "anisotropic-conductor"],
)
def test_rough_plate_in_a_box_renders_its_unpolarized_image(tmp_path, material):
    """A flat rough plate in a box of diffuse walls: no path meets two polarising events in a row (a plane cannot
    see itself, the walls depolarise), so S0 is the unpolarised render's within 4 standard errors of the
    difference (blocks of 2 x 2 pixels, their spread), while the plate's light is polarised."""
    text = (
        BOX
        + f"""
[materials.plate]
{material}

[[shapes]]
type = "rectangle"
material = "plate"
transform = [{{ scale = [0.6, 0.6, 1] }}, {{ rotate = {{ axis = [1, 0, 0], angle = -70 }} }},
             {{ translate = [0, 0.6, 0] }}]
"""
    )
    polarized = spectrace.render(_load(tmp_path, text, "polarized"), progress=False, colour_space="xyz")
    plain_text = text.replace('aovs = ["stokes", "dolp"]', "")
    plain = spectrace.render(_load(tmp_path, plain_text, "plain"), progress=False, colour_space="xyz")
    difference = (np.asarray(polarized.xyz) - np.asarray(plain.xyz))[..., 1]
    blocks = difference.reshape(4, 2, 4, 2).mean(axis=(1, 3))
    stderr = difference.std(ddof=1) / np.sqrt(4)
    assert np.all(np.abs(blocks) <= 4 * stderr + 1e-6)
    stokes = polarized.aovs["stokes"].reshape(SIZE, SIZE, 4, 3)[..., 1]
    assert np.asarray(plain.xyz)[..., 1].mean() > 0.05
    lit = stokes[..., 0] > 0
    assert (np.hypot(stokes[..., 1], stokes[..., 2])[lit] / stokes[..., 0][lit]).max() > 0.05


def _load(tmp_path, text: str, name: str):
    path = tmp_path / f"{name}.toml"
    path.write_text(text)
    return load_scene(path)


@pytest.mark.parametrize("material", [CONDUCTOR, PPLASTIC], ids=["conductor", "pplastic"])
def test_wavefront_renders_rough_polarising_surfaces_as_the_megakernel(tmp_path, device, material):
    """Both kernel shapes run the same segment function, next-event estimation's polarised gather included: the
    same bits in the image through the camera's polariser and in every Stokes image."""
    from spectrace.engine.wavefront import WavefrontRenderer

    scene = _load(tmp_path, _scene(material, LIGHT).replace("fov = 2", "fov = 2\npolarizer_angle = 30"), "scene")
    megakernel = spectrace.render(scene, progress=False, colour_space="xyz")
    wavefront = WavefrontRenderer(scene, device).render()
    assert np.asarray(megakernel.xyz)[..., 1].mean() > 0.01
    assert np.array_equal(np.asarray(megakernel.xyz), np.asarray(wavefront.xyz))
    assert np.array_equal(megakernel.aovs["stokes"], wavefront.aovs["stokes"])


def _rotation(k: np.ndarray, x_from: np.ndarray, x_to: np.ndarray) -> np.ndarray:
    """Re-expresses a Stokes vector of a beam along k given in the basis x_from in the basis x_to (both normal to
    k, y = k × x)."""
    theta = np.arctan2(np.dot(np.cross(k, x_from), x_to), np.dot(x_from, x_to))
    c, s = np.cos(2 * theta), np.sin(2 * theta)
    return np.array([[1, 0, 0, 0], [0, c, s, 0], [0, -s, c, 0], [0, 0, 0, 1]], float)


def test_polarised_light_in_a_rough_conductor_follows_the_full_mueller_matrix(tmp_path):
    """A small area light emitting light polarised at 30° from its dp/du, seen in a rough conductor: next-event
    estimation and BSDF sampling both reach it, through the conductor's whole Fresnel matrix on the microfacet (its
    retardance turns part of the linear light circular). Each pixel's S1..S3 over S0 against the Mueller product
    computed here at the light's centre: the light's 0.05-wide face, 2.5 away, bounds the tolerance."""
    normal = _unit(-LIGHT)  # facing the plate's centre
    u_axis = _unit(np.cross([0.0, 0.0, 1.0], normal))
    v_axis = np.cross(normal, u_axis)
    rows = np.column_stack([0.025 * u_axis, 0.025 * v_axis, normal, LIGHT])
    matrix = ", ".join("[" + ", ".join(f"{x:.9f}" for x in row) + "]" for row in rows)
    light = f"""
[[shapes]]
type = "rectangle"
material = "black"
emitter = {{ radiance = {{ value = 4000 }}, polarization = "linear 30" }}
transform = [{{ matrix = [{matrix}, [0, 0, 0, 1]] }}]
"""
    text = _scene(CONDUCTOR, LIGHT, spp=64).split("[[lights]]")[0] + light
    stokes, _ = _render(tmp_path, text)
    points, wo, x, _ = _pixel_geometry()
    phi = np.radians(30.0)
    emitted = np.array([1.0, np.cos(2 * phi), np.sin(2 * phi), 0.0])
    expected = np.zeros((SIZE, SIZE, 4))
    for i in range(SIZE):
        for j in range(SIZE):
            k = _unit(points[i, j] - LIGHT)  # the light's way
            w_o = wo[i, j]
            h = _unit(w_o - k)
            s = _unit(np.cross(h, w_o))
            light_basis = _unit(u_axis - k * np.dot(k, u_axis))
            into_plane = _rotation(k, light_basis, s)
            out_of_plane = _rotation(w_o, s, x[i, j])
            fresnel = fresnel_reflection(np.dot(w_o, h), complex(1.2, 2.0))
            expected[i, j] = out_of_plane @ fresnel @ into_plane @ emitted
    expected = expected[..., 1:] / expected[..., :1]
    measured = stokes[..., 1:] / stokes[..., :1]
    assert np.abs(expected[..., 2]).min() > 0.05  # circular light: the retardance is tested
    assert np.all(np.abs(measured - expected) <= 0.02 * np.abs(expected) + 3e-3), (measured, expected)
