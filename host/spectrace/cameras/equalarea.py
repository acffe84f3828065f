"""`equalarea`: the whole sphere of directions around `origin` on a square film by Clarberg's equal-area
octahedral mapping (kernels/camera_equal_area.cl; pbrt-v4's `spherical` camera with mapping "equalarea"), so every
pixel sees the same solid angle, 4π / pixel count. The image's centre looks at `target`, its four corners straight
away from it, its right toward forward × up and its bottom down; the circle through the midpoints of its edges is
the horizon at right angles to the view."""

import numpy as np

from spectrace.cameras.shared import frame

NAME = "equalarea"
MITSUBA_PLUGINS: tuple[str, ...] = ()
MITSUBA_NONE = "Mitsuba 3 has no such sensor"
PBRT_CAMERAS = ("spherical",)
PARAMETERS = ()


def basis(camera, aspect_ratio: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    return frame(camera)


def lens(camera) -> tuple[float, float]:
    return 0.0, 0.0


def pbrt_maps(context, camera) -> bool:
    """Whether this module maps the pbrt-v4 spherical camera: its mapping "equalarea", pbrt-v4's default."""
    return (context.string(camera, "mapping") or "equalarea") == "equalarea"


def from_pbrt(context, camera, view) -> dict | None:
    """pbrt-v4's spherical camera with mapping "equalarea" (cameras.cpp, SphericalCamera::GenerateRay): film
    position (u, v) in [0, 1]² looks along d = EqualAreaSquareToSphere(u, v) with d's y and z swapped, the camera
    direction (dx, dz, dy): the image's centre along the camera's +y, u toward its +x, v toward its +z. This camera
    looks along dx·right − dy·up + dz·forward, which is that with forward = the camera's +y, up = its −z and right
    = forward × up = its +x, in the world the perspective camera is imported into (image right = the camera's +x)."""
    if not pbrt_maps(context, camera):
        return None
    if view.lens_radius > 0.0:
        context.warn(camera.location, '"lensradius" not imported: the spherical camera is a pinhole')
    if view.window is not None:
        context.warn(camera.location, '"screenwindow" not imported: the spherical camera covers the whole sphere')
    if view.width != view.height:
        context.warn(camera.location, "the equal-area map is square: a film of another shape stretches it")
    return {
        "type": "equalarea",
        "origin": view.origin,
        "target": (np.asarray(view.origin) + np.asarray(view.up)).tolist(),
        "up": (-np.asarray(view.forward)).tolist(),
    }
