"""pbrt-v4 import (docs/pbrt.md): the file read (parser, graphics_state), one module per kind of plugin mapping it
onto spectrace's scene (cameras, shapes, materials, textures, media, lights; each material module's own
`from_pbrt`), and the import that runs them and writes the TOML (importer)."""

from spectrace.interop.pbrt.importer import import_pbrt, load_pbrt_scene, pbrt_scene_data

__all__ = ["import_pbrt", "load_pbrt_scene", "pbrt_scene_data"]
