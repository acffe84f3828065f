"""`scale`: a texture (or spectrum) times a factor, a number or a grey image texture: value = tex · scale, as
pbrt-v4's `scale` texture (its `tex` and `scale`). Its operands are spectra or image textures (not checkerboards,
nor other scale or mix textures); as a reflectance the product must stay within [0, 1] (checked from the largest
values of both). Mitsuba 3 has no such texture (its scale factors belong to emitters and BSDF parameters).
docs/textures.md."""

from dataclasses import dataclass

from spectrace.core.parameters import Parameter, Range
from spectrace.textures.shared import Placement, api_factor, api_operand, composite_factor

NAME = "scale"
API_NAME = "scale_texture"  # as mix_texture, whose plain name is the material's
COMPOSITE = True
PARAMETERS = (
    Parameter("tex", "spectrum", default=1.0, range=Range(0.0, 1.0), doc="what is scaled", textured=True),
    Parameter(
        "scale",
        "float",
        default=1.0,
        range=Range(0.0, None),
        doc="the factor: a number, or a grey image texture whose value at the point is the factor",
        textured=True,
    ),
)
MITSUBA_PLUGINS: tuple[str, ...] = ()
MITSUBA_NONE = "Mitsuba 3 has no scale texture"
PBRT_TEXTURES: tuple[str, ...] = ()
PBRT_NONE = (
    "pbrt-v4's scale texture imports as the spectrum it scales, scaled, or as a scaled copy of its image "
    "(spectrace.interop.pbrt.textures)"
)


@dataclass(frozen=True, eq=False)
class ScaleTexture:
    """tex (a Spectrum or an image texture) times scale (a float >= 0 or a one-channel image texture)."""

    tex: object
    scale: object = 1.0
    source: str = "scale"
    placement: Placement = Placement()  # unused: each operand places itself

    @property
    def operands(self) -> tuple:
        return (self.tex, self.scale)


MODEL = ScaleTexture


def from_spec(spec, resolver, key: str) -> ScaleTexture:
    tex = resolver.spectrum_or_texture(spec.tex, f"{key}.tex", "spectrum", inner=True)
    return ScaleTexture(tex, composite_factor(spec.scale, resolver, f"{key}.scale", upper=None))


def make(tex=1.0, scale=1.0) -> ScaleTexture:
    """tex (a reflectance: anything `spectrum` takes, an RGB triple, or an image texture) times scale (a number >= 0
    or a grey image texture), as pbrt-v4's `scale` texture; as a reflectance the product must stay within [0, 1]."""
    return ScaleTexture(api_operand(tex, "tex"), api_factor(scale, "scale", None))
