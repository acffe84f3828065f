"""`orthographic`: parallel projection (kernels/camera.cl, CAMERA_ORTHOGRAPHIC): every ray runs along the view
axis, from a point of the plane through `origin` facing it; the image covers `view_width` scene units across and
view_width / aspect ratio up, so an object's image size is its world size whatever its distance."""

import math

import numpy as np

from spectrace.cameras.shared import frame
from spectrace.core.parameters import REQUIRED, Parameter, Range

NAME = "orthographic"
MITSUBA_PLUGINS = ("orthographic",)
PBRT_CAMERAS = ("orthographic",)
VIEW_WIDTH = Parameter(
    "view_width",
    "float",
    "scene units",
    REQUIRED,
    Range(0.0, low_open=True),
    doc="the width the image covers; its height follows the film's aspect ratio",
)
PARAMETERS = (VIEW_WIDTH,)


def basis(camera, aspect_ratio: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    origin, forward, right, up = frame(camera)
    half = camera.view_width / 2.0
    return origin, forward, right * half, up * (half / aspect_ratio)


def lens(camera) -> tuple[float, float]:
    return 0.0, 0.0


def from_pbrt(context, camera, view) -> dict:
    """pbrt-v4's orthographic camera: its screen window (pbrt's default spans [-1, 1] along the frame's shorter
    side) sets view_width; an off-centre window moves the view's centre in the camera's plane."""
    x0, x1, y0, y1 = context.floats(camera, "screenwindow", view.default_window) or view.default_window
    if not (x1 > x0 and y1 > y0):
        raise context.error(camera.location, "screenwindow must have x0 < x1 and y0 < y1")
    if not math.isclose((x1 - x0) / (y1 - y0), view.width / view.height, rel_tol=1e-4):
        context.warn(
            camera.location, "the screen window's aspect ratio differs from the film's: the window's width is kept"
        )
    # pbrt's camera x is image right.
    centre = context.point(view.world_from_camera, [(x0 + x1) / 2.0, (y0 + y1) / 2.0, 0.0])
    table = {
        "type": "orthographic",
        "origin": centre,
        "target": (np.asarray(centre) + np.asarray(view.forward)).tolist(),
        "up": view.up,
        "view_width": x1 - x0,
    }
    if view.lens_radius > 0.0:
        context.warn(camera.location, '"lensradius" not imported: spectrace\'s orthographic camera is sharp')
    return table


def from_mitsuba(importer, sensor, properties, camera: dict, linear: np.ndarray, aspect: float) -> dict | None:
    """Mitsuba's view spans [-1, 1] along camera x and [-1/aspect, 1/aspect] along y, then to_world scales it."""
    half_x, half_y = np.linalg.norm(linear @ [1.0, 0.0, 0.0]), np.linalg.norm(linear @ [0.0, 1.0, 0.0])
    if not math.isclose(half_x, half_y, rel_tol=1e-6):
        importer.unsupported_plugin(sensor, " whose to_world scales x and y differently")
        return None
    return camera | {"view_width": 2.0 * float(half_x)}


def to_mitsuba(camera, exporter) -> dict:
    """Mitsuba's orthographic view spans [-1, 1] across, scaled by to_world."""
    return {"type": "orthographic", "to_world": exporter.camera_to_world(camera, float(camera.view_width) / 2.0)}
