"""Scenes: the TOML format (schema), its loader, and the resolved objects the renderer draws.

The names below load on first use, so that the leaf modules of this package (`limits`, `model`) can be imported by
lower layers (image readers, light modules) without pulling in the loader, which imports those layers back.
"""

import os
from pathlib import Path

from spectrace.lazy_names import lazy_names

MODEL_NAMES = ["Scene", "Camera", "Shape", "AreaEmitter", "Medium", "InstancedObject", "Instance"]


def material_model_names() -> dict[str, str]:
    """Each material's dataclass (its module's MODEL) by name -> the module it lives in; imports the registry."""
    from spectrace.materials import MATERIALS

    return {module.MODEL.__name__: module.MODEL.__module__ for module in MATERIALS.values()}


def load_scene(path: str | Path, overrides: dict | None = None):
    """Read, validate and resolve a TOML scene file; a bare name (`cornell_box`, `cornell_box.toml`) that is no file
    here names a bundled scene. Raises SpectraceError naming the file and key path. `overrides`: values replacing
    the file's at dotted key paths ("film.width": 64), as if the file said so. A scene in which nothing emits loads
    with a SpectraceWarning (spectrace.scene.scene_warnings)."""
    from spectrace.errors import SpectraceError
    from spectrace.resources import resolve_scene_path
    from spectrace.scene.loader import load_scene as load_scene_file
    from spectrace.scene.scene_warnings import warn

    if not isinstance(path, str | os.PathLike):
        raise SpectraceError(f"load_scene() reads a file: give its path (a str or a Path), got {path!r}"[:200])
    if overrides is not None and not (isinstance(overrides, dict) and all(isinstance(k, str) for k in overrides)):
        raise SpectraceError(f"overrides must map dotted key paths (str) to values, got {overrides!r}"[:200])
    scene = load_scene_file(resolve_scene_path(path), overrides)
    warn(scene, scene.source or path)
    return scene


__getattr__, __dir__ = lazy_names(
    __name__,
    dict.fromkeys(MODEL_NAMES, "spectrace.scene.model"),
    material_model_names,
    public=["load_scene", *MODEL_NAMES],
)
