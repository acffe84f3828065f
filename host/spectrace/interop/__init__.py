"""Scene interchange with other renderers: Mitsuba 3 XML import (see docs/mitsuba.md), pbrt-v4 import (see
docs/pbrt.md) and glTF 2.0 import (see docs/gltf.md)."""

from spectrace.interop.gltf import gltf_scene_data, import_gltf, load_gltf_scene
from spectrace.interop.mitsuba import import_mitsuba, load_mitsuba_scene, mitsuba_scene_data
from spectrace.interop.pbrt import import_pbrt, load_pbrt_scene, pbrt_scene_data

__all__ = [
    "gltf_scene_data",
    "import_gltf",
    "import_mitsuba",
    "import_pbrt",
    "load_gltf_scene",
    "load_mitsuba_scene",
    "load_pbrt_scene",
    "mitsuba_scene_data",
    "pbrt_scene_data",
]
