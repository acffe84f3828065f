"""The cameras (kernels/camera.cl): one module per type, each with its parameter table (the keys it takes beside
the shared ones in `shared.py`), the Mitsuba 3 plugins it imports and how it fills the RenderParams' camera fields.
`CAMERAS` lists them; a camera's position there is its device code (RenderParams.camera_type, CAMERA_<NAME> in the
kernels: `generated_sources`)."""

from spectrace.cameras import equalarea, equirectangular, orthographic, perspective, realistic, thinlens
from spectrace.cameras.base import CameraPlugin
from spectrace.core.contract import GeneratedSources
from spectrace.core.registry import Registry

CAMERAS = Registry[CameraPlugin]("camera", (perspective, thinlens, orthographic, equirectangular, equalarea, realistic))


def generated_sources() -> GeneratedSources:
    """CAMERA_<NAME> and CAMERA_TYPE_COUNT, which every kernel that makes camera rays is built with."""
    return GeneratedSources(CAMERAS.kernel_defines("CAMERA"))
