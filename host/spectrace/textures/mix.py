"""`mix`: two textures (or spectra) blended by an amount, a number in [0, 1] or a grey image texture:
value = (1 − amount) · tex1 + amount · tex2, as pbrt-v4's `mix` texture (its `tex1`, `tex2` and `amount`, default
0.5). Its operands are spectra or image textures (not checkerboards, nor other scale or mix textures); a blend of
reflectances in [0, 1] stays in [0, 1]. Mitsuba 3 has no such texture (its `blendbsdf` blends whole BSDFs).
docs/textures.md."""

from dataclasses import dataclass

from spectrace.core.parameters import Parameter, Range
from spectrace.textures.shared import Placement, api_factor, api_operand, composite_factor

NAME = "mix"
API_NAME = "mix_texture"  # spectrace.mix is the material
COMPOSITE = True
PARAMETERS = (
    Parameter("tex1", "spectrum", default=0.0, range=Range(0.0, 1.0), doc="the value where amount is 0", textured=True),
    Parameter("tex2", "spectrum", default=1.0, range=Range(0.0, 1.0), doc="the value where amount is 1", textured=True),
    Parameter(
        "amount",
        "float",
        default=0.5,
        range=Range(0.0, 1.0),
        doc="how much of tex2: a number, or a grey image texture whose value at the point is the amount",
        textured=True,
    ),
)
MITSUBA_PLUGINS: tuple[str, ...] = ()
MITSUBA_NONE = "Mitsuba 3 has no mix texture"
PBRT_TEXTURES: tuple[str, ...] = ()
PBRT_NONE = "pbrt-v4's mix texture is not imported (refused naming its line)"


@dataclass(frozen=True, eq=False)
class MixTexture:
    """(1 − amount) · tex1 + amount · tex2: tex1, tex2 Spectra or image textures, amount a float in [0, 1] or a
    one-channel image texture."""

    tex1: object
    tex2: object
    amount: object = 0.5
    source: str = "mix"
    placement: Placement = Placement()  # unused: each operand places itself

    @property
    def operands(self) -> tuple:
        return (self.tex1, self.tex2, self.amount)


MODEL = MixTexture


def from_spec(spec, resolver, key: str) -> MixTexture:
    sides = [
        resolver.spectrum_or_texture(getattr(spec, name), f"{key}.{name}", "spectrum", inner=True)
        for name in ("tex1", "tex2")
    ]
    amount = composite_factor(spec.amount, resolver, f"{key}.amount", upper=1.0, kind="amount")
    return MixTexture(sides[0], sides[1], amount)


def make(tex1=0.0, tex2=1.0, amount=0.5) -> MixTexture:
    """(1 − amount) · tex1 + amount · tex2, as pbrt-v4's `mix` texture: tex1, tex2 reflectances (anything `spectrum`
    takes, an RGB triple, or an image texture), amount a number in [0, 1] or a grey image texture."""
    return MixTexture(api_operand(tex1, "tex1"), api_operand(tex2, "tex2"), api_factor(amount, "amount", 1.0, "amount"))
