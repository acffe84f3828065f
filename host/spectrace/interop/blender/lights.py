"""Blender's lights in Blender's units, as Cycles renders them: a point or spot light's Power P (W) is a radiant
intensity I = P / 4π W/sr (a spot's cone cuts that intensity, it does not concentrate it), a sun's Strength S
(W/m²) the irradiance on a surface facing it, an area light's Power P its flux out of one face: radiance
L = P / (π A) over its world area A. The colour c is linear Rec.709 RGB; each becomes `{ rgb = c, scale = ... }`,
spectrace's D65-based uplift, so that an RGB render of the light's effect equals Cycles'. Lights shine along their
object's −z."""

from __future__ import annotations

import math

import numpy as np

from spectrace.interop.blender.context import BlendImport


def _colour(light) -> list[float]:
    colour = [float(v) for v in light.color]
    if getattr(light, "use_temperature", False):
        colour = [c * float(t) for c, t in zip(colour, light.temperature_color, strict=True)]
    return colour


def _power(light) -> float:
    """The light's Power (Strength for a sun) times 2^Exposure, as Cycles scales it."""
    return float(light.energy) * 2.0 ** float(getattr(light, "exposure", 0.0))


def light(ctx: BlendImport, obj, matrix: np.ndarray) -> tuple[list[dict], list[dict]]:
    """([[lights]] rows, [[shapes]] rows) of one light object placed by `matrix` (4×4, world)."""
    data = obj.data
    where = f"light '{obj.name}'"
    position = [float(v) for v in matrix[:3, 3]]
    axis = matrix[:3, :3] @ np.array([0.0, 0.0, -1.0])
    norm = float(np.linalg.norm(axis))
    if norm == 0.0:
        ctx.warn(where, "a light scaled to nothing is left out")
        return [], []
    axis = axis / norm
    colour = _colour(data)
    power = _power(data)
    if power <= 0.0 or max(colour) <= 0.0:
        return [], []
    if not getattr(data, "normalize", True) and data.type != "SUN":
        ctx.warn(where, "Normalize off is not imported (the power is spread over the light's size)")
    kind = data.type
    if kind in ("POINT", "SPOT") and getattr(data, "shadow_soft_size", 0.0) > 0.0:
        ctx.warn(where, "the radius of point and spot lights is not imported (they become points: hard shadows)")
    if kind == "POINT":
        intensity = {"rgb": colour, "scale": power / (4.0 * math.pi)}
        return [{"type": "point", "position": position, "intensity": intensity}], []
    if kind == "SPOT":
        half = float(data.spot_size) / 2.0
        # Cycles' blend: a smoothstep from the cone's edge over blend · (1 − cos half) in cos θ
        start = math.acos(min(1.0, math.cos(half) + float(data.spot_blend) * (1.0 - math.cos(half))))
        intensity = {"rgb": colour, "scale": power / (4.0 * math.pi)}
        if half > math.pi / 2.0:
            ctx.warn(where, "spot cones wider than 180° are imported as 180°")
            half = math.pi / 2.0
            start = min(start, half)
        return [
            {
                "type": "spot",
                "position": position,
                "target": [p + a for p, a in zip(position, axis.tolist(), strict=True)],
                "cutoff_angle": math.degrees(half),
                "falloff_start": math.degrees(start),
                "intensity": intensity,
            }
        ], []
    if kind == "SUN":
        if data.angle > math.radians(1.0):
            ctx.warn(where, "a sun's angular diameter is not imported (it becomes a distant light: hard shadows)")
        irradiance = {"rgb": colour, "scale": power}
        return [{"type": "distant", "direction": [float(v) for v in axis], "irradiance": irradiance}], []
    if kind == "AREA":
        return [], [_area(ctx, obj, matrix, colour, power, where)]
    ctx.warn(where, f"light type {kind} is not imported")
    return [], []


def _area(ctx: BlendImport, obj, matrix: np.ndarray, colour: list[float], power: float, where: str) -> dict:
    data = obj.data
    sx = float(data.size)
    sy = float(data.size_y) if data.shape in ("RECTANGLE", "ELLIPSE") else sx
    disk = data.shape in ("DISK", "ELLIPSE")
    if getattr(data, "spread", math.pi) < math.pi - 1e-6:
        ctx.warn(where, "an area light's spread is not imported (it emits into the whole hemisphere)")
    # The built-in rectangle and disk span [−1, 1]² facing +z: halve the size, and turn them to face −z.
    local_area = (math.pi / 4.0 if disk else 1.0) * sx * sy
    ex, ey = matrix[:3, 0], matrix[:3, 1]
    area = local_area * float(np.linalg.norm(np.cross(ex, ey)))
    radiance = {"rgb": colour, "scale": power / (math.pi * area) if area > 0.0 else 0.0}
    return {
        "type": "disk" if disk else "rectangle",
        "transform": [
            {"scale": [sx / 2.0, sy / 2.0, 1.0]},
            {"rotate": {"axis": [1.0, 0.0, 0.0], "angle": 180.0}},
            {"matrix": [[float(v) for v in row] for row in matrix]},
        ],
        "emitter": {"radiance": radiance},
        "name": obj.name,
        "hidden": not obj.visible_camera,  # taken out by the importer: whether Blender hides it from the camera
    }
