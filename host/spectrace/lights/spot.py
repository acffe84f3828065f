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
MITSUBA_PLUGINS = ()
MITSUBA_NONE = "Mitsuba 3's spot falls off with a different profile: neither is imported or exported as the other"
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
PARAMETERS = (
    *point.PARAMETERS,
    Parameter("target", "vector", "scene units", REQUIRED, doc="the point the axis goes through"),
    CUTOFF_ANGLE,
    FALLOFF_START,
)


def effective_solid_angle(cutoff_degrees: float, falloff_start_degrees: float) -> float:
    """∫ falloff dω over the sphere, sr: flux = intensity × this."""
    cos_start = np.cos(np.radians(falloff_start_degrees))
    cos_cut = np.cos(np.radians(cutoff_degrees))
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

    def effective_solid_angle(self) -> float:
        """∫ falloff dω over the sphere, sr: flux = intensity × this."""
        return effective_solid_angle(self.cutoff_degrees, self.falloff_start_degrees)


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
    intensity = point.spec_intensity(spec, resolver, key, effective_solid_angle(cutoff, start))
    return SpotLight(spec.position, direction, intensity, cutoff, start)


def write_rows(light: SpotLight, out: LightRows) -> None:
    out.add(
        light_row(
            LIGHT_SPOT,
            out.table.add(light.intensity),
            position=light.position,
            direction=light.direction,
            cos_falloff_start=np.cos(np.radians(light.falloff_start_degrees)),
            cos_cutoff=np.cos(np.radians(light.cutoff_degrees)),
        ),
        light.effective_solid_angle() * light.intensity.mean(),
    )
