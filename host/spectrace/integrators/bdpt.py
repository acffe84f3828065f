"""The `bdpt` integrator, bidirectional path tracing (kernels/integrator_bdpt.cl, kernels/bdpt.cl): what it refuses
beyond the light tracer's limits, its key pixels_per_light_path, and how many pixels share a light subpath. Its
passes are the light tracer's (spectrace.integrators.light): every pixel sample writes its own pixel's estimate to
that pixel's row and its light-to-camera connections as splat records, which the host adds to the film in a fixed
order (every pixel's own estimate, then the records)."""

from spectrace.core.parameters import Parameter, Range
from spectrace.integrators import light
from spectrace.integrators.base import SHARED_PARAMETERS, RenderHost, Scene, no_defines

NAME = "bdpt"
# Mitsuba 0.6's bidirectional path tracer (Mitsuba 3 has none), max_depth and rr_depth meaning the same.
MITSUBA_PLUGINS = ("bdpt",)
PBRT_INTEGRATORS: tuple[str, ...] = ()
PBRT_NONE = "pbrt-v4's bdpt converges to the path tracer's image and imports as path (path.py)"
# The most neighbouring pixels BDPT lets share one light subpath (integrator.pixels_per_light_path).
MAX_PIXELS_PER_LIGHT_PATH = 16
PIXELS_PER_LIGHT_PATH = Parameter(
    "pixels_per_light_path",
    "int",
    default=None,
    range=Range(1, MAX_PIXELS_PER_LIGHT_PATH),
    doc=f"neighbouring pixels whose camera subpaths share one light subpath, 1..{MAX_PIXELS_PER_LIGHT_PATH}; absent: "
    "4 where every surface is Lambertian and no medium fills a shape, 2 otherwise (docs/integrators.md)",
    schema_range=False,  # spectrace.integrators.value_problem says "1..16", whatever integrator the scene names
)
PARAMETERS = (*SHARED_PARAMETERS, PIXELS_PER_LIGHT_PATH)
PROGRAMS = {"megakernel": "integrator_bdpt.cl"}
SPLATS = "splats"  # its light-to-camera joins land in any pixel: whole films only
# Of base.FEATURES, what it refuses in any scene (`problem` says why; it refuses more in some scenes).
REFUSES: tuple[str, ...] = ("spectral bands", "AOVs", "pixel filters", "film responses", "hidden area lights")
CHECKPOINT_PROBLEM = None
# Its general program, every material and light joined at every strategy, took 330-390 CPU-s to build on PoCL, a
# scene's own 3-5 (the Cornell box, the material showcase): SPECTRACE_GENERAL_KERNELS=common builds each scene's own.
SHARES_GENERAL_PROGRAM = False

# Subpaths live in fixed arrays in the kernel (kernels/bdpt.cl's BDPT_MAX_SEGMENTS).
BDPT_MAX_SEGMENTS = 16
# Consecutive pixels whose camera subpaths share one light subpath, a work-item each group (RenderParams'
# bdpt_pixels_per_light_path, kernels/bdpt.cl), unless the scene sets integrator.pixels_per_light_path: where some
# path of light can reach the camera through a smooth or glossy surface or a medium (a caustic that mostly the
# light-to-camera strategy finds), and where every surface is diffuse and no medium fills a shape (the light-to-camera
# strategy then adds little that the others do not). Measured in docs/integrators.md ("Sharing light subpaths").
PIXELS_PER_LIGHT_PATH_SHARED = 2
PIXELS_PER_LIGHT_PATH_DIFFUSE = 4


def problem(scene: Scene, medium_count: int, spectral_bins: int) -> str | None:
    """Why the bidirectional path tracer cannot render this scene as asked, or None."""
    # BDPT adds its own pixel's strategies as whole-pixel records: the light tracer's spectral bands and filter
    # spreads are not in its kernels.
    if spectral_bins:
        return "integrator 'bdpt' does not write spectral bands yet; render without spectral output or use 'path'"
    if scene.pixel_filter.type != "box":
        return (
            f"integrator 'bdpt' adds whole pixels (the box filter), not a {scene.pixel_filter.type} filter; "
            "use film.filter = \"box\" or 'path'"
        )
    if found := light.splatting_problem(scene, NAME):
        return found
    if scene.max_depth < 0 or scene.max_depth > BDPT_MAX_SEGMENTS:
        return (
            f"integrator 'bdpt' keeps paths of at most {BDPT_MAX_SEGMENTS} segments: "
            f"set integrator.max_depth between 1 and {BDPT_MAX_SEGMENTS}, not {scene.max_depth}"
        )
    if scene.camera.type in light.SPHERICAL_CAMERAS:
        # Its importance is over the sphere of directions: kernels/bdpt.cl's eye vertex and MIS densities are the
        # film-plane cameras'.
        return (
            f"integrator 'bdpt' supports the perspective, thinlens and orthographic cameras, not {scene.camera.type!r}"
        )
    return None


defines = no_defines


def params(scene: Scene) -> dict[str, int]:
    return {"bdpt_pixels_per_light_path": pixels_per_light_path(scene)}


def passes(host: RenderHost, shape: str, spectral_bins: int) -> light.LightPasses:
    # Its t = 1 joins (light vertices 2 .. max_depth) are the records; its pixels' own sums go to a row each.
    capacity = min(max(host.scene.max_depth - 1, 1), light.MAX_RECORD_SLOTS)
    pixels = pixels_per_light_path(host.scene)
    return light.LightPasses(host, spectral_bins, "bdpt_pass", capacity, own_rows=True, pixels_per_path=pixels)


def only_diffuse(scene: Scene) -> bool:
    """Every surface of the scene (its instanced objects' too) is diffuse, and no medium fills a shape."""
    return all(
        shape.material is not None and shape.material.is_diffuse and shape.interior is None
        for shape in scene.every_shape
    )


def pixels_per_light_path(scene: Scene) -> int:
    """Neighbouring pixels whose camera subpaths share one light subpath: the scene's integrator.pixels_per_light_path,
    else PIXELS_PER_LIGHT_PATH_DIFFUSE where only_diffuse, else PIXELS_PER_LIGHT_PATH_SHARED."""
    if scene.pixels_per_light_path is not None:
        return int(scene.pixels_per_light_path)
    return PIXELS_PER_LIGHT_PATH_DIFFUSE if only_diffuse(scene) else PIXELS_PER_LIGHT_PATH_SHARED


def from_mitsuba(importer, element, properties, settings: dict) -> dict:
    """Mitsuba 0.6's bdpt; its per-strategy options change the noise, not the mean."""
    settings["type"] = NAME
    depth = settings["max_depth"]
    if not (isinstance(depth, int) and 0 <= depth <= BDPT_MAX_SEGMENTS):
        # Unbounded (Mitsuba's default, -1) or deeper than the kernel's subpath arrays: the longest paths this
        # integrator keeps, so the import renders; the paths left out carry what Russian roulette lets through
        # beyond that many bounces.
        importer.notes.append(
            f"{importer.at(element)}: integrator 'bdpt' with max_depth {depth} imported with "
            f"max_depth {BDPT_MAX_SEGMENTS}, the longest paths spectrace's bdpt keeps"
        )
        settings["max_depth"] = BDPT_MAX_SEGMENTS
    properties.understood(*importer.with_snake_case("lightImage", "sampleDirect", "samples_per_pass"))
    return settings
