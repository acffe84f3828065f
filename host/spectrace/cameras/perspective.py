"""`perspective`: a pinhole camera (kernels/camera.cl, CAMERA_PERSPECTIVE)."""

import numpy as np

from spectrace.cameras.shared import FOV, FOV_AXIS, perspective_basis

NAME = "perspective"
MITSUBA_PLUGINS = ("perspective",)
PARAMETERS = (FOV, FOV_AXIS)


def basis(camera, aspect_ratio: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    return perspective_basis(camera, aspect_ratio)


def lens(camera) -> tuple[float, float]:
    return 0.0, 0.0
