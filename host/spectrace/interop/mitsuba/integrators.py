"""Integrators: path (max_depth, rr_depth, hide_emitters), direct (as path with max_depth 2), volpath and
volpathmis (as path, which renders media), ptracer (as the light tracer, `light`), moment (its nested integrator),
aov (its nested integrator, and the AOVs spectrace's film keeps). Mitsuba 0.6's bdpt integrator (Mitsuba 3 has
none) imports as spectrace's bidirectional path tracer, `bdpt`; its sppm and photonmapper integrators as spectrace's
stochastic progressive photon mapping, `sppm`."""

from __future__ import annotations

from spectrace.integrators.bdpt import BDPT_MAX_SEGMENTS
from spectrace.interop.mitsuba.context import ImportContext, Properties
from spectrace.interop.mitsuba.plugins import SUPPORTED
from spectrace.interop.mitsuba.tree import Element, camel_to_snake, shown

# Mitsuba's aov integrator's AOV types -> spectrace's film AOVs of the same definition (kernels/aov.cl).
MITSUBA_AOVS = {"albedo": "albedo", "depth": "depth", "position": "position", "sh_normal": "normal"}


def integrator(ctx: ImportContext, element: Element, data: dict) -> None:
    """The <integrator> as the [integrator] table of `data` (the module's docstring says what each becomes)."""
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
    if kind == "direct":
        settings["max_depth"] = 2
        ctx.notes.append(
            f"{ctx.at(element)}: integrator 'direct' imported as path tracing with max_depth 2 "
            "(emitters seen directly and direct light)"
        )
        # Mitsuba's direct integrator's sample counts per technique change the noise, not the mean.
        properties.understood("emitter_samples", "bsdf_samples", "shading_samples")
    elif kind == "ptracer":
        # Mitsuba's particle tracer is spectrace's light tracer, with the same max_depth and rr_depth meaning;
        # how many light paths one of its passes runs changes the scheduling, not the image.
        settings["type"] = "light"
        properties.understood("samples_per_pass")
    elif kind == "bdpt":
        # Mitsuba 0.6's bidirectional path tracer (Mitsuba 3 has none): spectrace's bdpt, max_depth and rr_depth
        # meaning the same; its per-strategy options change the noise, not the mean.
        settings["type"] = "bdpt"
        depth = settings["max_depth"]
        if not (isinstance(depth, int) and 0 <= depth <= BDPT_MAX_SEGMENTS):
            # Unbounded (Mitsuba's default, -1) or deeper than the kernel's subpath arrays: the longest paths
            # spectrace's bdpt keeps, so the import renders; the paths left out carry what Russian roulette
            # lets through beyond that many bounces.
            ctx.notes.append(
                f"{ctx.at(element)}: integrator 'bdpt' with max_depth {depth} imported with "
                f"max_depth {BDPT_MAX_SEGMENTS}, the longest paths spectrace's bdpt keeps"
            )
            settings["max_depth"] = BDPT_MAX_SEGMENTS
        properties.understood(*_with_snake_case("lightImage", "sampleDirect", "samples_per_pass"))
    elif kind in ("sppm", "photonmapper"):
        # Mitsuba 0.6's photon mappers: spectrace's sppm, which converges to the same image; the photon counts,
        # radii and lookup sizes are its own (spectrace.integrators.sppm), so they are noted, not followed.
        settings["type"] = "sppm"
        own = _with_snake_case(  # a 0.x file's names arrive upgraded to snake_case
            "photonCount", "initialRadius", "alpha", "granularity", "maxPasses", "directSamples",
            "glossySamples", "globalPhotons", "causticPhotons", "volumePhotons", "globalLookupRadius",
            "causticLookupRadius", "lookupSize",
        )  # fmt: skip
        if any(name in properties for name in own):
            ctx.notes.append(
                f"{ctx.at(element)}: integrator '{kind}' imported as 'sppm'; its photon counts and radii are "
                "spectrace's own choice"
            )
        properties.understood(*own)
    elif kind.startswith("volpath"):
        ctx.notes.append(f"{ctx.at(element)}: integrator '{kind}' imported as 'path', which renders media")
        # volpath counts no null interaction toward max_depth, and Mitsuba's thindielectric transmits by a
        # null lobe: a pass straight through a thin sheet is no segment there (path counts it).
        settings["count_thin_passes"] = False
    elif kind == "moment":
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
    elif kind == "aov":
        aov_integrator(ctx, element, properties, data)
        return
    data["integrator"] = settings
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


def _with_snake_case(*names: str) -> tuple[str, ...]:
    """Mitsuba 0.6 property names as a 3.x file spells them and as a 0.x file's upgrade turns them (snake_case)."""
    return tuple(dict.fromkeys([*names, *(camel_to_snake(name) for name in names)]))
