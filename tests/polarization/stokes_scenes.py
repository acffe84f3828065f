"""Small scenes for the polarisation tests and what they measure: the mean Stokes images (Y of S0..S3 over the
pixels, with their standard errors from the pixels' spread) of a render with the `stokes` AOV, and the Mueller
matrices of the closed forms (E. Collett, "Field Guide to Polarization"), written here independently of the
kernels: a Stokes vector (S0, S1, S2, S3) in a basis (x, y = k × x), angles from x toward y.

Every scene asks for the `stokes` and `dolp` AOVs and renders with the general kernels the suite uses, so the tests
build one polarised program between them."""

from dataclasses import dataclass
from pathlib import Path

import numpy as np

import spectrace
from spectrace.scene.loader import load_scene

SIZE = 8


@dataclass
class Measured:
    stokes: np.ndarray  # mean Y of S0..S3 over the pixels
    stderr: np.ndarray  # their standard errors (the pixels' spread over √pixels)
    image_y: float  # mean Y of the image (through the camera's polariser, when it has one)
    image_stderr: float
    dolp: np.ndarray  # the degree of linear polarisation of each pixel


def measure(tmp_path: Path, text: str, name: str = "scene") -> Measured:
    path = tmp_path / f"{name}.toml"
    path.write_text(text)
    image = spectrace.render(load_scene(path), progress=False, colour_space="xyz")
    stokes = image.aovs["stokes"].reshape(-1, 4, 3)[:, :, 1].astype(np.float64)
    y = np.asarray(image.xyz, np.float64)[..., 1].ravel()
    n = stokes.shape[0]
    return Measured(
        stokes.mean(axis=0),
        stokes.std(axis=0, ddof=1) / np.sqrt(n),
        float(y.mean()),
        float(y.std(ddof=1) / np.sqrt(n)),
        np.asarray(image.aovs["dolp"], np.float64).ravel(),
    )


def header(camera: str = "", spp: int = 16, max_depth: int = 6, more: str = "") -> str:
    """A camera 3 units up +z looking down at the origin (image right +x, up +y) unless `camera` gives other keys."""
    camera = camera or "origin = [0, 0, 3]\ntarget = [0, 0, 0]\nfov = 10"
    return f"""
[camera]
{camera}

[film]
width = {SIZE}
height = {SIZE}
aovs = ["stokes", "dolp"]

[integrator]
max_depth = {max_depth}
{more}

[sampler]
spp = {spp}

[materials.black]
type = "diffuse"
reflectance = {{ value = 0 }}
"""


def sheets(*tables: str, camera: str = "") -> str:
    """An emitter of radiance 1 in the plane z = 0 seen by the header's camera through sheets parallel to it, the
    first nearest the emitter; each of `tables` is a material table's keys (type, angle, ...)."""
    text = (
        header(camera)
        + """
[[shapes]]
type = "rectangle"
material = "black"
emitter = { radiance = { value = 1 } }
transform = [{ scale = [2, 2, 1] }]
"""
    )
    for i, table in enumerate(tables):
        text += f"""
[materials.sheet{i}]
{table}

[[shapes]]
type = "rectangle"
material = "sheet{i}"
transform = [{{ translate = [0, 0, {1.0 + 0.25 * i}] }}]
"""
    return text


def rotator(theta: float) -> np.ndarray:
    """Re-expresses a Stokes vector in the basis turned by theta (radians)."""
    c, s = np.cos(2 * theta), np.sin(2 * theta)
    return np.array([[1, 0, 0, 0], [0, c, s, 0], [0, -s, c, 0], [0, 0, 0, 1]], float)


def aligned(element: np.ndarray, theta: float) -> np.ndarray:
    """An element given with its axis along x, turned to lie theta from x."""
    return rotator(-theta) @ element @ rotator(theta)


def polarizer(theta: float, k1: float = 1.0, k2: float = 0.0) -> np.ndarray:
    a, b, c = (k1 + k2) / 2, (k1 - k2) / 2, np.sqrt(k1 * k2)
    return aligned(np.array([[a, b, 0, 0], [b, a, 0, 0], [0, 0, c, 0], [0, 0, 0, c]], float), theta)


def retarder(theta: float, delta: float) -> np.ndarray:
    c, s = np.cos(delta), np.sin(delta)
    return aligned(np.array([[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, c, s], [0, 0, -s, c]], float), theta)


UNPOLARIZED = np.array([1.0, 0.0, 0.0, 0.0])


def fresnel_amplitudes(cos_i: float, eta: complex) -> tuple[complex, complex]:
    """Born & Wolf's r_s, r_p of light at cos θi onto relative index eta (complex for a conductor)."""
    sin2_t = (1 - cos_i**2) / eta**2
    cos_t = np.sqrt(complex(1 - sin2_t))
    r_s = (cos_i - eta * cos_t) / (cos_i + eta * cos_t)
    r_p = (eta * cos_i - cos_t) / (eta * cos_i + cos_t)
    return r_s, r_p


def fresnel_reflection(cos_i: float, eta: complex) -> np.ndarray:
    """The reflection's Mueller matrix in the s/p basis (x = s for both beams), Stokes vectors in Collett's
    convention: his fields go as exp(iωt), Born & Wolf's as exp(−iωt), so his amplitudes are the conjugates of these
    (the retardance entry Im(r_s* r_p); test_handedness checks the sense against Maxwell's equations)."""
    r_s, r_p = fresnel_amplitudes(cos_i, eta)
    ss, pp, cross = abs(r_s) ** 2, abs(r_p) ** 2, np.conj(r_s) * r_p
    a, b, c, d = (ss + pp) / 2, (ss - pp) / 2, cross.real, cross.imag
    return np.array([[a, b, 0, 0], [b, a, 0, 0], [0, 0, c, d], [0, 0, -d, c]], float)
