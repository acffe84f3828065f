"""Scene interchange with other renderers: Mitsuba 3 XML import (see docs/mitsuba.md) and pbrt-v4 import (see
docs/pbrt.md)."""

from spectrace.interop.mitsuba import import_mitsuba, load_mitsuba_scene, mitsuba_scene_data
from spectrace.interop.pbrt import import_pbrt, load_pbrt_scene, pbrt_scene_data

__all__ = [
    "import_mitsuba",
    "import_pbrt",
    "load_mitsuba_scene",
    "load_pbrt_scene",
    "mitsuba_scene_data",
    "pbrt_scene_data",
]
