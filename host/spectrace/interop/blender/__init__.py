"""Blender in: `spectrace import-blend SCENE.blend -o OUT.toml` and `spectrace render SCENE.blend`, through Blender's
Python module `bpy` (installed apart: `pip install bpy`, docs/blender.md). One module per kind: meshes, materials,
lights, cameras, world; importer reads the evaluated scene and writes the TOML."""

from spectrace.interop.blender.importer import (
    EXTRA_MESSAGE,
    SUFFIXES,
    WARNING_PREFIX,
    import_blend,
    load_blend_scene,
    require_bpy,
)

__all__ = ["EXTRA_MESSAGE", "SUFFIXES", "WARNING_PREFIX", "import_blend", "load_blend_scene", "require_bpy"]
