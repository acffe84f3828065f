"""`equirectangular`: the whole sphere of directions around `origin` as a latitude-longitude image
(kernels/camera.cl, CAMERA_EQUIRECTANGULAR), in the environment maps' convention (docs/scene-format.md): the image's
centre looks at `target`, `up` is its top row; columns span 360° of longitude, rows 180° of latitude. A 2:1 film
gives square texels of angle. Rendered with the frame looking along −z with +y up, the image is an environment map
that an `envmap` light without rotation reproduces."""

import numpy as np

from spectrace.cameras.shared import frame

NAME = "equirectangular"
MITSUBA_PLUGINS: tuple[str, ...] = ()
MITSUBA_NONE = "Mitsuba 3 has no such sensor"
# pbrt-v4's spherical camera with mapping "equirect" (its default, equalarea: spectrace.cameras.equalarea).
PBRT_CAMERAS = ("spherical",)
PBRT_CONDITION = ' (mapping "equirect" or "equalarea")'
# pbrt's longitude runs from +x toward +z, from right to left as seen from inside, where this camera's runs left to
# right: the import mirrors the world exactly when it does not for pbrt's other cameras (from_pbrt).
PBRT_MIRRORED = True
PARAMETERS = ()


def basis(camera, aspect_ratio: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    return frame(camera)


def lens(camera) -> tuple[float, float]:
    return 0.0, 0.0


def pbrt_maps(context, camera) -> bool:
    """Whether this module maps the pbrt-v4 spherical camera: its mapping "equirect"."""
    return context.string(camera, "mapping") == "equirect"


def from_pbrt(context, camera, view) -> dict | None:
    """pbrt-v4's spherical camera with mapping "equirect". pbrt-v4 (cameras.cpp, SphericalCamera::GenerateRay)
    sends film position (u, v) in [0, 1]² along θ = π v, φ = 2π u, camera direction (sin θ cos φ, cos θ,
    sin θ sin φ): row 0 toward the camera's +y, the image's centre (φ = π) along its −x, φ growing from +x toward +z.
    This camera (kernels/camera.cl) sends (u, v) along θ = π v, φ' = 2π u − π, sin θ sin φ' right + cos θ up +
    sin θ cos φ' forward. The two agree with up = the camera's +y, forward = its −x and right = forward × up = its
    −z, which holds when the world is mirrored exactly when the perspective camera's is not (PBRT_MIRRORED)."""
    if (mapping := context.string(camera, "mapping") or "equalarea") == "equalarea":
        return None  # the equalarea camera's
    if mapping != "equirect":
        raise context.error(
            camera.location,
            f"spherical camera mapping '{context.shown(mapping)}': spectrace imports \"equirect\" (its "
            'equirectangular camera) and "equalarea" (its equalarea camera)',
        )
    if view.lens_radius > 0.0:
        context.warn(camera.location, '"lensradius" not imported: the spherical camera is a pinhole')
    if view.window is not None:
        context.warn(camera.location, '"screenwindow" not imported: the spherical camera covers the whole sphere')
    forward = (-np.asarray(context.direction(view.world_from_camera, [1.0, 0.0, 0.0]))).tolist()
    return {
        "type": "equirectangular",
        "origin": view.origin,
        "target": (np.asarray(view.origin) + np.asarray(forward)).tolist(),
        "up": view.up,
    }
