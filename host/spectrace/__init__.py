"""spectrace: a physically based spectral path tracer on OpenCL.

Notebook use needs no CLI::

    import spectrace
    scene = spectrace.load_scene("scenes/cornell_box.toml")
    image = spectrace.render(scene, spp=16)
    image.to_srgb()          # (H, W, 3) display sRGB
    image.write("cornell.exr")
"""

from spectrace.errors import SpectraceError
from spectrace.image import Image
from spectrace.render.api import render
from spectrace.scene import AreaEmitter, Camera, DiffuseMaterial, Scene, Shape, load_scene

__version__ = "0.1.0"

__all__ = [
    "load_scene",
    "render",
    "Image",
    "Scene",
    "Camera",
    "Shape",
    "DiffuseMaterial",
    "AreaEmitter",
    "SpectraceError",
]
