"""`mix`: two materials, one of which shades each surface point: the second with probability `amount`, the first
otherwise (pbrt-v4's `mix` material, its MixMaterial::ChooseMaterial; Mitsuba 3's `blendbsdf`, its `weight`). What
a pixel averages is the blended BSDF (1 − amount) f₁ + amount f₂, for any two materials, mixes among them.

It has no BSDF of its own: kernels/material_mix.cl replaces it, where a path meets it, by one of its materials,
chosen by a hash of the point and the direction it is seen from (not a sampler draw: the sampler's dimensions and
so every other material's bits stay as they were, and a render splits into passes and tiles with the same bits).
Every integrator then sees one ordinary material at that vertex, the same for its light, its BSDF sample and the
connections BDPT makes to it. Its row (kernels/types.h) holds the two materials' rows' indices in `eta_offset`
and `k_offset` and the amount in `alpha` (its texture in `roughness_texture`); spectrace.materials appends the
materials' rows after it.
"""

from dataclasses import dataclass

import numpy as np

from spectrace.core.parameters import Parameter, Range
from spectrace.errors import SpectraceError
from spectrace.materials.base import Material
from spectrace.spectral.table import SpectrumTable
from spectrace.textures import COMPOSITE_TEXTURES

# The textures a `mix` texture cannot take as an operand (the kernel does not recurse: docs/textures.md).
_COMPOSITES = COMPOSITE_TEXTURES

NAME = "mix"
# No bsdf_mix.cl: the mix is resolved before any BSDF is called (kernels/material_mix.cl).
COMPOSITE = True
KERNEL_FILE = "material_mix.cl"
MITSUBA_PLUGINS = ("blendbsdf",)
PBRT_MATERIALS = ("mix",)
# Mixes within mixes, counting this one (MIX_MAX_DEPTH in kernels/material_mix.cl).
MAX_DEPTH = 8
# The Material row fields holding the two materials' row indices.
ROW_FIELDS = ("eta_offset", "k_offset")
AMOUNT_RANGE = Range(0.0, 1.0)
PARAMETERS = (
    Parameter(
        "materials",
        "materials",
        doc="the two materials mixed, by name ([materials.NAME] of this file); either may be a mix itself",
        type_doc="two material names",
    ),
    Parameter(
        "amount",
        "float",
        default=0.5,
        range=AMOUNT_RANGE,
        doc="the probability that a point shades with the second material (pbrt-v4's `amount`, Mitsuba's "
        "`weight`): the blend (1 − amount) f₁ + amount f₂",
        textured=True,
        texture_field="roughness_texture",
    ),
)
_AMOUNT = PARAMETERS[1]


@dataclass(frozen=True)
class MixMaterial(Material):
    """(1 − amount) · materials[0] + amount · materials[1], one of them chosen per shading point."""

    materials: tuple[Material, Material]
    amount: object = 0.5  # a float in [0, 1], or a one-channel texture of it

    @property
    def is_delta(self) -> bool:
        return all(m.is_delta for m in self.materials)

    @property
    def has_transmission(self) -> bool:
        return any(m.has_transmission for m in self.materials)

    @property
    def is_dispersive(self) -> bool:
        return any(m.is_dispersive for m in self.materials)

    @property
    def is_diffuse(self) -> bool:
        return all(m.is_diffuse for m in self.materials)


MODEL = MixMaterial


def depth(material) -> int:
    """How many mixes deep `material` is: 0 for a BSDF, 1 for a mix of two BSDFs."""
    if not isinstance(material, MixMaterial):
        return 0
    return 1 + max(depth(m) for m in material.materials)


def check(materials, amount, where) -> MixMaterial:
    """The mix of two resolved materials, or a SpectraceError naming the key (`where(name)`): a number amount in
    [0, 1] (a texture's values are checked where it is read), no deeper than MAX_DEPTH, and no opacity on a mixed
    material (the visibility queries read the opacity of the surface's own material: give it to the mix)."""
    from spectrace.textures import check_texture_values, is_texture

    materials = tuple(materials)
    if len(materials) != 2 or not all(isinstance(m, Material) for m in materials):
        raise SpectraceError("a mix takes two materials", where=where("materials"))
    for m in materials:
        if m.detail is not None and m.detail.is_cut_out:
            message = "a mixed material cannot have an opacity (cut-outs): give the opacity to the mix"
            raise SpectraceError(message, where=where("materials"))
    if is_texture(amount):
        check_texture_values(amount, "amount", where("amount"))
    else:
        amount = _AMOUNT.check(amount, where("amount"))
    mixed = MixMaterial((materials[0], materials[1]), amount)
    if depth(mixed) > MAX_DEPTH:
        raise SpectraceError(f"mixes nest at most {MAX_DEPTH} deep, this one {depth(mixed)}", where=where("materials"))
    return mixed


def from_spec(spec, resolver, key: str) -> MixMaterial:
    names = spec.materials
    materials = [resolver.material_named(name, f"{key}.materials") for name in names]
    amount = spec.amount
    if not isinstance(amount, float):
        amount = resolver.texture(amount, f"{key}.amount")
    return check(materials, amount, lambda name: resolver.where(f"{key}.{name}"))


def make(materials, amount=0.5) -> MixMaterial:
    """One of two materials (first, second) per shading point, the second with probability `amount` (a number in
    [0, 1] or a grey texture): the blend (1 − amount) · first + amount · second, as pbrt-v4's `mix` and Mitsuba's
    `blendbsdf`."""
    return check(materials, amount, lambda name: name)


def write_row(row: np.ndarray, material: MixMaterial, table: SpectrumTable) -> None:
    # The materials' row indices (ROW_FIELDS) are written by spectrace.materials once their rows are placed.
    row["alpha"] = float(material.amount)  # type: ignore[arg-type]  # a number here (material_row)


def surface_detail_problem(material: MixMaterial) -> str | None:
    """Why the mix's own surface detail cannot be honoured, or None: the normal is turned by the material chosen
    at the point, so a mix takes no normal or bump map of its own."""
    detail = material.detail
    if detail is not None and (getattr(detail, "normal_map", None) is not None or getattr(detail, "bump_map", None)):
        return "a mix takes no normal or bump map of its own; give them to its materials"
    return None


def check_spec(spec) -> None:
    if spec.normal_map is not None or spec.bump_map is not None:
        raise ValueError("a mix takes no normal or bump map of its own; give them to its materials")


SPEC_CHECKS = (check_spec,)


def from_mitsuba(importer, bsdf, properties) -> dict | None:
    """blendbsdf: its two nested bsdfs in order (weight 0 is the first alone, 1 the second), its `weight` a number
    or a texture."""
    nested = importer.nested(properties, "bsdf")
    if len(nested) != 2:
        importer.unsupported_plugin(bsdf, f" with {len(nested)} nested bsdfs (a blend takes two)")
        return None
    names = []
    for index, child in enumerate(nested):
        # On a shape whose v runs up, the materials' textures are flipped as the blend's own are.
        name = importer.material(child, f"{importer.attribute(bsdf, 'id') or 'blend'}_{index}", importer.flip_v)
        if name is None:
            return None
        names.append(name)
    table: dict = {"type": NAME, "materials": names}
    if "weight" in properties:
        weight = importer.resolve(properties["weight"])
        if weight.tag == "texture":
            texture = importer.scalar_texture(weight, "weight")
            if texture is None:
                return None
            table["amount"] = texture
        else:
            table["amount"] = importer.number(weight)
    else:
        table["amount"] = 0.5
    return table


# The pbrt-v4 float textures a mix's amount may be, and spectrace's textures they become.
_PBRT_AMOUNT_TEXTURES = ("imagemap", "checkerboard", "fbm", "wrinkled", "windy")
_AMOUNT_TEXTURES = ("bitmap", "checkerboard", "fbm", "wrinkled", "windy")


def from_pbrt(context, material) -> dict | None:
    """pbrt-v4's `mix`: at each intersection one of `materials` is chosen by a hash of the point and direction, the
    second with probability `amount` (its MixMaterial::ChooseMaterial), as this material chooses. Two diffuse
    materials with a number or image amount become instead one diffuse material of the blended reflectance,
    (1 - amount) R1 + amount R2 (the `mix` texture): the same average without the choice's noise. An amount of 0 or
    1, or the same material twice, is that material."""
    names = material.find("materials", "string")
    if names is None or len(names.values) != 2:
        raise context.error(material.location, f'{material.label()} needs "string materials" naming two materials')
    tables = []
    for name in names.values:
        if str(name) not in context.scene.named_materials:
            raise context.error(
                names.location, f"mix names '{context.shown(str(name))}', which no MakeNamedMaterial defined"
            )
        tables.append(context.material_table(context.scene.named_materials[str(name)]))
    amount_texture = material.find("amount", "texture")
    number = context.one(material, "amount", 0.5)
    amount: float | dict = number
    if amount_texture is not None:
        key = ("float", str(amount_texture.values[0]))
        if key not in context.scene.textures:
            raise context.error(
                amount_texture.location,
                f"\"{amount_texture.label()}\" names '{context.shown(key[1])}', which no Texture defined",
            )
        texture: dict = context.texture_table(context.scene.textures[key].entity)
        if texture.get("texture") not in _AMOUNT_TEXTURES:
            raise context.error(
                amount_texture.location, f"a mix's amount texture is one of {', '.join(_PBRT_AMOUNT_TEXTURES)}"
            )
        amount = texture
    elif number <= 0.0 or number >= 1.0:
        return tables[number >= 1.0]
    if tables[0] == tables[1]:
        return tables[0]
    if any(table is None for table in tables):
        raise context.error(material.location, "material 'mix' with an interface: spectrace mixes two materials")
    pair = [table for table in tables if table is not None]
    if (
        all(table["type"] == "diffuse" for table in pair)
        and (not isinstance(amount, dict) or amount.get("texture") == "bitmap")
        and not any(context.texture_kind(table["reflectance"]) in _COMPOSITES for table in pair)
    ):
        return {
            "type": "diffuse",
            "reflectance": {
                "texture": "mix",
                "tex1": pair[0]["reflectance"],
                "tex2": pair[1]["reflectance"],
                "amount": amount,
            },
        }
    materials = [context.material(str(name), names.location) for name in names.values]
    return {"type": "mix", "materials": materials, "amount": amount}


def to_mitsuba(material: MixMaterial, exporter) -> dict:
    """Mitsuba's blendbsdf of the two materials' own exports, with the amount as its weight."""
    from spectrace.textures import is_texture

    amount = material.amount
    weight = exporter.spectrum(amount) if is_texture(amount) else float(amount)  # type: ignore[arg-type]
    return {
        "type": "blendbsdf",
        "weight": weight,
        "bsdf_0": exporter.material(material.materials[0]),
        "bsdf_1": exporter.material(material.materials[1]),
    }
