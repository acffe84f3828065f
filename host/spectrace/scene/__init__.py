"""Scenes: the TOML format (schema), its loader, and the resolved objects the renderer draws."""

from spectrace.scene.loader import load_scene
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
