"""The keys every camera takes, and the frame they set (origin, forward, and image right = forward × up)."""

import numpy as np

from spectrace.core.parameters import REQUIRED, Parameter, Range

ORIGIN = Parameter("origin", "vector", "scene units", REQUIRED, doc="where the camera is (the lens's centre)")
TARGET = Parameter("target", "vector", "scene units", REQUIRED, doc="a point the camera looks at")
UP = Parameter("up", "vector", "", (0.0, 1.0, 0.0), doc="the image's up direction (need not be orthogonal)")
NEAR_CLIP = Parameter(
    "near_clip",
    "float",
    "scene units",
    0.0,
    Range(0.0),
    doc="distance along the view axis before which nothing is seen",
)
FAR_CLIP = Parameter(
    "far_clip",
    "float",
    "scene units",
    None,
    Range(0.0, low_open=True),
    doc="distance along the view axis beyond which nothing is seen (none: no limit); more than near_clip",
)
POLARIZER_ANGLE = Parameter(
    "polarizer_angle",
    "float",
    "degrees",
    None,
    Range(-360.0, 360.0),
    default_doc="none",
    doc="a linear polariser in front of the lens, its axis this far from the image's right toward its up (a "
    "polarised render: [polarization.md](polarization.md)); none: no filter",
)
PARAMETERS = (ORIGIN, TARGET, UP, NEAR_CLIP, FAR_CLIP, POLARIZER_ANGLE)

FOV = Parameter(
    "fov",
    "float",
    "degrees",
    REQUIRED,
    Range(0.0, 180.0, low_open=True, high_open=True),
    doc="full field of view along fov_axis",
    api_name="fov_degrees",
    schema_range=False,  # checked by the schema's validator, whose message names the range in degrees
)
FOV_AXIS = Parameter("fov_axis", "axis", "", "x", doc='"x" or "y": the image axis fov spans', type_doc='"x" or "y"')


def clip_problem(camera) -> str | None:
    """Why the camera's far clip cannot be, or None: it must lie beyond the near one."""
    if camera.far_clip is not None and not camera.far_clip > camera.near_clip:
        return f"far_clip ({camera.far_clip:g}) must be more than near_clip ({camera.near_clip:g})"
    return None


def frame(camera) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """origin, unit forward, unit right = forward × up, unit up (orthogonalised)."""
    origin = np.asarray(camera.origin, float)
    forward = np.asarray(camera.target, float) - origin
    forward /= np.linalg.norm(forward)
    right = np.cross(forward, np.asarray(camera.up, float))
    right /= np.linalg.norm(right)
    return origin, forward, right, np.cross(right, forward)


def perspective_basis(camera, aspect_ratio: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """origin, forward, right·tan(fov_x/2), up·tan(fov_y/2) for an image of width/height = aspect_ratio."""
    origin, forward, right, up = frame(camera)
    tan_half = np.tan(np.radians(camera.fov_degrees) / 2.0)
    if camera.fov_axis == "x":
        tan_x, tan_y = tan_half, tan_half / aspect_ratio
    else:
        tan_x, tan_y = tan_half * aspect_ratio, tan_half
    return origin, forward, right * tan_x, up * tan_y
