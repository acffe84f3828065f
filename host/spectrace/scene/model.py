"""A scene resolved for rendering: world-space meshes, spectra on the wavelength grid, validated settings.

These are the objects the Python API builds directly and the TOML loader produces; the renderer consumes only
these, never the file format.
"""

from dataclasses import dataclass, field
from pathlib import Path
from typing import Literal

import numpy as np

from spectrace.geometry.analytic import AnalyticSurface
from spectrace.geometry.mesh import TriangleMesh
from spectrace.lights.area import AreaEmitter, EmitterImage  # noqa: F401 (part of the model's names)
from spectrace.lights.base import Light
from spectrace.lights.constant import ConstantEnvironment  # noqa: F401 (the lights' models, part of the model's names)
from spectrace.lights.distant import DistantLight  # noqa: F401
from spectrace.lights.envmap import EnvironmentMap  # noqa: F401
from spectrace.lights.point import PointLight  # noqa: F401
from spectrace.lights.spot import SpotLight  # noqa: F401
from spectrace.materials.base import Material
from spectrace.spectral.spectrum import Spectrum

SamplerType = Literal["independent", "sobol"]
IntegratorType = Literal["path", "direct", "light"]
INTEGRATOR_TYPES: tuple[str, ...] = ("path", "direct", "light")  # docs/integrators.md
SAMPLER_TYPES: tuple[str, ...] = ("independent", "sobol")
# Lower error than the independent sampler at equal spp on every scene measured (docs/sampling.md).
DEFAULT_SAMPLER: SamplerType = "sobol"


@dataclass(frozen=True)
class Camera:
    origin: tuple[float, float, float]
    target: tuple[float, float, float]
    up: tuple[float, float, float] = (0.0, 1.0, 0.0)
    fov_degrees: float = 45.0
    fov_axis: Literal["x", "y"] = "x"
    near_clip: float = 0.0  # distance along the view axis before which nothing is seen (Mitsuba's near_clip)

    def basis(self, aspect_ratio: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """origin, forward, right·tan(fov_x/2), up·tan(fov_y/2) for an image of width/height = aspect_ratio.

        right = forward × up, so with +y up and +z forward the image's right is world -x (as in the Cornell box
        data, whose red wall at x ≈ 550 mm appears on the left).
        """
        origin = np.asarray(self.origin, float)
        forward = np.asarray(self.target, float) - origin
        forward /= np.linalg.norm(forward)
        right = np.cross(forward, np.asarray(self.up, float))
        right /= np.linalg.norm(right)
        up = np.cross(right, forward)
        tan_half = np.tan(np.radians(self.fov_degrees) / 2.0)
        if self.fov_axis == "x":
            tan_x, tan_y = tan_half, tan_half / aspect_ratio
        else:
            tan_x, tan_y = tan_half * aspect_ratio, tan_half
        return origin, forward, right * tan_x, up * tan_y


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


@dataclass(frozen=True)
class Shape:
    mesh: TriangleMesh  # world space
    material: Material | None  # None only with an interior: an index-matched boundary that rays cross unchanged
    emitter: AreaEmitter | None = None
    name: str = ""
    interior: Medium | None = None  # fills the closed mesh, on the back side of its faces (outward winding)
    # An analytic sphere, disk or cylinder that the kernels intersect exactly; `mesh` is then its tessellation, for
    # what reads triangles (bounds, export), and is not rendered.
    analytic: AnalyticSurface | None = None


@dataclass(frozen=True)
class Scene:
    camera: Camera
    width: int
    height: int
    shapes: list[Shape]
    lights: list[Light] = field(default_factory=list)
    integrator: IntegratorType = "path"
    max_depth: int = 8
    rr_depth: int = 5
    hide_environment: bool = False  # camera rays that leave the scene see black (Mitsuba's hide_emitters)
    exposure: float = 0.0  # stops applied to the RGB outputs (not to the film's XYZ)
    spp: int = 16
    seed: int = 0
    sampler: SamplerType = DEFAULT_SAMPLER
    source: Path | None = None
    notes: dict = field(default_factory=dict)

    def with_overrides(self, **changes) -> "Scene":
        """A copy with some settings replaced (spp, width, height, seed, max_depth, ...); None keeps a value."""
        from dataclasses import replace

        return replace(self, **{k: v for k, v in changes.items() if v is not None})
