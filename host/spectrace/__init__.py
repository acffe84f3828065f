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

import warnings

# colour-science warns on import that matplotlib, which only its plotting needs, is missing (it comes with the plot
# extra; a figure asked for without it is refused naming the extra: spectrace.plot_extra). colour is imported late,
# where first needed (it takes about a second), so the filter stays for the process rather than around one import.
warnings.filterwarnings("ignore", message=".*Matplotlib.* related API features are not available")

from spectrace.cache_folder import ensure_usable_cache_folder
from spectrace.lazy_names import lazy_names
from spectrace.scene import MODEL_NAMES, material_model_names

# Before anything else: matplotlib (through colour) and, later, PoCL and pyopencl set up caches under it.
ensure_usable_cache_folder()

# The names below load on first use (PEP 562), so that `spectrace --help` and `import spectrace.cli` do not pay for
# colour-science, SciPy and the OpenCL host code. Where each name lives (the materials' and textures' names:
# _registry_names):
_LAZY = {
    **dict.fromkeys(
        [
            "area_emitter",
            "medium",
            "density_grid",
            "mesh_from_trimesh",
            "render",
            "rgb_emission",
            "rgb_reflectance",
            "shape",
            "sdf_grid",
            "curve",
            "instanced_object",
            "instance",
            "spectrum",
            "transformed",
        ],
        "spectrace.api",
    ),
    **dict.fromkeys(
        ["Adaptation", "ColourSpace", "WhiteBalance", "parse_white_balance"], "spectrace.film.colour_output"
    ),
    "SpectraceError": "spectrace.errors",
    "Session": "spectrace.session",
    "save_scene": "spectrace.session.scene_toml",
    **dict.fromkeys(["denoise", "directly_seen_emission"], "spectrace.denoising"),
    "Image": "spectrace.film.image",
    "PixelFilter": "spectrace.pixel_filters",
    **dict.fromkeys(MODEL_NAMES, "spectrace.scene.model"),
    "load_scene": "spectrace.scene",
    "view": "spectrace.viewer",
    "Spectrum": "spectrace.spectral.spectrum",
    **dict.fromkeys(["FilmResponse", "load_sensor", "delta_e_2000_map"], "spectrace.film.response"),
}


def _registry_names() -> dict[str, str]:
    """Names that come from the registries: each material's constructor (`spectrace.diffuse`, ...: its module's
    `make`, which spectrace.api exposes) and its dataclass, each light's constructor (`spectrace.point_light`, ...:
    its module's `make`, under its API_NAME) and each texture's constructor (`spectrace.bitmap`, ...: its module's
    API_NAME)."""
    from spectrace.lights import LIGHTS
    from spectrace.materials import MATERIALS
    from spectrace.textures import TEXTURES

    textures = dict.fromkeys((module.API_NAME for module in TEXTURES.values()), "spectrace.api")
    lights = {m.API_NAME: "spectrace.api" for m in LIGHTS.values() if m.API_NAME is not None}
    return dict.fromkeys(MATERIALS, "spectrace.api") | lights | material_model_names() | textures


__version__ = "0.1.0"

_names_getattr, _names_dir = lazy_names(
    __name__,
    _LAZY,
    _registry_names,
    public=[
        "load_scene",
        "save_scene",
        "render",
        "Session",
        "Image",
        *MODEL_NAMES,
        "PixelFilter",
        "SpectraceError",
        "Spectrum",
        "spectrum",
        "rgb_reflectance",
        "rgb_emission",
        "mesh_from_trimesh",
        "transformed",
        "shape",
        "sdf_grid",
        "curve",
        "instanced_object",
        "instance",
        "medium",
        "density_grid",
        "area_emitter",
        "ColourSpace",
        "Adaptation",
        "WhiteBalance",
        "parse_white_balance",
        "denoise",
        "directly_seen_emission",
        "FilmResponse",
        "load_sensor",
        "delta_e_2000_map",
    ],
)

# Subpackages and modules a user reaches as attributes after `import spectrace` alone
# (`spectrace.interop.load_mitsuba_scene`): imported on first use, as the names above.
SUBMODULES = (
    *("api", "cameras", "device", "displays", "film", "geometry", "integrators", "interop", "io", "lights"),
    *("materials", "pixel_filters", "plots", "spectral", "sweep", "textures", "validation"),
)


def __getattr__(name: str) -> object:
    if name in SUBMODULES:
        import importlib

        return importlib.import_module(f"spectrace.{name}")
    return _names_getattr(name)


def __dir__() -> list[str]:
    return sorted({*_names_dir(), *SUBMODULES})
