"""`distant`: parallel light from infinity, e.g. the sun (kernels/lights.cl)."""

from dataclasses import dataclass

import numpy as np

from spectrace.core.contract import LIGHT_DISTANT
from spectrace.core.parameters import REQUIRED, Parameter
from spectrace.lights.base import Light, LightRows, light_row, unit_direction
from spectrace.spectral.spectrum import Spectrum

NAME = "distant"
MITSUBA_PLUGINS = ("directional",)
PBRT_LIGHTS = ("distant",)
IS_ENVIRONMENT = False
PARAMETERS = (
    Parameter("direction", "vector", "", REQUIRED, doc="the direction the light travels"),
    Parameter("irradiance", "spectrum", "W/(m² nm)", REQUIRED, doc="on a surface facing the light"),
)


@dataclass(frozen=True)
class DistantLight(Light):
    """Parallel light travelling along `direction`: irradiance E(λ) in W/(m² nm) on a surface facing it."""

    direction: tuple[float, float, float]
    irradiance: Spectrum


MODEL = DistantLight


def from_spec(spec, resolver, key: str) -> DistantLight:
    direction = unit_direction(spec.direction, resolver.where(f"{key}.direction"))
    return DistantLight(direction, resolver.spectrum(spec.irradiance, f"{key}.irradiance", True))


def write_rows(light: DistantLight, out: LightRows) -> None:
    # The flux through the disc the scene's bounding sphere shows the light.
    out.add(
        light_row(LIGHT_DISTANT, out.table.add(light.irradiance), direction=light.direction),
        np.pi * out.scene_radius**2 * light.irradiance.mean(),
    )


def from_mitsuba(importer, emitter, properties, to_world) -> dict | None:
    direction = (
        importer.vector(properties["direction"])
        if "direction" in properties
        else (to_world[:3, :3] @ [0.0, 0.0, 1.0]).tolist()
    )
    if not any(direction):
        raise importer.fail(properties.get("direction", emitter), "the direction must not be zero")
    irradiance = importer.emission(properties, "irradiance")
    return None if irradiance is None else {"type": "distant", "direction": direction, "irradiance": irradiance}


def from_pbrt(context, light, matrix) -> dict | None:
    """pbrt-v4's distant light, shining from `from` toward `to`; `illuminance` is its irradiance's luminance."""
    scale = context.one(light, "scale", 1.0)
    start = context.vector(light, "from", [0.0, 0.0, 0.0])
    end = context.vector(light, "to", [0.0, 0.0, 1.0])
    illuminance = context.one(light, "illuminance", -1.0)
    if illuminance > 0:
        scale *= illuminance
    return {
        "type": "distant",
        "direction": context.direction(matrix, np.subtract(end, start)),
        "irradiance": context.emission(light, "L", scale),
    }


def to_mitsuba(light: DistantLight, exporter) -> dict:
    return {
        "type": "directional",
        "direction": list(light.direction),
        "irradiance": exporter.spectrum(light.irradiance),
    }
