"""`point`: an isotropic point light, given by its intensity or by its power (kernels/light_point.cl).

Also the one place a power (total flux, W) becomes an intensity (W/(sr nm)), for spot lights too.
"""

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from spectrace.core import limits
from spectrace.core.parameters import REQUIRED, Parameter, Range
from spectrace.errors import SpectraceError
from spectrace.lights.base import DeviceLight, Light, LightRows, check_position, light_row, vector3
from spectrace.spectral import spectrum_input
from spectrace.spectral.grid import integrate_on_grid
from spectrace.spectral.spectrum import Spectrum
from spectrace.spectral.spectrum_input import SpectrumLike

NAME = "point"
API_NAME = "point_light"
MITSUBA_PLUGINS = ("point",)
PBRT_LIGHTS = ("point",)
IS_ENVIRONMENT = False
# Intensity I(λ), W/(sr nm).
POINT = DeviceLight("point", "position")
DEVICE_TYPES = (POINT,)
FULL_SPHERE_SR = 4.0 * np.pi
POSITION = Parameter("position", "vector", "scene units", REQUIRED, doc="where the light is")
INTENSITY = Parameter("intensity", "spectrum", "W/(sr nm)", None, doc="I(λ); give either intensity or power")
# Its range is reported with the other rules of intensity and power (source_problem), at the light's key.
POWER = Parameter(
    "power", "float", "W", None, Range(0.0), doc="total flux over 360–830 nm", api_name="power_w", schema_range=False
)
SPECTRUM = Parameter(
    "spectrum",
    "spectrum",
    "",
    None,
    default_doc="equal energy",
    doc="the spectral shape of power, normalised so that ∫Φ(λ)dλ = power",
)
PARAMETERS = (POSITION, INTENSITY, POWER, SPECTRUM)


@dataclass(frozen=True)
class PointLight(Light):
    """Isotropic point light: intensity I(λ) in W/(sr nm) (a flux Φ(λ) in W/nm gives I = Φ/4π)."""

    position: tuple[float, float, float]
    intensity: Spectrum


MODEL = PointLight


def source_problem(intensity, power, spectrum, power_name: str = "power") -> str | None:
    """Why the given intensity / power / spectrum do not set one intensity, or None."""
    if (intensity is None) == (power is None):
        return f"give exactly one of intensity, {power_name}"
    if spectrum is not None and power is None:
        return f"spectrum sets the shape of {power_name}; with intensity, put the spectrum in intensity"
    return POWER.range_problem(power) if power is not None else None


def check_spec(spec) -> None:
    if problem := source_problem(spec.intensity, spec.power, spec.spectrum):
        raise ValueError(problem)


SPEC_CHECKS = (check_spec,)


def intensity_from_power(
    power: float,
    shape: Spectrum | None,
    solid_angle_sr: float,
    where: str | None = None,
    power_where: str | None = None,
) -> Spectrum:
    """I(λ), W/(sr nm): `power` W spread over `solid_angle_sr` with the spectral shape `shape` (equal energy when
    None) normalised to ∫Φ(λ)dλ = power."""
    if shape is None:
        shape = Spectrum.constant(1.0, name="equal energy")
    total = float(integrate_on_grid(shape.values))
    if total <= 0:
        raise SpectraceError("the spectrum of a light given by power must not be zero", where=where)
    factor = power / total / solid_angle_sr
    with np.errstate(over="ignore"):
        if problem := limits.spectrum_magnitude_problem(shape.values * factor):
            raise SpectraceError(problem, where=power_where)
    return shape * factor


def spec_intensity(spec, resolver, key: str, solid_angle_sr: float) -> Spectrum:
    """The intensity a point or spot light's table gives, directly or through its power."""
    if spec.intensity is not None:
        return resolver.spectrum(spec.intensity, f"{key}.intensity", emission=True)
    shape = resolver.spectrum(spec.spectrum, f"{key}.spectrum", emission=True) if spec.spectrum is not None else None
    return intensity_from_power(
        spec.power, shape, solid_angle_sr, where=resolver.where(key), power_where=resolver.where(f"{key}.power")
    )


def from_spec(spec, resolver, key: str) -> PointLight:
    check_position(spec.position, resolver.where(f"{key}.position"))
    return PointLight(spec.position, spec_intensity(spec, resolver, key, FULL_SPHERE_SR))


def write_rows(light: PointLight, out: LightRows) -> None:
    out.add(
        light_row(out.code(POINT), out.table.add(light.intensity), position=light.position),
        4.0 * np.pi * light.intensity.mean(),
    )


def make(
    position: Sequence[float],
    intensity: SpectrumLike | None = None,
    power_w: float | None = None,
    spectrum: SpectrumLike | None = None,
) -> PointLight:
    """Isotropic point light: `intensity` I(λ) in W/(sr nm), or `power_w` (total flux over 360..830 nm, W) with
    the spectral shape `spectrum` (equal energy by default): I = Φ(λ)/4π."""
    return PointLight(vector3(position, "position"), make_intensity(intensity, power_w, spectrum, FULL_SPHERE_SR))


def make_intensity(
    intensity: SpectrumLike | None, power_w: float | None, shape_spectrum: SpectrumLike | None, solid_angle_sr: float
) -> Spectrum:
    """I(λ), W/(sr nm), of a Python API point or spot light: given, or `power_w` (W over 360..830 nm) spread over
    `solid_angle_sr` with the spectral shape `shape_spectrum` (equal energy by default), as a scene file's `power` +
    `spectrum`."""
    if problem := source_problem(intensity, power_w, shape_spectrum, power_name="power_w"):
        raise SpectraceError(problem)
    if intensity is not None:
        return spectrum_input.emission(intensity, "intensity")
    assert power_w is not None  # source_problem has refused giving neither
    shape_values = spectrum_input.emission(shape_spectrum, "spectrum") if shape_spectrum is not None else None
    return intensity_from_power(power_w, shape_values, solid_angle_sr)


def from_mitsuba(importer, emitter, properties, to_world) -> dict | None:
    position = importer.vector(properties["position"]) if "position" in properties else to_world[:3, 3].tolist()
    intensity = importer.emission(properties, "intensity")
    return None if intensity is None else {"type": "point", "position": position, "intensity": intensity}


def from_pbrt(context, light, matrix) -> dict | None:
    """pbrt-v4's point light at `from` (its transform applied); `power` is spread over the whole sphere."""
    scale = context.one(light, "scale", 1.0)
    power = context.one(light, "power", -1.0)
    if power > 0:
        scale *= power / (4.0 * math.pi)
    return {
        "type": "point",
        "position": context.point(matrix, context.vector(light, "from", [0.0, 0.0, 0.0])),
        "intensity": context.emission(light, "I", scale),
    }


def to_mitsuba(light: PointLight, exporter) -> dict:
    return {"type": "point", "position": list(light.position), "intensity": exporter.spectrum(light.intensity)}
