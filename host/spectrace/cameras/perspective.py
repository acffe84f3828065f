"""`perspective`: a pinhole camera (kernels/camera.cl, CAMERA_PERSPECTIVE)."""

import numpy as np

from spectrace.cameras.shared import FOV, FOV_AXIS, perspective_basis

NAME = "perspective"
MITSUBA_PLUGINS = ("perspective",)
# pbrt-v4's perspective camera without a lens (thinlens.py takes one with lensradius > 0).
PBRT_CAMERAS = ("perspective",)
PARAMETERS = (FOV, FOV_AXIS)
PBRT_DEFAULT_FOV = 90.0


def basis(camera, aspect_ratio: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    return perspective_basis(camera, aspect_ratio)


def lens(camera) -> tuple[float, float]:
    return 0.0, 0.0


def from_pbrt(context, camera, view) -> dict | None:
    """pbrt-v4's pinhole perspective camera, or None for one with a lens (thinlens.py's)."""
    if view.lens_radius > 0.0:
        return None
    return pbrt_perspective(context, camera, view)


def pbrt_perspective(context, camera, view) -> dict:
    """The table of a pbrt-v4 perspective camera's view: pbrt's `fov` spans the frame's shorter side."""
    if view.window is not None:
        context.warn(view.window.location, '"screenwindow" not imported (the image spans pbrt\'s default window)')
    fov = context.one(camera, "fov", PBRT_DEFAULT_FOV)
    if not 0.0 < fov < 180.0:
        raise context.error(camera.location, f"fov must lie in (0, 180) degrees, got {fov:g}")
    return {
        "origin": view.origin,
        "target": (np.asarray(view.origin) + np.asarray(view.forward)).tolist(),
        "up": view.up,
        "fov": fov,
        "fov_axis": "y" if view.aspect > 1.0 else "x",
    }


def from_mitsuba(importer, sensor, properties, camera: dict, linear: np.ndarray, aspect: float) -> dict:
    """Mitsuba's perspective sensor: its fov (with fov_axis, or from focal_length) as the horizontal fov."""
    return camera | {"fov": importer.fov_x(properties, aspect, sensor), "fov_axis": "x"}


def to_mitsuba(camera, exporter) -> dict:
    return {
        "type": camera.type,
        "fov": float(camera.fov_degrees),
        "fov_axis": camera.fov_axis,
        "to_world": exporter.camera_to_world(camera),
    }
