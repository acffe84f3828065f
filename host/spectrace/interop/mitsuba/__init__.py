"""Mitsuba 3 XML scenes -> spectrace scene TOML, for the subset spectrace represents exactly; and a loaded scene
back to a Mitsuba 3 scene dict for side-by-side renders (export.py).

One module per kind of Mitsuba plugin, each a set of functions of the import's context (context.py): tree.py reads
the file as Mitsuba's parser does ($parameters, <default>, <include>, <path>, the 0.x upgrade); plugins.py names
what is imported and which spectrace module maps it; transforms.py, textures.py (colours, spectra, textures),
materials.py, emitters.py, media.py, shapes.py, sensors.py (camera, film, sampler) and integrators.py map each
kind; importer.py ties them together and writes the TOML. Each BSDF, emitter, texture and camera is mapped by its
spectrace module, which names the Mitsuba plugins it imports (MITSUBA_PLUGINS) and converts them (`from_mitsuba`):
spectrace.materials.<name> for BSDFs, spectrace.lights.<name> for emitters (lights.area for a shape's),
spectrace.textures.<name> for textures, spectrace.cameras.<name> for sensors. The plugin -> module tables are built
from the registries (MATERIALS, LIGHTS, TEXTURES, CAMERAS).

Bad values are reported as one SpectraceError naming the file and the element path
(`scene.xml: shape[2]/transform/translate@x`, docs/mitsuba.md "Bad input"). Anything else (another plugin type,
a texture where spectrace takes none, other media) is reported in one error naming each unsupported plugin and
its line; choices spectrace makes differently (the reconstruction filter, the sampler) are returned as notes.
Parameters are documented in Mitsuba 3's plugin reference (mitsuba.readthedocs.io, "Plugin reference").
"""

from spectrace.interop.mitsuba.importer import (
    WARNING_PREFIX,
    import_mitsuba,
    load_mitsuba_scene,
    mitsuba_scene_data,
)
from spectrace.interop.mitsuba.plugins import supported_text

__all__ = ["WARNING_PREFIX", "import_mitsuba", "load_mitsuba_scene", "mitsuba_scene_data", "supported_text"]
