"""`orthographic`: parallel projection (kernels/camera.cl, CAMERA_ORTHOGRAPHIC): every ray runs along the view
axis, from a point of the plane through `origin` facing it; the image covers `view_width` scene units across and
view_width / aspect ratio up, so an object's image size is its world size whatever its distance."""

import numpy as np

from spectrace.cameras.shared import frame
from spectrace.core.parameters import REQUIRED, Parameter, Range

NAME = "orthographic"
MITSUBA_PLUGINS = ("orthographic",)
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
