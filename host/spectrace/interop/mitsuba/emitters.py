"""Emitters: each one is mapped by its spectrace light module (spectrace.lights.<name>: MITSUBA_PLUGINS,
`from_mitsuba`), an emitter on a shape by spectrace.lights.area; here the dispatch, and the emission a mapping
reads with Mitsuba's default where the file gives none."""

from __future__ import annotations

from spectrace.interop.mitsuba.context import ImportContext
from spectrace.interop.mitsuba.plugins import EMITTER_MODULES, SHAPE_EMITTER_MODULES
from spectrace.interop.mitsuba.textures import checked_textures, spectrum
from spectrace.interop.mitsuba.transforms import to_world
from spectrace.interop.mitsuba.tree import Element
from spectrace.lights import LIGHTS


def default_emission() -> dict:
    """What an emitter emits when its spectrum is not given: Mitsuba's d65 of unit luminance."""
    return {"rgb": [1.0, 1.0, 1.0]}


def emission(ctx: ImportContext, properties: dict, key: str) -> dict | None:
    """An emitter's spectrum `key`, or the default emission where it is not given."""
    return spectrum(ctx, properties[key], key) if key in properties else default_emission()


def light(ctx: ImportContext, element: Element) -> dict | None:
    """An <emitter> child of the scene as a [[lights]] table, by its light module; None where it is not imported
    (recorded)."""
    kind = ctx.kind(element)
    properties = ctx.properties(element)
    matrix = to_world(ctx, properties)
    if kind in EMITTER_MODULES:
        table = EMITTER_MODULES[kind].from_mitsuba(ctx, element, properties, matrix)
        return table if table is None or checked_textures(ctx, table, LIGHTS[table["type"]]) else None
    ctx.unsupported_object(element, " (not on a shape)" if kind in SHAPE_EMITTER_MODULES else "")
    return None


def shape_emitter(ctx: ImportContext, emitter: Element) -> dict | None:
    """A shape's emitter as its `emitter` table, or None (recorded as unsupported)."""
    module = SHAPE_EMITTER_MODULES.get(ctx.kind(emitter))
    if module is None:
        ctx.unsupported_plugin(emitter, " on a shape")
        return None
    table = module.from_mitsuba(ctx, emitter, ctx.properties(emitter))
    return table if table is not None and checked_textures(ctx, table, module) else None
