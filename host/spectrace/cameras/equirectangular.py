"""`equirectangular`: the whole sphere of directions around `origin` as a latitude-longitude image
(kernels/camera.cl, CAMERA_EQUIRECTANGULAR), in the environment maps' convention (docs/scene-format.md): the image's
centre looks at `target`, `up` is its top row; columns span 360° of longitude, rows 180° of latitude. A 2:1 film
gives square texels of angle. Rendered with the frame looking along −z with +y up, the image is an environment map
that an `envmap` light without rotation reproduces."""

import numpy as np

from spectrace.cameras.shared import frame

NAME = "equirectangular"
MITSUBA_PLUGINS: tuple[str, ...] = ()  # Mitsuba 3 has no such sensor
PARAMETERS = ()


def basis(camera, aspect_ratio: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    return frame(camera)


def lens(camera) -> tuple[float, float]:
    return 0.0, 0.0
