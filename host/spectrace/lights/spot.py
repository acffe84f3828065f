"""`spot`: a point light emitting into a cone, with a smooth falloff toward its edge, optionally through a slide: a
texture projected over the cone (Mitsuba 3's spot `texture`; kernels/light_spot.cl)."""

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from spectrace.core.contract import NO_TEXTURE
from spectrace.core.parameters import REQUIRED, Parameter, Range
from spectrace.errors import SpectraceError
from spectrace.lights import point
from spectrace.lights.base import DeviceLight, Light, LightRows, check_position, light_row, unit_direction, vector3
from spectrace.spectral.spectrum import Spectrum
from spectrace.spectral.spectrum_input import SpectrumLike

NAME = "spot"
API_NAME = "spot_light"
MITSUBA_PLUGINS = ("spot",)
PBRT_LIGHTS = ("spot",)
IS_ENVIRONMENT = False
# Intensity on the axis I(λ), W/(sr nm), falling to 0 at the cutoff.
SPOT = DeviceLight("spot", "position")
DEVICE_TYPES = (SPOT,)
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
SLIDE = Parameter(
    "slide",
    "spectrum",
    "",
    None,
    default_doc="none",
    doc="a reflectance texture the intensity passes through, projected over the cone: texture coordinates "
    "(0.5, 0.5) + ½ (x, y) / (z tan cutoff_angle) in the light's frame (x along axis × slide_up, y down the image), "
    "so the image spans the cone's cutoff square (Mitsuba 3's spot `texture`)",
    textured=True,
)
SLIDE_UP = Parameter(
    "slide_up",
    "vector",
    "",
    (0.0, 1.0, 0.0),
    default_doc="[0, 1, 0]",
    doc="with a slide: the direction the top of the image faces, not along the axis",
)
PARAMETERS = (
    *point.PARAMETERS,
    Parameter("target", "vector", "scene units", REQUIRED, doc="the point the axis goes through"),
    CUTOFF_ANGLE,
    FALLOFF_START,
    LINEAR_FALLOFF,
    SLIDE,
    SLIDE_UP,
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
    slide: Any = None  # a reflectance texture (spectrace.textures) projected over the cone, or None
    slide_x: tuple[float, float, float] = (1.0, 0.0, 0.0)  # unit, across the axis: the image's u direction

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
    if spec.slide is None:
        return SpotLight(spec.position, direction, intensity, cutoff, start, linear)
    slide = resolver.spectrum_or_texture(spec.slide, f"{key}.slide", "spectrum")
    if isinstance(slide, Spectrum):
        raise SpectraceError(
            "a slide is a texture (a constant one is a factor of the intensity)", where=resolver.where(f"{key}.slide")
        )
    x = slide_x(direction, spec.slide_up, resolver.where(f"{key}.slide_up"))
    return SpotLight(spec.position, direction, intensity, cutoff, start, linear, slide, x)


def slide_x(direction, slide_up, where: str | None = None) -> tuple[float, float, float]:
    """The image's u direction across the axis: Mitsuba's local frame looks down +z with y down the image, so
    x = y × z with y the part of −slide_up across the axis."""
    down = -np.asarray(slide_up, float)
    down = down - np.dot(down, direction) * np.asarray(direction)
    if not np.linalg.norm(down) > 1e-6:
        raise SpectraceError("slide_up must not lie along the axis", where=where)
    x = np.cross(down / np.linalg.norm(down), direction)
    return (float(x[0]), float(x[1]), float(x[2]))


def slide_angle(direction, x) -> float:
    """The angle of x from the tangent of the axis' orthonormal basis (Duff et al. 2017, as kernels/sampling.cl
    builds it) toward its bitangent: the kernel rebuilds x from the axis and this one number."""
    n = np.asarray(direction, float)
    sign = 1.0 if n[2] >= 0.0 else -1.0
    a = -1.0 / (sign + n[2])
    b = n[0] * n[1] * a
    tangent = np.array([1.0 + sign * n[0] * n[0] * a, sign * b, -sign * n[0]])
    bitangent = np.array([b, sign + n[1] * n[1] * a, -n[1]])
    return float(np.arctan2(np.dot(x, bitangent), np.dot(x, tangent)))


def write_rows(light: SpotLight, out: LightRows) -> None:
    # The slide's angle rides in the axis' spare w (kernels/lights.cl), 0 and unread without one: the same rows.
    slide = light.slide is not None
    out.add(
        light_row(
            out.code(SPOT),
            out.table.add(light.intensity),
            position=light.position,
            direction=light.direction,
            direction_w=slide_angle(light.direction, light.slide_x) if slide else 0.0,
            cos_falloff_start=np.cos(np.radians(light.falloff_start_degrees)),
            cos_cutoff=np.cos(np.radians(light.cutoff_degrees)),
            linear_falloff=light.linear_falloff,
            texture=out.textures.add(light.slide, "spectrum") if slide else NO_TEXTURE,
        ),
        # A slide only dims (a reflectance): the unfiltered power bounds the light's for its pick probability.
        light.effective_solid_angle() * light.intensity.mean(),
    )


def make(
    position: Sequence[float],
    target: Sequence[float],
    cutoff_angle: float = CUTOFF_ANGLE.number_default,
    falloff_start: float | None = None,
    intensity: SpectrumLike | None = None,
    power_w: float | None = None,
    spectrum: SpectrumLike | None = None,
    linear_falloff: bool = False,
    slide=None,
    slide_up: Sequence[float] = (0.0, 1.0, 0.0),
) -> SpotLight:
    """Spot light at `position` aimed at `target`: full intensity (W/(sr nm), on the axis) up to `falloff_start`
    degrees from the axis (default ¾ of the cutoff), smooth fall (linear in the angle with `linear_falloff`) to 0 at
    `cutoff_angle` degrees; or `power_w` W spread over the cone's effective solid angle. `slide`: a reflectance
    texture the light passes through, projected over the cone's cutoff square, its top toward `slide_up`."""
    origin = np.asarray(vector3(position, "position"))
    direction = unit_direction(
        np.asarray(vector3(target, "target")) - origin, None, "spot light target equals its position"
    )
    cutoff, start = cone(cutoff_angle, falloff_start, "cutoff_angle", "falloff_start")
    solid_angle = effective_solid_angle(cutoff, start, linear_falloff)
    emitted = point.make_intensity(intensity, power_w, spectrum, solid_angle)
    if slide is None:
        return SpotLight(tuple(origin), direction, emitted, cutoff, start, bool(linear_falloff))
    x = slide_x(direction, vector3(slide_up, "slide_up"), "slide_up")
    return SpotLight(tuple(origin), direction, emitted, cutoff, start, bool(linear_falloff), slide, x)


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
    table = {
        "type": "spot",
        "position": position.tolist(),
        "target": (position + matrix[:3, 2]).tolist(),
        "cutoff_angle": cutoff,
        "falloff_start": beam,
        "linear_falloff": True,
        "intensity": intensity,
    }
    if "texture" in properties:
        # Mitsuba multiplies the intensity by the texture looked up in its local frame, whose y runs down the image:
        # the image's top faces the frame's -y.
        slide = importer.spectrum(properties["texture"], "texture")
        if slide is None:
            return None
        table["slide"] = slide
        table["slide_up"] = (-matrix[:3, 1]).tolist()
    return table


def from_pbrt(context, light, matrix) -> dict | None:
    """pbrt-v4's spot light from `from` toward `to`, full intensity within coneangle − conedeltaangle; `power` is
    spread over the cone as pbrt-v4's SpotLight spreads it (the falloff band counted at half)."""
    scale = context.one(light, "scale", 1.0)
    start = context.vector(light, "from", [0.0, 0.0, 0.0])
    end = context.vector(light, "to", [0.0, 0.0, 1.0])
    cone = context.one(light, "coneangle", 30.0)
    delta = context.one(light, "conedeltaangle", 5.0)
    power = context.one(light, "power", -1.0)
    if power > 0:
        cos_end, cos_start = math.cos(math.radians(cone)), math.cos(math.radians(cone - delta))
        solid_angle = 2.0 * math.pi * ((1.0 - cos_start) + (cos_start - cos_end) / 2.0)
        if not solid_angle > 0.0:  # intensity = power / solid angle: a closed cone would need infinite
            raise context.error(light.location, f'"power" needs a cone of positive solid angle (coneangle {cone:g})')
        scale *= power / solid_angle
    return {
        "type": "spot",
        "position": context.point(matrix, start),
        "target": context.point(matrix, end),
        "cutoff_angle": cone,
        "falloff_start": max(cone - delta, 0.0),
        "intensity": context.emission(light, "I", scale),
    }
