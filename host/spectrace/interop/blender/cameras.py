"""Blender's camera as spectrace's `[camera]` and `[film]`: it looks along its object's −z with +y up. The sensor
fit decides which image axis the field of view (perspective: 2 atan(sensor / 2 lens)) or the orthographic scale
spans: Auto the larger one with the sensor width, Horizontal the width, Vertical the height with the sensor
height. Depth of field is Cycles' thin lens: aperture radius = lens (mm) / 1000 / (2 f-stop) in scene units (the
millimetres taken as metres per unit, as Cycles does), focus on the focus object or at the focus distance."""

from __future__ import annotations

import math

import numpy as np

from spectrace.interop.blender.context import BlendImport


def film(scene) -> tuple[int, int]:
    render = scene.render
    width = max(1, round(render.resolution_x * render.resolution_percentage / 100))
    height = max(1, round(render.resolution_y * render.resolution_percentage / 100))
    return width, height


# Cycles' Blackman-Harris filter of width w (intern/cycles/scene/film.cpp: the window spans [−w, w], its standard
# deviation 0.277 w) as the windowed Gaussian of radius w with the same standard deviation: σ = 0.280 w; the two
# shapes differ by at most 2.6 % of their peak.
_BLACKMAN_HARRIS_STDDEV = 0.280


def pixel_filter(scene) -> dict | None:
    """Cycles' pixel filter as spectrace's: Box of width w a box of radius w/2; Gaussian of width w Cycles'
    exp(−8 x²/w²) over [−1.5 w, 1.5 w], σ = w/4; Blackman-Harris as above."""
    cycles = getattr(scene, "cycles", None)
    if cycles is None:
        return None
    width = float(cycles.filter_width)
    kind = cycles.pixel_filter_type
    if kind == "BOX":
        return {"type": "box", "radius": width / 2.0}
    if kind == "GAUSSIAN":
        return {"type": "gaussian", "stddev": width / 4.0, "radius": 1.5 * width}
    return {"type": "gaussian", "stddev": _BLACKMAN_HARRIS_STDDEV * width, "radius": width}


def camera(ctx: BlendImport, scene, obj, matrix: np.ndarray) -> tuple[dict, dict]:
    data = obj.data
    where = f"camera '{obj.name}'"
    width, height = film(scene)
    aspect = (width * scene.render.pixel_aspect_x) / (height * scene.render.pixel_aspect_y)
    origin = matrix[:3, 3]
    forward = matrix[:3, :3] @ np.array([0.0, 0.0, -1.0])
    up = matrix[:3, :3] @ np.array([0.0, 1.0, 0.0])
    forward, up = forward / np.linalg.norm(forward), up / np.linalg.norm(up)
    table: dict = {
        "origin": [float(v) for v in origin],
        "target": [float(v) for v in origin + forward],
        "up": [float(v) for v in up],
    }
    fit = data.sensor_fit
    axis = ("x" if aspect >= 1.0 else "y") if fit == "AUTO" else ("x" if fit == "HORIZONTAL" else "y")
    if data.shift_x != 0.0 or data.shift_y != 0.0:
        ctx.warn(where, "lens shift is not imported")
    if data.type == "ORTHO":
        span = float(data.ortho_scale)
        table |= {"type": "orthographic", "view_width": span if axis == "x" else span * aspect}
    elif data.type == "PERSP":
        sensor = float(data.sensor_height if fit == "VERTICAL" else data.sensor_width)
        fov = math.degrees(2.0 * math.atan(sensor / (2.0 * float(data.lens))))
        table |= {"type": "perspective", "fov": fov, "fov_axis": axis}
        if data.dof.use_dof:
            if data.dof.focus_object is not None:
                target = np.array(data.dof.focus_object.matrix_world.translation)
                focus = float(np.dot(target - origin, forward))
            else:
                focus = float(data.dof.focus_distance)
            table["type"] = "thinlens"
            table["aperture_radius"] = float(data.lens) / 1000.0 / (2.0 * float(data.dof.aperture_fstop))
            if focus > 0.0:
                table["focus_distance"] = focus
            if data.dof.aperture_blades >= 3:
                ctx.warn(where, "a polygonal aperture is imported as a round one")
    else:
        ctx.warn(where, f"camera type {data.type} is imported as a 50 mm perspective camera")
        table |= {"type": "perspective", "fov": 39.6, "fov_axis": "x"}
    if data.clip_start > 0.0:
        table["near_clip"] = float(data.clip_start)
    if data.clip_end > data.clip_start:
        table["far_clip"] = float(data.clip_end)
    film_table: dict = {"width": width, "height": height}
    if (found := pixel_filter(scene)) is not None:
        film_table["filter"] = found
    return table, film_table
