"""pbrt-v4's homogeneous and `uniformgrid` media (MakeNamedMedium, inside a shape through MediumInterface) as
spectrace's `interior` tables (a uniformgrid's density as an inline grid, placed by the CTM at MakeNamedMedium)."""

from __future__ import annotations

from spectrace.interop.pbrt.context import Context
from spectrace.interop.pbrt.graphics_state import Entity, Shape
from spectrace.interop.pbrt.parser import error, shown


def interior_table(context: Context, shape: Shape) -> dict | None:
    """The spectrace `interior` for the named medium inside a shape (MediumInterface's first name)."""
    if shape.outside_medium:
        context.warn(
            shape.entity.location,
            f"outside medium '{shown(shape.outside_medium)}' not imported (spectrace's media fill closed shapes)",
        )
    name = shape.inside_medium
    if not name:
        return None
    if name not in context.scene.media:
        raise error(shape.entity.location, f"MediumInterface names '{shown(name)}', which no MakeNamedMedium defined")
    if name not in context.interior_of:
        context.interior_of[name] = medium_table(context, context.scene.media[name])
    return context.interior_of[name]


def medium_table(context: Context, medium: Entity) -> dict:
    from spectrace.interop.pbrt.subsurface import preset_name
    from spectrace.spectral.media_presets import medium_presets

    context.read.add(id(medium))
    kind = context.string(medium, "type", "")
    if kind not in ("homogeneous", "uniformgrid"):
        raise error(
            medium.location, f"medium '{shown(kind or '')}': spectrace imports homogeneous and uniformgrid media"
        )
    table: dict = {}
    if kind == "uniformgrid":
        table["density"] = _uniform_grid(context, medium)
    if (preset := context.string(medium, "preset")) is not None:
        # pbrt's named media (Jensen et al. 2001, Narasimhan et al. 2006) are the same measurements as spectrace's
        # presets, in 1/mm (pbrt: per scene unit times scale; spectrace: per mm times scale, its millimetres per
        # scene unit: the same numbers).
        if preset_name(preset) not in medium_presets():
            raise error(
                medium.location, f"medium preset '{shown(preset)}' (spectrace has {', '.join(medium_presets())})"
            )
        table["preset"] = preset_name(preset)
    else:
        # pbrt's coefficients default to 1 per scene unit, spectrace's to 0.
        table["sigma_a"] = context.spectrum(medium, "sigma_a", "medium") or {"value": 1.0}
        table["sigma_s"] = context.spectrum(medium, "sigma_s", "medium") or {"value": 1.0}
    scale = context.one(medium, "scale", 1.0)
    if not scale > 0:
        raise error(medium.location, f"a medium's scale must be > 0, got {scale:g}")
    if scale != 1.0:
        table["scale"] = scale
    if (g := context.one(medium, "g", 0.0)) != 0.0:
        table["g"] = g
    emission = context.spectrum(medium, "Le", "medium")
    medium.find("Lescale")
    if kind == "uniformgrid" and (medium.find("temperature") or medium.find("temperaturescale")):
        context.warn(medium.location, "a medium's temperature grid (emission) not imported")
    if emission is not None and emission not in ({"value": 0.0}, {"rgb": [0.0, 0.0, 0.0]}):
        context.warn(medium.location, "a medium's emission (Le) not imported")
    return table


def _uniform_grid(context: Context, medium: Entity) -> dict:
    """A uniformgrid's `density` (nx·ny·nz values, x fastest) over the box p0–p1 of the medium's space, as
    spectrace's inline grid; the CTM at MakeNamedMedium places it. pbrt-v4 fades the density to 0 over the
    outermost half voxel, spectrace holds the face's value there (docs/media.md)."""
    resolution = [context.integer(medium, axis, 1, low=1) for axis in ("nx", "ny", "nz")]
    density = context.floats(medium, "density")
    if density is None:
        raise error(
            medium.location, 'a uniformgrid medium needs "float density" (spectrace imports no temperature grid)'
        )
    count = resolution[0] * resolution[1] * resolution[2]
    if len(density) != count:
        parameter = medium.find("density")
        raise error(
            parameter.location if parameter else medium.location,
            f'"float density" has {len(density)} values; nx·ny·nz = {count}',
        )
    p0 = context.vector(medium, "p0", [0.0, 0.0, 0.0])
    p1 = context.vector(medium, "p1", [1.0, 1.0, 1.0])
    matrix = context.world @ context.scene.world_from_medium[medium.name]
    return {
        "values": density,
        "resolution": resolution,
        "box": [p0, p1],
        "transform": [{"matrix": matrix.tolist()}],
    }
