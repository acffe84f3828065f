"""`constant`: a uniform environment, the same radiance from every direction (kernels/light_environment.cl)."""

import math
from dataclasses import dataclass

import numpy as np

from spectrace.core.parameters import REQUIRED, Parameter
from spectrace.lights.base import DeviceLight, Light, LightRows, light_row
from spectrace.spectral import spectrum_input
from spectrace.spectral.spectrum import Spectrum
from spectrace.spectral.spectrum_input import SpectrumLike

NAME = "constant"
API_NAME = "constant_environment"
MITSUBA_PLUGINS = ("constant",)
# pbrt-v4's `infinite` is two lights here: this one without an image, envmap with one.
PBRT_LIGHTS = ("infinite",)
IS_ENVIRONMENT = True
# Radiance L(λ), W/(m² sr nm), the same from every direction at infinity.
ENVIRONMENT = DeviceLight("environment", "infinite")
DEVICE_TYPES = (ENVIRONMENT,)
PARAMETERS = (Parameter("radiance", "spectrum", "W/(m² sr nm)", REQUIRED, doc="from every direction"),)


@dataclass(frozen=True)
class ConstantEnvironment(Light):
    """Uniform light from every direction at infinity: radiance L(λ) in W/(m² sr nm)."""

    radiance: Spectrum


MODEL = ConstantEnvironment


def from_spec(spec, resolver, key: str) -> ConstantEnvironment:
    return ConstantEnvironment(resolver.spectrum(spec.radiance, f"{key}.radiance", emission=True))


def write_rows(light: ConstantEnvironment, out: LightRows) -> None:
    out.add(
        light_row(out.code(ENVIRONMENT), out.table.add(light.radiance)),
        4.0 * np.pi**2 * out.scene_radius**2 * light.radiance.mean(),
        environment=True,
    )


def make(radiance: SpectrumLike) -> ConstantEnvironment:
    """The same radiance L(λ), W/(m² sr nm), from every direction."""
    return ConstantEnvironment(spectrum_input.emission(radiance, "radiance"))


def from_mitsuba(importer, emitter, properties, to_world) -> dict | None:
    radiance = importer.emission(properties, "radiance")
    return None if radiance is None else {"type": "constant", "radiance": radiance}


def from_pbrt(context, light, matrix) -> dict | None:
    """pbrt-v4's `infinite` light without an image (None with one: envmap's); `illuminance` is that of the upper
    hemisphere, π times the radiance."""
    if light.find("filename", "string") is not None:
        return None
    scale = context.one(light, "scale", 1.0)
    illuminance = context.one(light, "illuminance", -1.0)
    if illuminance > 0:
        scale *= illuminance / math.pi
    return {"type": "constant", "radiance": context.emission(light, "L", scale)}


def to_mitsuba(light: ConstantEnvironment, exporter) -> dict:
    return {"type": "constant", "radiance": exporter.spectrum(light.radiance)}
