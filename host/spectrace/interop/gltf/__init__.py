"""glTF 2.0 in: `spectrace import-gltf MODEL.glb -o OUT.toml` and `spectrace render MODEL.glb` (docs/gltf.md).
One module per kind: document (JSON, buffers, accessors), nodes, meshes, materials, textures, cameras, lights;
importer ties them together and writes the TOML."""

from spectrace.interop.gltf.importer import (
    MATERIAL_MODELS,
    SUFFIXES,
    WARNING_PREFIX,
    gltf_scene_data,
    import_gltf,
    load_gltf_scene,
)

__all__ = ["MATERIAL_MODELS", "SUFFIXES", "WARNING_PREFIX", "gltf_scene_data", "import_gltf", "load_gltf_scene"]
