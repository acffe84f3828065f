"""spectrace: a physically based spectral path tracer on OpenCL.

Notebook use needs no CLI::

    import spectrace
    scene = spectrace.load_scene("scenes/cornell_box.toml")
    image = spectrace.render(scene, spp=16)
    image.to_srgb()          # (H, W, 3) display sRGB
    image.write("cornell.exr")

Scenes can also be built from Python objects (`spectrace.api`: spectrum, diffuse, shape, point_light, ...);
docs/python-api.md shows how.
"""

from spectrace.cache_folder import ensure_usable_cache_folder

# Before the imports below: matplotlib (through colour) and, later, PoCL and pyopencl set up caches under it.
ensure_usable_cache_folder()

from spectrace.api import (  # noqa: E402
    area_emitter,
    conductor,
    constant_environment,
    dielectric,
    diffuse,
    distant_light,
    medium,
    mesh_from_trimesh,
    mirror,
    plastic,
    point_light,
    render,
    retroreflector,
    rgb_emission,
    rgb_reflectance,
    shape,
    spectrum,
    spot_light,
    transformed,
)
from spectrace.colour_output import Adaptation, ColourSpace, WhiteBalance, parse_white_balance
from spectrace.errors import SpectraceError
from spectrace.image import Image
from spectrace.scene import (
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
    load_scene,
)
from spectrace.spectral.spectrum import Spectrum

__version__ = "0.1.0"

__all__ = [
    "load_scene",
    "render",
    "Image",
    "Scene",
    "Camera",
    "Shape",
    "DiffuseMaterial",
    "MirrorMaterial",
    "ConductorMaterial",
    "PlasticMaterial",
    "RetroreflectorMaterial",
    "DielectricMaterial",
    "AreaEmitter",
    "Medium",
    "SpectraceError",
    "Spectrum",
    "spectrum",
    "rgb_reflectance",
    "rgb_emission",
    "mesh_from_trimesh",
    "transformed",
    "shape",
    "diffuse",
    "medium",
    "mirror",
    "conductor",
    "plastic",
    "retroreflector",
    "dielectric",
    "area_emitter",
    "point_light",
    "spot_light",
    "distant_light",
    "constant_environment",
    "ColourSpace",
    "Adaptation",
    "WhiteBalance",
    "parse_white_balance",
]
