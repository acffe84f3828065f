"""`checkerboard`: two spectra (or image textures) alternating in squares of the texture coordinates: side 0 where
floor(s) + floor(t) is even, st = uv · uv_scale + uv_offset (the default uv_scale 2 gives 2 × 2 squares on the unit
square, as Mitsuba 3's checkerboard). Evaluated exactly at the point, without filtering its edges. docs/textures.md."""

from dataclasses import dataclass

from spectrace.core.parameters import Parameter, Range
from spectrace.spectral.spectrum import Spectrum
from spectrace.textures.mapping import PARAMETERS as MAPPING_PARAMETERS
from spectrace.textures.mapping import api_mapping
from spectrace.textures.shared import (
    UV_OFFSET,
    Placement,
    api_operand,
    pbrt_two_sided,
    two_sided_from_spec,
    uv_pair,
    uv_scale,
)

NAME = "checkerboard"
API_NAME = NAME
COMPOSITE = True
PARAMETERS = (
    Parameter(
        "color0",
        "spectrum",
        default=0.4,
        range=Range(0.0, 1.0),
        doc="the squares where floor(s) + floor(t) is even",
        textured=True,
    ),
    Parameter("color1", "spectrum", default=0.2, range=Range(0.0, 1.0), doc="the other squares", textured=True),
    uv_scale(2.0),
    UV_OFFSET,
    *MAPPING_PARAMETERS,
)
MITSUBA_PLUGINS = ("checkerboard",)
PBRT_TEXTURES = ("checkerboard",)
# Mitsuba 3's checkerboard changes colour where frac(uv') crosses 1/2, uv' = to_uv(uv): twice as many squares per
# unit of uv' as spectrace's squares per unit of st, so st = 2 uv'.
MITSUBA_SQUARES_PER_UNIT = 2.0


@dataclass(frozen=True, eq=False)
class CheckerboardTexture:
    """Two sides, each a spectrum or an image texture (a bitmap or spectral texture, not another checkerboard)."""

    color0: object
    color1: object
    placement: Placement = Placement(uv_scale=(2.0, 2.0))
    source: str = "checkerboard"


MODEL = CheckerboardTexture


def from_spec(spec, resolver, key: str) -> CheckerboardTexture:
    return two_sided_from_spec(CheckerboardTexture, ("color0", "color1"), spec, resolver, key)


def make(
    color0=0.4,
    color1=0.2,
    *,
    uv_scale: float | tuple[float, float] = 2.0,
    uv_offset=(0.0, 0.0),
    mapping: str = "uv",
    transform=(),
    v1=(1.0, 0.0, 0.0),
    v2=(0.0, 1.0, 0.0),
) -> CheckerboardTexture:
    """Squares of color0 and color1 (reflectances: anything `spectrum` takes, an RGB triple, or an image texture)
    over the texture coordinates: color0 where floor(s) + floor(t) is even, st = uv · uv_scale + uv_offset."""
    return CheckerboardTexture(
        api_operand(color0, "color0"),
        api_operand(color1, "color1"),
        api_mapping(
            Placement(uv_scale=uv_pair(uv_scale, "uv_scale", None), uv_offset=uv_pair(uv_offset, "uv_offset", None)),
            mapping,
            transform,
            v1,
            v2,
        ),
    )


def sides(texture: CheckerboardTexture) -> tuple:
    return texture.color0, texture.color1


def is_spectrum(value) -> bool:
    return isinstance(value, Spectrum)


def from_mitsuba(importer, texture, properties) -> dict | None:
    """Mitsuba 3's `checkerboard`: color0 and color1 (Mitsuba's defaults, 0.4 and 0.2, are spectrace's), to_uv."""
    table: dict = {"type": NAME}
    for parameter in PARAMETERS[:2]:
        key = parameter.name
        side = importer.spectrum(properties[key], key) if key in properties else {"value": parameter.default}
        if side is None:
            return None
        if "texture" in side and importer.texture_type(side["texture"]) == NAME:
            importer.unsupported_plugin(importer.resolve(properties[key]), f" as {key} of a checkerboard")
            return None
        table[key] = side
    for key in properties:
        if key not in ("color0", "color1", "to_uv"):
            importer.unsupported_plugin(texture, f" with {key}")
    placement = importer.uv_placement(texture, properties, MITSUBA_SQUARES_PER_UNIT)
    return None if placement is None else table | placement


def to_mitsuba(texture: CheckerboardTexture, exporter) -> dict:
    scale, offset = texture.placement.uv_scale, texture.placement.uv_offset
    return {
        "type": "checkerboard",
        "color0": exporter.spectrum(texture.color0),
        "color1": exporter.spectrum(texture.color1),
        "to_uv": exporter.uv_transform(
            [s / MITSUBA_SQUARES_PER_UNIT for s in scale], [o / MITSUBA_SQUARES_PER_UNIT for o in offset]
        ),
    }


def from_pbrt(context, texture, uv: tuple[float, float, float, float]) -> dict:
    """pbrt-v4's 2D checkerboard (tex1 1, tex2 0 by default); `uv` its (uscale, vscale, udelta, vdelta)."""
    if context.integer(texture, "dimension", 2) != 2:
        raise context.error(texture.location, f"{texture.label()}: a 3D checkerboard (spectrace's is 2D)")
    return pbrt_two_sided(context, texture, uv, "checkerboard", {"tex1": "color0", "tex2": "color1"})
