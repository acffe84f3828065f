"""`dots`: pbrt-v4's polka dots (Pharr, Jakob & Humphreys, 4th ed., 10.6.4 "Polka Dots"): two spectra (or image
textures), `inside` on randomly placed dots and `outside` elsewhere. The plane st = uv · uv_scale + uv_offset is cut
into unit cells centred on the integer points; a cell holds a dot where Perlin noise (10.6.1) at its centre + ½ is
positive, of radius 0.35, its centre shifted by up to 0.15 along s and t by the noise at two other points of the
cell. Evaluated exactly at the point, like a checkerboard (edges not filtered); kernels/noise.cl evaluates it.
docs/textures.md."""

from dataclasses import dataclass

from spectrace.core.parameters import Parameter, Range
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

NAME = "dots"
API_NAME = "dots_texture"  # spectrace.dots would read as a shape
COMPOSITE = True
PARAMETERS = (
    Parameter("inside", "spectrum", default=1.0, range=Range(0.0, 1.0), doc="the value on the dots", textured=True),
    Parameter("outside", "spectrum", default=0.0, range=Range(0.0, 1.0), doc="the value elsewhere", textured=True),
    uv_scale(1.0),
    UV_OFFSET,
    *MAPPING_PARAMETERS,
)
MITSUBA_PLUGINS: tuple[str, ...] = ()
MITSUBA_NONE = "Mitsuba 3 has no procedural textures"
PBRT_TEXTURES = ("dots",)


@dataclass(frozen=True, eq=False)
class DotsTexture:
    """Two sides, each a spectrum or an image texture (not a composite): side 0 (`inside`) on the dots."""

    inside: object
    outside: object
    placement: Placement = Placement()
    source: str = "dots"

    @property
    def color0(self) -> object:
        """The side the kernel reads on a dot (a two-sided composite's side 0, as a checkerboard's)."""
        return self.inside

    @property
    def color1(self) -> object:
        return self.outside


MODEL = DotsTexture


def from_spec(spec, resolver, key: str) -> DotsTexture:
    return two_sided_from_spec(DotsTexture, ("inside", "outside"), spec, resolver, key)


def make(
    inside=1.0,
    outside=0.0,
    *,
    uv_scale: float | tuple[float, float] = 1.0,
    uv_offset=(0.0, 0.0),
    mapping: str = "uv",
    transform=(),
    v1=(1.0, 0.0, 0.0),
    v2=(0.0, 1.0, 0.0),
) -> DotsTexture:
    """pbrt-v4's polka dots: `inside` on the dots, `outside` elsewhere (reflectances: anything `spectrum` takes, an
    RGB triple, or an image texture), one cell per unit of st = uv · uv_scale + uv_offset."""
    return DotsTexture(
        api_operand(inside, "inside"),
        api_operand(outside, "outside"),
        api_mapping(
            Placement(uv_scale=uv_pair(uv_scale, "uv_scale", None), uv_offset=uv_pair(uv_offset, "uv_offset", None)),
            mapping,
            transform,
            v1,
            v2,
        ),
    )


def from_pbrt(context, texture, uv: tuple[float, float, float, float]) -> dict:
    """pbrt-v4's `dots` (inside 1, outside 0 by default); `uv` its (uscale, vscale, udelta, vdelta)."""
    return pbrt_two_sided(context, texture, uv, "dots", {"inside": "inside", "outside": "outside"})
