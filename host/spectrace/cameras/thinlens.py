"""`thinlens`: a perspective camera with a thin lens, for depth of field (kernels/camera.cl, CAMERA_THINLENS;
Pharr, Jakob & Humphreys, 4th ed., 5.2.3; Mitsuba 3's `thinlens`).

Points at `focus_distance` (measured along the view axis) image sharply; a point at distance z images to a disk,
the circle of confusion, whose radius on the plane of focus is aperture_radius · |z − focus_distance| / z, i.e.
that divided by focus_distance · tan(fov/2) in half image widths. The image records radiance as the pinhole does
(the flux through the aperture divided by its area), so a wider aperture blurs more without brightening.
The aperture is `aperture_radius`, or `f_number` with the lens's `focal_length` (radius = focal_length / 2N)."""

import numpy as np

from spectrace.cameras import perspective
from spectrace.cameras.perspective import pbrt_perspective
from spectrace.cameras.shared import FOV, FOV_AXIS, perspective_basis
from spectrace.core.parameters import Parameter, Range

NAME = "thinlens"
MITSUBA_PLUGINS = ("thinlens",)
# pbrt-v4's perspective camera with lensradius > 0 (perspective.py takes one without).
PBRT_CAMERAS = ("perspective",)
APERTURE_RADIUS = Parameter(
    "aperture_radius", "float", "scene units", None, Range(0.0), doc="the lens's radius; or give f_number"
)
F_NUMBER = Parameter(
    "f_number", "float", "", None, Range(0.0, low_open=True), doc="focal_length / aperture diameter, with focal_length"
)
FOCAL_LENGTH = Parameter(
    "focal_length", "float", "scene units", None, Range(0.0, low_open=True), doc="the lens's, for f_number"
)
FOCUS_DISTANCE = Parameter(
    "focus_distance",
    "float",
    "scene units",
    None,
    Range(0.0, low_open=True),
    default_doc="the distance to target",
    doc="distance along the view axis of the plane in focus",
)
PARAMETERS = (FOV, FOV_AXIS, APERTURE_RADIUS, F_NUMBER, FOCAL_LENGTH, FOCUS_DISTANCE)


def aperture_problem(aperture_radius, f_number, focal_length) -> str | None:
    """Why the keys do not set one aperture, or None."""
    if (aperture_radius is None) == (f_number is None):
        return "give exactly one of aperture_radius, f_number"
    if (f_number is None) != (focal_length is None):
        return "f_number and focal_length go together"
    return None


def check_spec(spec) -> None:
    if problem := aperture_problem(spec.aperture_radius, spec.f_number, spec.focal_length):
        raise ValueError(problem)


SPEC_CHECKS = (check_spec,)


def aperture_radius(aperture_radius, f_number, focal_length) -> float:
    return float(aperture_radius) if aperture_radius is not None else float(focal_length) / (2.0 * float(f_number))


def basis(camera, aspect_ratio: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    return perspective_basis(camera, aspect_ratio)


def lens(camera) -> tuple[float, float]:
    return camera.aperture_radius, camera.focus_distance


def from_pbrt(context, camera, view) -> dict | None:
    """pbrt-v4's perspective camera with a lens (lensradius > 0; focaldistance 1e6 by default), or None."""
    if not view.lens_radius > 0.0:
        return None
    table = pbrt_perspective(context, camera, view)
    if not view.focus > 0.0:
        raise context.error(camera.location, f"focaldistance must be > 0, got {view.focus:g}")
    return {"type": "thinlens", **table, "aperture_radius": view.lens_radius, "focus_distance": view.focus}


def from_mitsuba(importer, sensor, properties, camera: dict, linear: np.ndarray, aspect: float) -> dict | None:
    """Mitsuba's thinlens: a perspective view, aperture_radius (required, as in Mitsuba) and focus_distance."""
    camera = perspective.from_mitsuba(importer, sensor, properties, camera, linear, aspect)
    if "aperture_radius" not in properties:
        raise importer.fail(sensor, "thinlens needs aperture_radius (Mitsuba 3 requires it too)", "type")
    aperture = importer.number(properties["aperture_radius"])
    # Mitsuba's default focus is 10 000 scene units away: as good as infinity for a scene of metres.
    focus = importer.number(properties["focus_distance"]) if "focus_distance" in properties else 1e4
    if not aperture >= 0.0 or not focus > 0.0:
        raise importer.fail(sensor, "thinlens needs aperture_radius >= 0 and focus_distance > 0", "type")
    return camera | {"aperture_radius": aperture, "focus_distance": focus}


def to_mitsuba(camera, exporter) -> dict:
    return perspective.to_mitsuba(camera, exporter) | {
        "aperture_radius": float(camera.aperture_radius),
        "focus_distance": float(camera.focus_distance),
    }
