"""`spot`: a point light emitting into a cone, with a smooth falloff toward its edge (kernels/lights.cl)."""

from dataclasses import dataclass

import numpy as np

from spectrace.engine.device_types import LIGHT_SPOT
from spectrace.errors import SpectraceError
from spectrace.lights import point
from spectrace.lights.base import Light, LightRows, check_position, light_row, unit_direction
from spectrace.materials.parameters import REQUIRED, Parameter, Range
from spectrace.spectral.spectrum import Spectrum

NAME = "spot"
MITSUBA_PLUGINS = ("spot",)
IS_ENVIRONMENT = False
CUTOFF_ANGLE = Parameter(
    "cutoff_angle",
    "float",
    "degrees",
    30.0,
    Range(0.0, 90.0, low_open=True),
    doc="from the axis, where the intensity reaches 0",
)
FALLOFF_START = Parameter(
    "falloff_start",
    "float",
    "degrees",
    None,
    Range(0.0),
    default_doc="¾ of the cutoff",
    doc="from the axis, where the intensity starts to fall",
)
LINEAR_FALLOFF = Parameter(
    "linear_falloff",
    "bool",
    default=False,
    doc="fall linearly in the angle θ from falloff_start to cutoff_angle (Mitsuba 3's profile) instead of "
    "smoothstep in cos θ (pbrt-v4's)",
)
PARAMETERS = (
    *point.PARAMETERS,
    Parameter("target", "vector", "scene units", REQUIRED, doc="the point the axis goes through"),
    CUTOFF_ANGLE,
    FALLOFF_START,
    LINEAR_FALLOFF,
)


def effective_solid_angle(cutoff_degrees: float, falloff_start_degrees: float, linear_falloff: bool = False) -> float:
    """∫ falloff dω over the sphere, sr: flux = intensity × this."""
    cut, start = np.radians(cutoff_degrees), np.radians(falloff_start_degrees)
    if linear_falloff:
        # 2π ∫ f(θ) sin θ dθ with f = (θc − θ)/(θc − θs) on [θs, θc], integrated by parts; a hard edge when θs = θc.
        if cut - start < 1e-6:
            return 2.0 * np.pi * (1.0 - np.cos(cut))
        return 2.0 * np.pi * (1.0 - (np.sin(cut) - np.sin(start)) / (cut - start))
    cos_start, cos_cut = np.cos(start), np.cos(cut)
    return 2.0 * np.pi * ((1.0 - cos_start) + 0.5 * (cos_start - cos_cut))


@dataclass(frozen=True)
class SpotLight(Light):
    """Point light emitting into a cone about `direction`: I(λ) on the axis in W/(sr nm), full up to
    falloff_start_degrees from the axis, falling smoothly (smoothstep in cos θ) to 0 at cutoff_degrees."""

    position: tuple[float, float, float]
    direction: tuple[float, float, float]
    intensity: Spectrum
    cutoff_degrees: float = CUTOFF_ANGLE.number_default
    falloff_start_degrees: float = 25.0
    linear_falloff: bool = False

    def effective_solid_angle(self) -> float:
        """∫ falloff dω over the sphere, sr: flux = intensity × this."""
        return effective_solid_angle(self.cutoff_degrees, self.falloff_start_degrees, self.linear_falloff)


MODEL = SpotLight
SPEC_CHECKS = point.SPEC_CHECKS


def cone(
    cutoff_angle: float, falloff_start: float | None, where_cutoff: str | None = None, where_start: str | None = None
) -> tuple[float, float]:
    """(cutoff, falloff start) in degrees: the start defaults to ¾ of the cutoff and must not exceed it."""
    cutoff = CUTOFF_ANGLE.check(cutoff_angle, where_cutoff)
    start = 0.75 * cutoff if falloff_start is None else FALLOFF_START.check(falloff_start, where_start)
    if start > cutoff:
        raise SpectraceError(f"falloff_start ({start}) exceeds cutoff_angle ({cutoff})", where=where_start)
    return cutoff, start


def from_spec(spec, resolver, key: str) -> SpotLight:
    check_position(spec.position, resolver.where(f"{key}.position"))
    direction = unit_direction(np.subtract(spec.target, spec.position), resolver.where(f"{key}.target"))
    cutoff, start = cone(
        spec.cutoff_angle,
        spec.falloff_start,
        resolver.where(f"{key}.cutoff_angle"),
        resolver.where(f"{key}.falloff_start"),
    )
    linear = bool(spec.linear_falloff)
    intensity = point.spec_intensity(spec, resolver, key, effective_solid_angle(cutoff, start, linear))
    return SpotLight(spec.position, direction, intensity, cutoff, start, linear)


def write_rows(light: SpotLight, out: LightRows) -> None:
    out.add(
        light_row(
            LIGHT_SPOT,
            out.table.add(light.intensity),
            position=light.position,
            direction=light.direction,
            cos_falloff_start=np.cos(np.radians(light.falloff_start_degrees)),
            cos_cutoff=np.cos(np.radians(light.cutoff_degrees)),
            linear_falloff=light.linear_falloff,
        ),
        light.effective_solid_angle() * light.intensity.mean(),
    )


def from_mitsuba(importer, emitter, properties, to_world) -> dict | None:
    """Mitsuba 3's spot shines along its local +z from its local origin, linearly in θ from beam_width (default ¾
    of the cutoff) to cutoff_angle (default 20°): the same profile, through linear_falloff."""
    cutoff = importer.number(properties["cutoff_angle"]) if "cutoff_angle" in properties else 20.0
    beam = importer.number(properties["beam_width"]) if "beam_width" in properties else 0.75 * cutoff
    intensity = importer.emission(properties, "intensity")
    if intensity is None:
        return None
    matrix = np.asarray(to_world, dtype=float)
    position = matrix[:3, 3]
    return {
        "type": "spot",
        "position": position.tolist(),
        "target": (position + matrix[:3, 2]).tolist(),
        "cutoff_angle": cutoff,
        "falloff_start": beam,
        "linear_falloff": True,
        "intensity": intensity,
    }
