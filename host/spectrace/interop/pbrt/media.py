"""pbrt-v4's homogeneous media (MakeNamedMedium, inside a shape through MediumInterface) as spectrace's `interior`
tables."""

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
    from spectrace.spectral.media_presets import medium_presets

    context.read.add(id(medium))
    kind = context.string(medium, "type", "")
    if kind != "homogeneous":
        raise error(medium.location, f"medium '{shown(kind or '')}': spectrace imports homogeneous media")
    table: dict = {}
    if (preset := context.string(medium, "preset")) is not None:
        # pbrt's Jensen et al. presets are the same measurements as spectrace's, in 1/mm (pbrt: per scene unit
        # times scale; spectrace: per mm times scale, its millimetres per scene unit: the same numbers).
        if preset.lower() not in medium_presets():
            raise error(
                medium.location, f"medium preset '{shown(preset)}' (spectrace has {', '.join(medium_presets())})"
            )
        table["preset"] = preset.lower()
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
    if emission is not None and emission not in ({"value": 0.0}, {"rgb": [0.0, 0.0, 0.0]}):
        context.warn(medium.location, "a medium's emission (Le) not imported")
    return table
