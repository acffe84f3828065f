"""A scene resolved for rendering: world-space meshes, spectra on the wavelength grid, validated settings.

These are the objects the Python API builds directly and the TOML loader produces; the renderer consumes only
these, never the file format.
"""

from dataclasses import dataclass, field
from pathlib import Path
from typing import Literal

import numpy as np

from spectrace.geometry.mesh import TriangleMesh
from spectrace.spectral.glasses import IndexOfRefraction
from spectrace.spectral.spectrum import Spectrum


SamplerType = Literal["independent", "sobol"]
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


# Materials: one dataclass per BSDF (docs/materials.md gives each model, kernels/bsdf_<name>.cl implements it).
# `roughness` is the GGX α (Mitsuba 3's `alpha`); 0 (below 1e-3) means a smooth surface with a delta lobe.


@dataclass(frozen=True)
class DiffuseMaterial:
    """Lambertian, f = R(λ)/π, reflecting on both faces."""

    reflectance: Spectrum


@dataclass(frozen=True)
class MirrorMaterial:
    """Perfect specular reflection of reflectance R(λ)."""

    reflectance: Spectrum


@dataclass(frozen=True)
class ConductorMaterial:
    """Metal of complex index of refraction η(λ) + i k(λ) relative to the outside, smooth or GGX-rough; the Fresnel
    reflectance is multiplied by `specular_tint` when given."""

    eta: Spectrum
    k: Spectrum
    roughness: float = 0.0
    specular_tint: Spectrum | None = None


@dataclass(frozen=True)
class PlasticMaterial:
    """Diffuse base of albedo `reflectance` under a clear coat of index `ior` relative to the outside."""

    reflectance: Spectrum
    ior: float = 1.5
    roughness: float = 0.0


@dataclass(frozen=True)
class RetroreflectorMaterial:
    """Returns light toward where it came from: a GGX lobe of width `roughness` about the incident direction."""

    reflectance: Spectrum
    roughness: float = 0.1


@dataclass(frozen=True)
class DielectricMaterial:
    """Glass, water: Fresnel reflection and Snell refraction at an interface to an interior of index `ior` relative
    to the exterior (air), which may depend on the wavelength (dispersion); smooth or GGX-rough. The geometric
    normal (the winding) points to the exterior. `specular_tint` multiplies both lobes when given."""

    ior: IndexOfRefraction
    roughness: float = 0.0
    specular_tint: Spectrum | None = None


Material = (DiffuseMaterial | MirrorMaterial | ConductorMaterial | PlasticMaterial | RetroreflectorMaterial
            | DielectricMaterial)


@dataclass(frozen=True, eq=False)
class EmitterImage:
    """An image shown by an area light (a picture on a screen): each texel emits r·R(λ) + g·G(λ) + b·B(λ) of the
    three primaries for its linear drive (r, g, b); texture coordinates place it (u right, v down)."""

    drive: np.ndarray  # (height, width, 3) linear drive per texel, row 0 at the top
    primaries: tuple[Spectrum, Spectrum, Spectrum]  # W/(m² sr nm) at full drive, scale applied


@dataclass(frozen=True)
class AreaEmitter:
    radiance: Spectrum  # W/(m² sr nm), scale applied; with an image, its mean emission
    two_sided: bool = False
    image: EmitterImage | None = None


@dataclass(frozen=True)
class PointLight:
    """Isotropic point light: intensity I(λ) in W/(sr nm) (a flux Φ(λ) in W/nm gives I = Φ/4π)."""

    position: tuple[float, float, float]
    intensity: Spectrum


@dataclass(frozen=True)
class SpotLight:
    """Point light emitting into a cone about `direction`: I(λ) on the axis in W/(sr nm), full up to
    falloff_start_degrees from the axis, falling smoothly (smoothstep in cos θ) to 0 at cutoff_degrees."""

    position: tuple[float, float, float]
    direction: tuple[float, float, float]
    intensity: Spectrum
    cutoff_degrees: float = 30.0
    falloff_start_degrees: float = 25.0

    def effective_solid_angle(self) -> float:
        """∫ falloff dω over the sphere, sr: flux = intensity × this."""
        cos_start = np.cos(np.radians(self.falloff_start_degrees))
        cos_cut = np.cos(np.radians(self.cutoff_degrees))
        return 2.0 * np.pi * ((1.0 - cos_start) + 0.5 * (cos_start - cos_cut))


@dataclass(frozen=True)
class DistantLight:
    """Parallel light travelling along `direction`: irradiance E(λ) in W/(m² nm) on a surface facing it."""

    direction: tuple[float, float, float]
    irradiance: Spectrum


@dataclass(frozen=True)
class ConstantEnvironment:
    """Uniform light from every direction at infinity: radiance L(λ) in W/(m² sr nm)."""

    radiance: Spectrum


@dataclass(frozen=True, eq=False)
class EnvironmentMap:
    """Light from a latitude-longitude image at infinity: `rgb` (height, width, 3) linear sRGB, times `scale`;
    each texel's radiance is the D65-based emission uplift of its colour (RGB (1,1,1) = D65 at Y = 1), in
    W/(m² sr nm). +y is up; the image centre looks along −z (see kernels/environment.cl)."""

    rgb: np.ndarray
    scale: float = 1.0


Light = PointLight | SpotLight | DistantLight | ConstantEnvironment | EnvironmentMap


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


@dataclass(frozen=True)
class Scene:
    camera: Camera
    width: int
    height: int
    shapes: list[Shape]
    lights: list[Light] = field(default_factory=list)
    integrator: Literal["path", "direct"] = "path"
    max_depth: int = 8
    rr_depth: int = 5
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
