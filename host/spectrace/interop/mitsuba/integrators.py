"""Integrators: each integrator module of spectrace.integrators maps the Mitsuba plugins it lists in MITSUBA_PLUGINS
with its `from_mitsuba` (path: path, direct, volpath, volpathmis; light: ptracer; Mitsuba 0.6's bdpt and its sppm
and photonmapper: bdpt, sppm); this module reads the keys they share (max_depth, rr_depth, hide_emitters) and the two
integrators that hold another: moment (its nested integrator), aov (its nested integrator, and the AOVs
spectrace's film keeps) and stokes (its nested integrator, polarised, with the Stokes images)."""

from __future__ import annotations

from spectrace.interop.mitsuba.context import ImportContext, Properties
from spectrace.interop.mitsuba.plugins import INTEGRATOR_MODULES, SUPPORTED
from spectrace.interop.mitsuba.tree import Element, camel_to_snake, shown

# Mitsuba's aov integrator's AOV types -> spectrace's film AOVs of the same definition (kernels/aov.cl).
MITSUBA_AOVS = {"albedo": "albedo", "depth": "depth", "position": "position", "sh_normal": "normal"}


def integrator(ctx: ImportContext, element: Element, data: dict) -> None:
    """The <integrator> as the [integrator] table of `data`, from the module whose MITSUBA_PLUGINS name it."""
    kind = ctx.kind(element)
    if kind not in SUPPORTED["integrator"]:
        ctx.unsupported_object(element)
        return
    properties = ctx.properties(element)
    settings = {"type": "path", "max_depth": -1}  # Mitsuba's path tracers default to unbounded depth
    if "max_depth" in properties:
        settings["max_depth"] = ctx.integer(properties["max_depth"])
    if "rr_depth" in properties:
        settings["rr_depth"] = ctx.integer(properties["rr_depth"])
    if "hide_emitters" in properties and ctx.boolean(properties["hide_emitters"]):
        # Mitsuba's camera rays then see no environment and pass through area lights (measured: behind a
        # hidden area light they see the lit wall it hides, with its path and direct integrators alike).
        settings["hide_emitters"] = True
    if kind == "moment":
        # Mitsuba's moment integrator renders its nested integrator's image with the second moment as extra
        # channels: the image is the nested one's.
        nested = ctx.nested(properties, "integrator")
        if len(nested) != 1:
            raise ctx.fail(element, f"integrator 'moment' needs exactly one nested integrator, got {len(nested)}")
        ctx.notes.append(
            f"{ctx.at(element)}: integrator 'moment' imported as the integrator it holds (spectrace's image "
            "has no moment channels)"
        )
        integrator(ctx, nested[0], data)
        return
    if kind == "aov":
        aov_integrator(ctx, element, properties, data)
        return
    if kind == "stokes":
        stokes_integrator(ctx, element, properties, data)
        return
    data["integrator"] = INTEGRATOR_MODULES[kind].from_mitsuba(ctx, element, properties, settings)
    ctx.origins["integrator"] = element


def aov_integrator(ctx: ImportContext, element: Element, properties: Properties, data: dict) -> None:
    """Mitsuba's `aov` integrator: its nested integrator's image, and the AOVs its `aovs` list names
    ("name:type, ..."). The types spectrace's film keeps (the same definitions: spectrace.film.aovs) become the film's
    aovs; each other type is a warning naming it, and so is an aov integrator without a nested one (Mitsuba's
    image then holds the AOVs alone; spectrace renders the path tracer's image beside them)."""
    nested = ctx.nested(properties, "integrator")
    if len(nested) > 1:
        raise ctx.fail(element, f"integrator 'aov' with {len(nested)} nested integrators (spectrace renders one)")
    where = f"{shown(str(element.file or ctx.xml_path), 200)}:{element.line}: integrator 'aov'"
    kept: list[str] = []
    text = ctx.text(properties["aovs"]) if "aovs" in properties else ""
    for entry in filter(None, (part.strip() for part in text.split(","))):
        kind = entry.split(":", 1)[-1].strip()
        if kind in MITSUBA_AOVS and MITSUBA_AOVS[kind] not in kept:
            kept.append(MITSUBA_AOVS[kind])
        elif kind not in MITSUBA_AOVS:
            ctx.warnings.append(
                f"{where}: AOV '{shown(entry)}' is not imported (spectrace's film keeps the types "
                f"{', '.join(sorted(MITSUBA_AOVS))})"
            )
    if kept:
        ctx.film_aovs = kept
    if nested:
        integrator(ctx, nested[0], data)
    else:
        ctx.warnings.append(f"{where}: it holds no integrator; its image is spectrace's path tracer's")
        data["integrator"] = {"type": "path", "max_depth": -1}
        ctx.origins["integrator"] = element


def stokes_integrator(ctx: ImportContext, element: Element, properties: Properties, data: dict) -> None:
    """Mitsuba's `stokes` integrator (its polarised variants): the integrator it holds, rendered with polarised
    transport, and the `stokes` AOV, S0..S3 as film XYZ each (docs/polarization.md) where Mitsuba writes each
    Stokes component's colour after its image's."""
    nested = ctx.nested(properties, "integrator")
    if len(nested) != 1:
        raise ctx.fail(element, f"integrator 'stokes' needs exactly one nested integrator, got {len(nested)}")
    integrator(ctx, nested[0], data)
    if "integrator" in data:
        data["integrator"]["polarized"] = True
    ctx.film_aovs = [*ctx.film_aovs, "stokes"] if "stokes" not in ctx.film_aovs else ctx.film_aovs


def with_snake_case(*names: str) -> tuple[str, ...]:
    """Mitsuba 0.6 property names as a 3.x file spells them and as a 0.x file's upgrade turns them (snake_case)."""
    return tuple(dict.fromkeys([*names, *(camel_to_snake(name) for name in names)]))
