"""Scene interchange with other renderers: Mitsuba 3 XML import (see docs/mitsuba.md), pbrt-v4 import (see
docs/pbrt.md) and glTF 2.0 import (see docs/gltf.md). Each importer loads on first use: a TOML scene, which every
command reads through `spectrace.interop.scene_files`, pays for none of them (~0.6 s of a command's start)."""

from spectrace.lazy_names import lazy_names

_WHERE = {
    **dict.fromkeys(("gltf_scene_data", "import_gltf", "load_gltf_scene"), "spectrace.interop.gltf"),
    **dict.fromkeys(("import_mitsuba", "load_mitsuba_scene", "mitsuba_scene_data"), "spectrace.interop.mitsuba"),
    **dict.fromkeys(("import_pbrt", "load_pbrt_scene", "pbrt_scene_data"), "spectrace.interop.pbrt"),
}
__all__ = sorted(_WHERE)
__getattr__, __dir__ = lazy_names(__name__, _WHERE)
