"""pbrt-v4's lights as spectrace's: `point`, `spot`, `distant`, `infinite` (a constant environment, or an image
one resampled to a latitude-longitude map, spectrace.interop.pbrt.envmap) and `diffuse` area lights on shapes.
`power` (point, spot, area) and `illuminance` (distant, infinite) rescale the emission exactly as pbrt-v4's light
constructors do; the emission itself is pbrt's normalised spectrum (Context.emission).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from spectrace.core.limits import linear_map_problem
from spectrace.interop.pbrt.context import Context, unique_name
from spectrace.interop.pbrt.envmap import to_latitude_longitude, upper_illuminance
from spectrace.interop.pbrt.graphics_state import Entity
from spectrace.interop.pbrt.meshes import MeshData
from spectrace.interop.pbrt.parser import error, shown

LIGHTS = ("point", "spot", "distant", "infinite")
AREA_LIGHTS = ("diffuse",)


def area_light(context: Context, light: Entity, mesh: MeshData | None, matrix: np.ndarray, shape: Entity) -> dict:
    context.read.add(id(light))
    if light.kind not in AREA_LIGHTS:
        raise error(light.location, f"area light '{shown(light.kind)}' (pbrt-v4's only one is diffuse)")
    if light.find("filename") is not None:
        raise error(light.location, "an area light showing an image file is not imported")
    two_sided = context.boolean(light, "twosided", False)
    scale = context.one(light, "scale", 1.0)
    power = context.one(light, "power", -1.0)
    if power > 0:
        if mesh is not None:
            area = mesh.world_area(matrix)
        else:  # an analytic shape: pbrt's Shape::Area(), in the shape's object space (unscaled)
            area = _analytic_area(context, shape)
        # Radiance = power / (sides · area · π): a shape without area would need infinite radiance.
        if not (area > 0.0 and math.isfinite(area)):
            raise error(light.location, f'"power" needs a shape with a positive finite area, got area {area:g}')
        scale *= power / ((2.0 if two_sided else 1.0) * area * math.pi)
    table: dict[str, object] = {"radiance": context.emission(light, "L", scale)}
    if two_sided:
        table["two_sided"] = True
    return table


def _analytic_area(context: Context, entity: Entity) -> float:
    """pbrt-v4's Area() of a whole sphere, disk or cylinder: object-space, whatever the transform scales."""
    radius = context.one(entity, "radius", 1.0)
    if entity.kind == "sphere":
        return 4.0 * math.pi * radius**2
    if entity.kind == "disk":
        return math.pi * radius**2
    return 2.0 * math.pi * radius * abs(context.one(entity, "zmax", 1.0) - context.one(entity, "zmin", -1.0))


def light_table(context: Context, light) -> dict:
    entity, matrix = light.entity, light.world_from_light
    context.read.add(id(entity))
    kind = entity.kind
    # Every light but a point takes a direction through its transform: a singular one maps it to zero (or NaN).
    if kind != "point" and (problem := linear_map_problem(matrix[:3, :3])):
        raise error(entity.location, f"the light's transform {problem}")
    scale = context.one(entity, "scale", 1.0)
    if kind == "point":
        power = context.one(entity, "power", -1.0)
        if power > 0:
            scale *= power / (4.0 * math.pi)
        return {
            "type": "point",
            "position": context.point(matrix, context.vector(entity, "from", [0.0, 0.0, 0.0])),
            "intensity": context.emission(entity, "I", scale),
        }
    if kind == "spot":
        start = context.vector(entity, "from", [0.0, 0.0, 0.0])
        end = context.vector(entity, "to", [0.0, 0.0, 1.0])
        cone = context.one(entity, "coneangle", 30.0)
        delta = context.one(entity, "conedeltaangle", 5.0)
        power = context.one(entity, "power", -1.0)
        if power > 0:
            cos_end, cos_start = math.cos(math.radians(cone)), math.cos(math.radians(cone - delta))
            solid_angle = 2.0 * math.pi * ((1.0 - cos_start) + (cos_start - cos_end) / 2.0)
            if not solid_angle > 0.0:  # intensity = power / solid angle: a closed cone would need infinite
                raise error(entity.location, f'"power" needs a cone of positive solid angle (coneangle {cone:g})')
            scale *= power / solid_angle
        return {
            "type": "spot",
            "position": context.point(matrix, start),
            "target": context.point(matrix, end),
            "cutoff_angle": cone,
            "falloff_start": max(cone - delta, 0.0),
            "intensity": context.emission(entity, "I", scale),
        }
    if kind == "distant":
        start = context.vector(entity, "from", [0.0, 0.0, 0.0])
        end = context.vector(entity, "to", [0.0, 0.0, 1.0])
        illuminance = context.one(entity, "illuminance", -1.0)
        if illuminance > 0:
            scale *= illuminance
        return {
            "type": "distant",
            "direction": context.direction(matrix, np.subtract(end, start)),
            "irradiance": context.emission(entity, "L", scale),
        }
    if kind == "infinite":
        if entity.find("filename", "string") is not None:
            return environment_map(context, entity, matrix, scale)
        if entity.find("portal") is not None:
            context.warn(entity.location, '"portal" not imported')
        illuminance = context.one(entity, "illuminance", -1.0)
        if illuminance > 0:
            scale *= illuminance / math.pi
        return {"type": "constant", "radiance": context.emission(entity, "L", scale)}
    raise error(
        entity.location, f"light '{shown(kind)}': spectrace imports {', '.join(LIGHTS)} and diffuse area lights"
    )


def environment_map(context: Context, entity: Entity, matrix: np.ndarray, scale: float) -> dict:
    """An image infinite light: its equal-area square resampled to a latitude-longitude EXR (envmap.py)."""
    from spectrace.io.images import read_environment_map

    path = context.file_path(entity, "filename")
    assert path is not None
    if path.suffix.lower() not in (".exr", ".hdr", ".rgbe"):
        raise error(
            entity.location,
            f"infinite light image '{shown(path.name)}': spectrace reads OpenEXR and Radiance HDR maps",
        )
    square = read_environment_map(path, str(entity.location))
    height, width = square.shape[:2]
    if height != width:
        raise error(entity.location, f"'{shown(path.name)}' is {width} x {height}: pbrt-v4's maps are square")
    if entity.find("L") is not None:
        raise error(entity.location, 'both "L" and "filename" given (pbrt-v4 refuses them too)')
    if entity.find("portal") is not None:
        context.warn(entity.location, '"portal" not imported')
    illuminance = context.one(entity, "illuminance", -1.0)
    if illuminance > 0:
        reference = upper_illuminance(square)
        if not (reference > 0.0 and math.isfinite(reference)):
            raise error(
                entity.location,
                f'"illuminance" rescales the map\'s upper hemisphere, whose illuminance is {reference:g}',
            )
        scale *= illuminance / reference
    # RGB texels are illuminants of the colour space's D65, normalised as an RGB light's L: spectrace's envmap
    # texels are D65-based with RGB (1, 1, 1) at Y = 1, so pbrt's scale carries over.
    linear = (context.world @ matrix)[:3, :3]
    image = to_latitude_longitude(square, linear / np.cbrt(abs(np.linalg.det(linear))), min(height, 2048))
    file = unique_name(path.stem, {Path(n).stem for n in context.files}) + ".exr"
    context.files[file] = image
    return {"type": "envmap", "file": f"{context.mesh_folder}/{file}", "scale": scale}
