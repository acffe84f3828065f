"""What a scene that loads may still not be meant as: one in which nothing emits renders black. Mitsuba 3 renders
such a scene black without a word and pbrt-v4 with a warning; spectrace renders it black too (every integrator
handles an empty BVH and an empty light list) and says so in one line, since a file whose lights were forgotten or
not imported is the likelier reading than a black image asked for."""

import warnings
from pathlib import Path

from spectrace.errors import SpectraceWarning
from spectrace.scene.model import Scene


def scene_warnings(scene: Scene) -> list[str]:
    """The warnings loading `scene` gives (without the "warning: " a command line prints before each)."""
    shapes = scene.every_shape
    if scene.lights or any(shape.emitter is not None or shape.glows_inside for shape in shapes):
        return []
    if not shapes:
        return ["the scene has neither shapes nor lights: it renders black"]
    return ["nothing in the scene emits light (no lights, emitting shapes or glowing media): it renders black"]


def warn(scene: Scene, source: str | Path) -> None:
    """The Python API's form of the warnings: each a SpectraceWarning naming `source`, the file the user named."""
    for text in scene_warnings(scene):
        warnings.warn(f"{source}: {text}", SpectraceWarning, stacklevel=3)
