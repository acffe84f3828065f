"""Scene interchange with other renderers: Mitsuba 3 XML import (see docs/mitsuba.md)."""

from spectrace.interop.mitsuba_xml import import_mitsuba, load_mitsuba_scene, mitsuba_scene_data

__all__ = ["import_mitsuba", "load_mitsuba_scene", "mitsuba_scene_data"]
