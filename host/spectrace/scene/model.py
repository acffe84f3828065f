"""A scene resolved for rendering: world-space meshes, spectra on the wavelength grid, validated settings.

These are the objects the Python API builds directly and the TOML loader produces; the renderer consumes only
these, never the file format.
"""

from dataclasses import dataclass, field
from numbers import Real
from pathlib import Path
from typing import Any, Literal

import numpy as np

from spectrace.core import limits
from spectrace.core.equality import fields_equal, identity_hash
from spectrace.errors import SpectraceError
from spectrace.film.aovs import parse_aovs
from spectrace.film.response import FilmResponse
from spectrace.geometry.analytic import AnalyticSurface
from spectrace.geometry.curves import CurveSurface
from spectrace.geometry.grid_volume import GridVolume
from spectrace.geometry.mesh import TriangleMesh
from spectrace.integrators import INTEGRATORS
from spectrace.lights.area import AreaEmitter, EmitterImage  # noqa: F401 (part of the model's names)
from spectrace.lights.base import Light
from spectrace.lights.constant import ConstantEnvironment  # noqa: F401 (the lights' models, part of the model's names)
from spectrace.lights.distant import DistantLight  # noqa: F401
from spectrace.lights.envmap import EnvironmentMap  # noqa: F401
from spectrace.lights.point import PointLight  # noqa: F401
from spectrace.lights.spot import SpotLight  # noqa: F401
from spectrace.materials.base import Material
from spectrace.pixel_filters import BOX_FILTER, PixelFilter
from spectrace.spectral.spectrum import Spectrum

SamplerType = Literal["independent", "sobol"]
SAMPLER_TYPES: tuple[str, ...] = ("independent", "sobol")
# Lower error than the independent sampler at equal spp on every scene measured (docs/sampling.md).
DEFAULT_SAMPLER: SamplerType = "sobol"


@dataclass(frozen=True)
class Camera:
    """A camera of any type (spectrace.cameras: each type's module says which fields it reads)."""

    origin: tuple[float, float, float]
    target: tuple[float, float, float]
    up: tuple[float, float, float] = (0.0, 1.0, 0.0)
    fov_degrees: float = 45.0  # perspective, thinlens
    fov_axis: Literal["x", "y"] = "x"
    near_clip: float = 0.0  # distance along the view axis before which nothing is seen (Mitsuba's near_clip)
    far_clip: float | None = None  # distance along the view axis beyond which nothing is seen (Mitsuba's far_clip)
    type: str = "perspective"  # a name of spectrace.cameras.CAMERAS
    aperture_radius: float = 0.0  # thinlens: scene units
    focus_distance: float = 1.0  # thinlens: scene units along the view axis
    view_width: float = 2.0  # orthographic: scene units across the image
    polarizer_angle: float | None = None  # a linear polariser in front of the lens, degrees from the image's right
    lens_system: Any = None  # realistic: its focused spectrace.cameras.realistic.LensSystem

    def basis(self, aspect_ratio: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """origin, forward, and the right and up vectors the kernels read for an image of width/height =
        aspect_ratio (a perspective camera's: right·tan(fov_x/2), up·tan(fov_y/2)).

        right = forward × up, so with +y up and +z forward the image's right is world -x (as in the Cornell box
        data, whose red wall at x ≈ 550 mm appears on the left).
        """
        from spectrace.cameras import CAMERAS

        return CAMERAS[self.type].basis(self, aspect_ratio)


# Materials and lights live in their own modules (spectrace.materials, spectrace.lights), each with its parameter
# table; a shape's material is any module's MODEL (a subclass of Material), a light any light module's (of Light).
# The materials' dataclasses are named here too, found through their registry.


def __getattr__(name: str) -> type:
    if name.startswith("__"):
        raise AttributeError(f"module '{__name__}' has no attribute '{name}'")
    from spectrace.materials import MATERIALS

    for module in MATERIALS.values():
        if module.MODEL.__name__ == name:
            return module.MODEL
    raise AttributeError(f"module '{__name__}' has no attribute '{name}'")


@dataclass(frozen=True)
class Medium:
    """A homogeneous participating medium filling a closed shape (docs/media.md): absorption σa(λ) and scattering
    σs(λ) coefficients in 1/scene unit, and the Henyey–Greenstein asymmetry g in (−1, 1) (0: isotropic)."""

    sigma_a: Spectrum
    sigma_s: Spectrum
    g: float = 0.0
    name: str = ""
    # A heterogeneous medium: the coefficients times a voxel grid's density (and σs times its albedo).
    density: GridVolume | None = None
    # A glowing medium: radiance σa(λ, x) Le(λ, x) per unit length, Le = emission(λ) times the grid's emission
    # scale and normalised blackbody at its temperature where it has them (kernels/medium_emission.cl).
    emission: Spectrum | None = None


@dataclass(frozen=True)
class Shape:
    mesh: TriangleMesh  # world space
    # None only with an interior or an emitter: a surface that rays cross unchanged (an index-matched boundary, a
    # light seen through); it still emits.
    material: Material | None
    emitter: AreaEmitter | None = None
    name: str = ""
    interior: Medium | None = None  # fills the closed mesh, on the back side of its faces (outward winding)
    # An analytic sphere, disk or cylinder that the kernels intersect exactly; `mesh` is then its tessellation, for
    # what reads triangles (bounds, export), and is not rendered. Curves (geometry/curves.py) are analytic too.
    analytic: AnalyticSurface | CurveSurface | None = None

    @property
    def glows_inside(self) -> bool:
        """Whether a medium that emits fills it (a glowing medium)."""
        return self.interior is not None and self.interior.emission is not None


@dataclass(frozen=True, eq=False)
class InstancedObject:
    """A group of shapes declared once, in its own object space, and placed any number of times by Instances (Mitsuba
    3's shapegroup, pbrt-v4's ObjectBegin/ObjectEnd): its triangles are stored once on the device under a BVH of their
    own (kernels/scene.cl, "Instances"), its analytic shapes once, intersected exactly through each instance's map.
    Emitters are refused in objects."""

    __eq__ = fields_equal  # by value (arrays too), hashed by identity
    __hash__ = identity_hash

    shapes: list[Shape]  # object space
    name: str = ""


@dataclass(frozen=True, eq=False)
class Instance:
    """One placement of an InstancedObject (Mitsuba 3's instance, pbrt-v4's ObjectInstance): its object space taken
    to world space by `to_world`, an invertible 4 x 4 affine matrix (a mirroring one is allowed)."""

    __eq__ = fields_equal  # by value (arrays too), hashed by identity
    __hash__ = identity_hash

    object: InstancedObject
    to_world: np.ndarray  # (4, 4)
    name: str = ""


@dataclass(frozen=True)
class Scene:
    camera: Camera
    width: int
    height: int
    shapes: list[Shape]
    lights: list[Light] = field(default_factory=list)
    integrator: str = "path"  # a name of spectrace.integrators.INTEGRATORS
    max_depth: int = 8
    rr_depth: int = 5
    hide_environment: bool = False  # camera rays that leave the scene see black
    hide_emitters: bool = False  # Mitsuba 3's hide_emitters: the environment hidden, area lights seen through
    count_thin_passes: bool = True  # path: a pass straight through a thindielectric counts toward max_depth
    polarized: bool = False  # path: polarised transport (also implied by polarising materials, Stokes AOVs, a filter)
    pixels_per_light_path: int | None = None  # bdpt: pixels sharing one light subpath; None: chosen from the scene
    pixel_filter: PixelFilter = BOX_FILTER  # the pixel's reconstruction filter (spectrace.pixel_filters)
    exposure: float = 0.0  # stops applied to the RGB outputs (not to the film's XYZ)
    film_response: FilmResponse = field(default_factory=FilmResponse)  # observers and sensor of the film
    spp: int = 16
    seed: int = 0
    sampler: SamplerType = DEFAULT_SAMPLER
    aovs: tuple[str, ...] = ()  # AOVs kept beside the image (spectrace.film.aovs.AOV_NAMES), in that order
    source: Path | None = None
    notes: dict = field(default_factory=dict)
    instances: list[Instance] = field(default_factory=list)  # placed copies of objects stored once

    def __post_init__(self) -> None:
        # A dataclass checks no types, and a Python caller may pass anything: refused here, naming the field, is
        # what would fail far from the call (a fractional width, an unknown integrator) or be read by its truth
        # (hide_emitters=1). The ranges are checked where the scene is rendered (spectrace.core.limits).
        if problem := settings_type_problem(self):
            raise SpectraceError(problem)
        object.__setattr__(self, "aovs", parse_aovs(self.aovs, where="aovs"))

    def __repr__(self) -> str:
        # The dataclass's own repr prints every vertex and spectrum (kilobytes in a notebook): the size, the
        # settings and the counts instead.
        triangles = sum(len(shape.mesh.faces) for shape in self.shapes)
        emitters = sum(shape.emitter is not None for shape in self.shapes)
        instanced = f", {len(self.instances)} instances" if self.instances else ""
        source = f", source={self.source.name!r}" if self.source is not None else ""
        return (
            f"Scene({self.width}x{self.height}, spp={self.spp}, integrator={self.integrator!r}, "
            f"{len(self.shapes)} shapes ({triangles} triangles, {emitters} emitting), {len(self.lights)} lights"
            f"{instanced}{source})"
        )

    @property
    def every_shape(self) -> list[Shape]:
        """Its own shapes, then each placed object's (in object space), once per placement."""
        return [*self.shapes, *(shape for instance in self.instances for shape in instance.object.shapes)]

    def with_overrides(self, **changes) -> "Scene":
        """A copy with some settings replaced (spp, width, height, seed, max_depth, ...); None keeps a value."""
        from dataclasses import replace

        return replace(self, **{k: v for k, v in changes.items() if v is not None})


def settings_type_problem(scene: Scene) -> str | None:
    """Why a Scene's settings are not of their types (whole numbers, a known integrator and sampler, flags, a
    number of stops), or None."""
    return (
        limits.choice_problem("integrator", scene.integrator, tuple(INTEGRATORS))
        or limits.choice_problem("sampler", scene.sampler, SAMPLER_TYPES)
        or next(
            (
                problem
                for name in ("width", "height", "spp", "seed", "max_depth", "rr_depth")
                if (problem := limits.whole_number_problem(name, getattr(scene, name)))
            ),
            None,
        )
        or next(
            (
                problem
                for name in ("hide_environment", "hide_emitters", "count_thin_passes", "polarized")
                if (problem := limits.flag_problem(name, getattr(scene, name)))
            ),
            None,
        )
        # The type alone: a NaN or huge exposure is the renderer's to refuse, as for a file's.
        or (
            limits.exposure_problem(scene.exposure)
            if isinstance(scene.exposure, bool) or not isinstance(scene.exposure, Real)
            else None
        )
        or (
            None
            if isinstance(scene.aovs, str | list | tuple)
            else f"aovs must be a sequence of AOV names, got {scene.aovs!r}"
        )
    )
