"""Scenes: the TOML format (schema), its loader, and the resolved objects the renderer draws."""

from pathlib import Path

from spectrace.scene.loader import load_scene as load_scene_file
from spectrace.scene.model import (
    AreaEmitter,
    Camera,
    ConductorMaterial,
    DielectricMaterial,
    DiffuseMaterial,
    Medium,
    MirrorMaterial,
    PlasticMaterial,
    RetroreflectorMaterial,
    Scene,
    Shape,
)

__all__ = ["load_scene", "Scene", "Camera", "Shape", "DiffuseMaterial", "MirrorMaterial", "ConductorMaterial",
           "PlasticMaterial", "RetroreflectorMaterial", "DielectricMaterial", "AreaEmitter", "Medium"]


def load_scene(path: str | Path) -> Scene:
    """Read, validate and resolve a TOML scene file; a bare name (`cornell_box`, `cornell_box.toml`) that is no file
    here names a bundled scene. Raises SpectraceError naming the file and key path."""
    from spectrace.resources import resolve_scene_path

    return load_scene_file(resolve_scene_path(path))
