"""Which Mitsuba 3 plugins the import reads, per element, and which spectrace module maps each: the one table that
the unsupported-plugin error and `spectrace import-mitsuba --help` name, and the tags Mitsuba's parser knows.

The BSDF, emitter, texture and sensor columns and the rfilters come from the registries (each module's
MITSUBA_PLUGINS), so a material, light, texture, camera or pixel filter that names a plugin there is imported without
a change here.
"""

from __future__ import annotations

from spectrace.cameras import CAMERAS
from spectrace.integrators import INTEGRATORS
from spectrace.lights import LIGHTS, area
from spectrace.materials import MATERIALS
from spectrace.pixel_filters import PIXEL_FILTERS
from spectrace.textures import TEXTURES


def _modules_by_plugin(modules) -> dict:
    """Mitsuba plugin name -> the module (material, light, texture, integrator) that imports it (its
    MITSUBA_PLUGINS)."""
    return {plugin: module for module in modules for plugin in module.MITSUBA_PLUGINS}


BSDF_MODULES = _modules_by_plugin(MATERIALS.values())
EMITTER_MODULES = _modules_by_plugin(LIGHTS.values())  # emitters of their own, <emitter> children of <scene>
SHAPE_EMITTER_MODULES = _modules_by_plugin((area,))  # emitters on a shape
TEXTURE_MODULES = _modules_by_plugin(TEXTURES.values())
# `twosided` wraps one BSDF: without it, a reflecting material imports with two_sided = false. The surface-detail
# adapters wrap one BSDF too, and become keys of its material (spectrace.materials.surface): normal_map, bump_map,
# opacity.
SURFACE_DETAIL_WRAPPERS = ("normalmap", "bumpmap", "mask")
BSDF_WRAPPERS = ("twosided", *SURFACE_DETAIL_WRAPPERS)
# Mitsuba sensor plugin → spectrace camera type, from the cameras' modules (spectrace.cameras).
CAMERA_PLUGINS = {plugin: name for name, module in CAMERAS.items() for plugin in module.MITSUBA_PLUGINS}
CAMERA_MODULES = _modules_by_plugin(CAMERAS.values())
# Mitsuba rfilter plugin → spectrace pixel filter, from the filters' modules (spectrace.pixel_filters); another
# rfilter is replaced by the box filter with a note.
FILTER_PLUGINS = {plugin: name for name, module in PIXEL_FILTERS.items() for plugin in module.MITSUBA_PLUGINS}
# Mitsuba integrator plugin → spectrace integrator, from the integrators' modules (spectrace.integrators); `moment`
# and `aov` hold another integrator, whose image they render, `stokes` one it renders polarised (integrators.py).
INTEGRATOR_MODULES = _modules_by_plugin(INTEGRATORS.values())
INTEGRATOR_WRAPPERS = ("moment", "aov", "stokes")
SUPPORTED = {
    "shape": (
        *("obj", "ply", "serialized", "rectangle", "cube", "sphere", "disk", "cylinder", "sdfgrid"),
        *("linearcurve", "bsplinecurve", "shapegroup", "instance"),
    ),
    "bsdf": (*BSDF_MODULES, *BSDF_WRAPPERS, "null"),  # null: a shape without material (shapes.py)
    "emitter": (*SHAPE_EMITTER_MODULES, *EMITTER_MODULES),
    "texture": tuple(TEXTURE_MODULES),
    "sensor": tuple(CAMERA_PLUGINS),
    "film": ("hdrfilm", "specfilm"),
    "integrator": (*INTEGRATOR_MODULES, *INTEGRATOR_WRAPPERS),
    "medium": ("homogeneous",),
    "volume": ("constvolume",),  # a homogeneous medium's sigma_t or albedo (media.py)
    "phase": ("hg", "isotropic"),
}
# The spectrum plugins imported as spectra (spectra.spectrum_element), also when written as <texture type="...">.
SPECTRUM_PLUGINS = ("uniform", "irregular", "regular", "blackbody", "d65", "srgb")

OBJECT_TAGS = (
    "scene",
    "shape",
    "bsdf",
    "emitter",
    "sensor",
    "film",
    "sampler",
    "integrator",
    "rfilter",
    "texture",
    "medium",
    "phase",
    "volume",
    "spectrum",
)
# Elements that set a named property of the object holding them.
PROPERTY_TAGS = ("float", "integer", "string", "boolean", "rgb", "point", "vector", "transform")
# Every tag Mitsuba 3's parser knows (src/core/parser.cpp): the objects, the properties, a transform's steps, and
# the parser's own (<include> and <path> are gone once the file is read: spectrace.interop.mitsuba.tree). Any other
# tag is a misspelling or another program's; Mitsuba refuses it, the import reports it (--strict: an error).
TRANSFORM_STEPS = ("translate", "rotate", "scale", "matrix", "lookat")
KNOWN_TAGS = frozenset((*OBJECT_TAGS, *PROPERTY_TAGS, *TRANSFORM_STEPS, "ref", "alias", "default", "include", "path"))


def importable(tag: str, kind: str) -> bool:
    """Whether a nested object of this tag and type is one the importer reads (the rest, under a plugin it does not
    import, is named with it)."""
    if tag in ("sampler", "rfilter"):  # replaced by spectrace's own, with a note
        return True
    if tag in ("texture", "spectrum") and kind in SPECTRUM_PLUGINS:
        return True
    return kind in SUPPORTED.get(tag, ())


def supported_text() -> str:
    """The plugins spectrace imports, per element: "shape obj, ply, ...; bsdf diffuse, ...; ..." (the modules'
    MITSUBA_PLUGINS through the registries, and what the importer itself reads)."""
    return "; ".join(f"{tag} {', '.join(kinds)}" for tag, kinds in SUPPORTED.items())
