"""Dispersion in the light tracer: a nearly parallel beam of two spectral lines (450 and 650 nm) from a far spot light
passes the built-in SF11 prism near minimum deviation and lands on a screen 50 units away as two lines, at the
places Snell's law at both faces and the glass's Sellmeier index send them (spectrace.validation's prism geometry and
deviation formula). A path tracer cannot render this at all (a point light seen through glass)."""

import numpy as np

from spectrace.engine.renderer import Renderer
from spectrace.geometry import primitives
from spectrace.geometry.mesh import TriangleMesh
from spectrace.materials.dielectric import DielectricMaterial
from spectrace.scene.model import Camera, DiffuseMaterial, Scene, Shape, SpotLight
from spectrace.spectral.glasses import glass
from spectrace.spectral.grid import GRID_NM
from spectrace.spectral.spectrum import Spectrum
from spectrace.validation import PRISM_GLASS, PRISM_INCIDENCE_DEGREES, prism_deviation_degrees

LINES_NM = (450.0, 650.0)
SCREEN_DISTANCE = 50.0
CAMERA_DISTANCE = 12.0
WIDTH, HEIGHT = 160, 16


def _turned(vector: np.ndarray, degrees: float) -> np.ndarray:
    """`vector` (in the xy plane) turned counter-clockwise about +z."""
    c, s = np.cos(np.radians(degrees)), np.sin(np.radians(degrees))
    return np.array([c * vector[0] - s * vector[1], s * vector[0] + c * vector[1], 0.0])


OUTWARD_LEFT = np.array([-np.sqrt(3.0) / 2.0, 0.5, 0.0])  # the built-in prism's left face normal
ENTRY = np.array([-0.5, 0.5 / np.sqrt(3.0), 0.0])  # midpoints of its left and right faces
EXIT = np.array([0.5, 0.5 / np.sqrt(3.0), 0.0])
BEAM = _turned(-OUTWARD_LEFT, PRISM_INCIDENCE_DEGREES)


def _leaving(wavelength_nm: float) -> np.ndarray:
    n = float(glass(PRISM_GLASS).ior(wavelength_nm))
    return _turned(BEAM, -prism_deviation_degrees(n, PRISM_INCIDENCE_DEGREES))


def _scene() -> Scene:
    axis = _leaving(550.0)
    centre = EXIT + SCREEN_DISTANCE * axis
    across = np.array([-axis[1], axis[0], 0.0]) * 15.0
    up = np.array([0.0, 0.0, 3.0])
    corners = np.array([centre - across - up, centre + across - up, centre + across + up, centre - across + up])
    faces = np.array([[0, 1, 2], [0, 2, 3]])
    if np.dot(np.cross(corners[1] - corners[0], corners[2] - corners[0]), -axis) < 0:
        faces = faces[:, ::-1]
    screen = Shape(mesh=TriangleMesh(vertices=corners, faces=faces), material=DiffuseMaterial(Spectrum.constant(0.8)))
    prism = Shape(mesh=primitives.prism(), material=DielectricMaterial(glass(PRISM_GLASS).index_of_refraction()))
    lines = sum(np.exp(-0.5 * ((GRID_NM - line) / 0.5) ** 2) for line in LINES_NM)
    # 1000 units away, a cone of 0.3 units' radius at the prism: the beam enters the left face around its middle.
    lamp = SpotLight(
        position=tuple(ENTRY - 1000.0 * BEAM),
        direction=tuple(BEAM),
        intensity=Spectrum(1e6 * lines, name="two lines"),
        cutoff_degrees=float(np.degrees(np.arctan(0.3 / 1000.0))),
        falloff_start_degrees=0.9 * float(np.degrees(np.arctan(0.3 / 1000.0))),
    )
    camera = Camera(
        origin=tuple(centre - CAMERA_DISTANCE * axis),
        target=tuple(centre),
        up=(0.0, 0.0, 1.0),
        fov_degrees=float(2 * np.degrees(np.arctan(8.0 / CAMERA_DISTANCE))),
    )
    return Scene(
        camera=camera, width=WIDTH, height=HEIGHT, shapes=[prism, screen], lights=[lamp], integrator="light",
        max_depth=4, spp=32, seed=2,
    )  # fmt: skip


def _pixel_column(scene: Scene, point: np.ndarray) -> float:
    """Where a point lands across the image, in pixels from the left edge (camera.cl's mapping inverted)."""
    origin, forward, right, _ = scene.camera.basis(scene.width / scene.height)
    d = point - origin
    ndc_x = np.dot(d, right) / (np.dot(right, right) * np.dot(d, forward))
    return 0.5 * (ndc_x + 1.0) * scene.width


def _where_the_line_lands(scene: Scene, wavelength_nm: float) -> float:
    axis = _leaving(550.0)
    centre = EXIT + SCREEN_DISTANCE * axis
    leaving = _leaving(wavelength_nm)
    t = np.dot(centre - EXIT, axis) / np.dot(leaving, axis)
    return _pixel_column(scene, EXIT + t * leaving)


def test_spectral_lines_land_where_snells_law_sends_them(device):
    scene = _scene()
    profile = Renderer(scene, device).render().xyz[..., 1].astype(np.float64).sum(axis=0)
    expected = [_where_the_line_lands(scene, line) for line in LINES_NM]
    assert abs(expected[0] - expected[1]) > 20  # the two lines are far apart on the film
    middle = int(round(0.5 * (expected[0] + expected[1])))
    columns = np.arange(scene.width) + 0.5
    for line, where in zip(LINES_NM, expected, strict=True):
        side = slice(0, middle) if where < middle else slice(middle, scene.width)
        weights = profile[side]
        assert weights.sum() > 0, f"no light at {line} nm"
        centroid = float(np.sum(columns[side] * weights) / weights.sum())
        # The beam is 0.6 units (6 pixels) wide; its rays leave the prism within about 0.02 units of the exit face's
        # middle, whichever their wavelength.
        assert abs(centroid - where) < 0.5, (line, centroid, where)
