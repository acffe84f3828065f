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
PBRT_TEXTURES = ("mix",)
# pbrt-v4's defaults (MixTexture::Create): tex1 0, tex2 1, amount 0.5.
PBRT_DEFAULTS = {"tex1": 0.0, "tex2": 1.0, "amount": 0.5}
# What an imported operand may come out as that spectrace's mix does not nest (textures.COMPOSITE_TEXTURES, which
# this module cannot import: tests/interop/test_pbrt_mix_texture.py holds the two equal).
PBRT_COMPOSITES = ("checkerboard", "dots", "directionmix", "scale", "mix")


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


def from_pbrt(context, texture, uv) -> dict:
    """pbrt-v4's `mix`, float or spectrum: tex1, tex2 and amount each a value or a texture of the mix's own kind
    (amount always a float one). A constant texture is its value; a composite operand (checkerboard, dots, scale,
    mix) is refused naming its line, as spectrace's mix does not nest."""
    table: dict = {"texture": NAME}
    for name in ("tex1", "tex2", "amount"):
        table[name] = _pbrt_operand(context, texture, name)
    amount = table["amount"]
    if set(amount) == {"value"}:  # a number: pbrt's "float amount" or a constant texture of it
        table["amount"] = float(amount["value"])
    return table


def _pbrt_operand(context, texture, name: str) -> dict:
    default = PBRT_DEFAULTS[name]
    if name == "amount":
        if texture.find(name, "texture") is None:
            return {"value": float(context.one(texture, name, default))}
    elif (value := context.spectrum(texture, name, "albedo")) is not None:
        return value
    reference = texture.find(name, "texture")
    if reference is None:
        return {"value": default}
    declared = next(t for t in context.scene.textures.values() if t.entity is texture)
    key = ("float" if name == "amount" else declared.value_type, str(reference.values[0]))
    if key not in context.scene.textures:
        raise context.error(
            reference.location, f"\"{reference.label()}\" names '{context.shown(key[1])}', which no Texture defined"
        )
    inner = context.texture_table(context.scene.textures[key].entity)
    if inner.get("texture") in PBRT_COMPOSITES:
        raise context.error(
            reference.location,
            f'{texture.label()}: a {inner["texture"]} texture as "{name}" (spectrace\'s mix takes spectra, image '
            "and solid textures)",
        )
    if name == "amount" and "texture" not in inner:
        return {"value": float(inner.get("value", default)) * float(inner.get("scale", 1.0))}
    return inner
