"""pbrt-v4's lights: each light module of spectrace.lights maps the pbrt types it lists in PBRT_LIGHTS with its
`from_pbrt(context, light, matrix) -> dict | None` (area's, on a shape, `from_pbrt(context, light, area)`); this
module dispatches to them through the registry (spectrace.lights.LIGHTS), and resamples an image `infinite` light's
map (envmap.py). `power` (point, spot, area) and `illuminance` (distant, infinite) rescale the emission exactly as
pbrt-v4's light constructors do; the emission itself is pbrt's normalised spectrum (Context.emission).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from spectrace.core.limits import linear_map_problem
from spectrace.interop.pbrt.context import Context, unique_name
from spectrace.interop.pbrt.envmap import to_latitude_longitude, upper_illuminance
from spectrace.interop.pbrt.graphics_state import Entity, Light
from spectrace.interop.pbrt.meshes import MeshData
from spectrace.interop.pbrt.parser import error, shown
from spectrace.lights import LIGHTS as LIGHT_MODULES
from spectrace.lights import area

# pbrt light type -> the light modules whose from_pbrt maps it (their PBRT_LIGHTS), in the registry's order. pbrt's
# `infinite` is two of spectrace's lights (constant, and envmap for one with an image): each module's from_pbrt
# returns None for the other's.
_MAPPINGS: dict[str, list] = {}
for _module in LIGHT_MODULES.values():
    for _kind in _module.PBRT_LIGHTS:
        _MAPPINGS.setdefault(_kind, []).append(_module)
LIGHTS = tuple(_MAPPINGS)
AREA_LIGHTS = area.PBRT_LIGHTS


def area_light(context: Context, light: Entity, mesh: MeshData | None, matrix: np.ndarray, shape: Entity) -> dict:
    """The `emitter` table of a shape's AreaLightSource (spectrace.lights.area's from_pbrt)."""
    context.read.add(id(light))
    if light.kind not in AREA_LIGHTS:
        raise error(light.location, f"area light '{shown(light.kind)}' (pbrt-v4's only one is diffuse)")

    def shape_area() -> float:
        if mesh is not None:
            return mesh.world_area(matrix)
        return _analytic_area(context, shape)  # pbrt's Shape::Area(), in the shape's object space (unscaled)

    return area.from_pbrt(context, light, shape_area)


def _analytic_area(context: Context, entity: Entity) -> float:
    """pbrt-v4's Area() of a sphere, disk or cylinder, partial ones included (φmax r (zmax − zmin) for the sphere
    and cylinder, φmax (r² − r_inner²) / 2 for the disk): object-space, whatever the transform scales."""
    radius = context.one(entity, "radius", 1.0)
    phimax = math.radians(min(max(context.one(entity, "phimax", 360.0), 0.0), 360.0))
    if entity.kind == "sphere":
        z = sorted((context.one(entity, "zmin", -radius), context.one(entity, "zmax", radius)))
        zmin, zmax = (min(max(value, -radius), radius) for value in z)
        return phimax * radius * (zmax - zmin)
    if entity.kind == "disk":
        return 0.5 * phimax * (radius**2 - context.one(entity, "innerradius", 0.0) ** 2)
    return phimax * radius * abs(context.one(entity, "zmax", 1.0) - context.one(entity, "zmin", -1.0))


def light_table(context: Context, light: Light) -> dict:
    """The `[[lights]]` table of a LightSource, from the module that maps its type."""
    entity, matrix = light.entity, light.world_from_light
    context.read.add(id(entity))
    kind = entity.kind
    # Every light but a point takes a direction through its transform: a singular one maps it to zero (or NaN).
    if kind != "point" and (problem := linear_map_problem(matrix[:3, :3])):
        raise error(entity.location, f"the light's transform {problem}")
    for module in _MAPPINGS.get(kind, ()):
        if (table := module.from_pbrt(context, entity, matrix)) is not None:
            return table
    raise error(
        entity.location, f"light '{shown(kind)}': spectrace imports {', '.join(LIGHTS)} and diffuse area lights"
    )


def environment_map(context: Context, entity: Entity, matrix: np.ndarray, scale: float) -> dict:
    """An image infinite light: its equal-area square resampled to a latitude-longitude EXR (envmap.py), which
    spectrace.lights.envmap's from_pbrt asks for."""
    from spectrace.io.images import read_environment_map

    if context.absent(entity, "filename", "a constant grey map"):
        from spectrace.interop.pbrt.placeholders import grey_square

        path, square = Path("placeholder.exr"), grey_square()
    else:
        found = context.file_path(entity, "filename")
        assert found is not None
        path = found
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
    spectrace_from_light = linear / np.cbrt(abs(np.linalg.det(linear)))
    image = to_latitude_longitude(square, spectrace_from_light, min(height, 2048))
    file = unique_name(path.stem, {Path(n).stem for n in context.files}) + ".exr"
    context.files[file] = image
    context.environment_sources[file] = (square, spectrace_from_light, str(path))
    return {"type": "envmap", "file": f"{context.mesh_folder}/{file}", "scale": scale}
