"""`principled`: the material most exported scenes are made of (Mitsuba 3's `principled`, glTF 2.0's
metallic-roughness, Blender's Principled BSDF): a diffuse base with Burley's retro-reflection, a GGX specular lobe
that is a dielectric's, a metal's or a blend of the two, rough or near-smooth transmission through a dielectric of
index `eta` (dispersive where `eta` names a glass), a clearcoat and a sheen, each weighted by a parameter that takes
a number or a grey texture (docs/materials.md, kernels/bsdf_principled.cl).

The model is Mitsuba 3's principled BSDF (after Burley 2012/2015, "Physically Based Shading at Disney" and
"Extending the Disney BRDF to a BSDF with Integrated Subsurface Scattering"), so an exported `principled` maps
one-to-one. Emission is no parameter: a glowing surface is an area light on the shape (the importers turn glTF's
emissive factor and Blender's emission into one); transparency (alpha) is the surface detail's `opacity`.
"""

from dataclasses import dataclass
from typing import Any

import numpy as np

from spectrace.core.contract import NO_TEXTURE
from spectrace.core.parameters import Parameter, Range, reflectance
from spectrace.errors import SpectraceError
from spectrace.materials.base import Material
from spectrace.materials.dielectric import write_ior
from spectrace.spectral.glasses import IndexOfRefraction, index_of_refraction
from spectrace.spectral.spectrum import Spectrum
from spectrace.spectral.spectrum_input import SpectrumLike
from spectrace.spectral.table import SpectrumTable
from spectrace.textures import number_or_texture, reflectance_or_texture

NAME = "principled"
MITSUBA_PLUGINS = ("principled",)
PBRT_MATERIALS = ()
PBRT_NONE = (
    "pbrt-v4 has no principled (Disney) material; its coateddiffuse, conductor and dielectric map onto plastic, "
    "conductor and dielectric"
)
UNIT = Range(0.0, 1.0)
# The index's range: above 1 (the interior is the denser medium, as every exported principled has it) and no more
# than the dielectric's upper limit.
ETA_RANGE = Range(1.0, 4.0, low_open=True)


def _weight(name: str, default: float, doc: str) -> Parameter:
    return Parameter(name, "float", default=default, range=UNIT, doc=doc, textured=True)


BASE_COLOR = reflectance(
    0.5,
    "base colour: the diffuse albedo, a metal's reflectance at normal incidence, the tint of transmission (its "
    "square root, once per crossing)",
    name="base_color",
    textured=True,
)
ROUGHNESS = _weight(
    "roughness",
    0.5,
    "perceptual roughness r of the specular and transmission lobes: GGX α = max(0.001, r²) (not α itself, unlike "
    "the other materials' `roughness`); also scales the diffuse retro-reflection",
)
ANISOTROPIC = _weight(
    "anisotropic",
    0.0,
    "stretches the specular lobe along the surface's dp/du (its texture coordinates' u): αu = α/√(1 − 0.9 a), "
    "αv = α √(1 − 0.9 a)",
)
METALLIC = _weight("metallic", 0.0, "blend from dielectric (0) to metal (1) whose Schlick F0 is `base_color`")
SPEC_TRANS = _weight(
    "spec_trans",
    0.0,
    "share of the dielectric part that is transmission through the surface (glass) instead of diffuse reflection",
)
ETA = Parameter(
    "eta",
    "ior",
    "dimensionless",
    default=1.5,
    range=ETA_RANGE,
    type_doc=f"number, glass name or coefficients as the dielectric's `ior`, in {ETA_RANGE} over 360–830 nm",
    doc="index of refraction of the interior relative to the outside: the dielectric Fresnel term and "
    "refraction; a dispersive index splits white light",
)
SPECULAR = Parameter(
    "specular",
    "float",
    default=None,
    range=Range(0.0, 1.0, low_open=True),
    default_doc="none",
    doc="the index written as a reflectance level instead of `eta` (Mitsuba 3's and Blender's): "
    "eta = 2/(1 − √(0.08 specular)) − 1, so 0.5 gives 1.5; give `eta` or `specular`, not both; a grey texture "
    "gives the index per point (a texel of 0: no dielectric reflection), a constant one over wavelength",
    textured=True,
)
ANISOTROPIC_ROTATION = Parameter(
    "anisotropic_rotation",
    "float",
    "degrees",
    default=0.0,
    range=Range(-360.0, 360.0),
    doc="turns the direction `anisotropic` stretches along, counter-clockwise about the normal from dp/du: "
    "the tangent is cos θ x + sin θ (n × x), or cos θ x + sin θ w (n × x) where the mesh supplies tangents of "
    "handedness w (glTF's anisotropyRotation, Blender's Anisotropic Rotation × 360°)",
)
ANISOTROPIC_DIRECTION = Parameter(
    "anisotropic_direction",
    "texture",
    default=None,
    type_doc="texture",
    doc="a raw 3-channel `bitmap` whose red and green give the direction `anisotropic` stretches along per point, "
    "d = 2 (r, g) − 1 in the frame `anisotropic_rotation` turned (x along it, y toward the signed bitangent), as "
    "glTF's anisotropyTexture; blue is not read, and a texel of d = 0 leaves the direction as it was",
)
SPEC_TINT = _weight("spec_tint", 0.0, "tints the dielectric reflection at normal incidence toward the base colour")
SHEEN = _weight("sheen", 0.0, "a grazing-angle retro-reflective layer for cloth (Burley's sheen)")
SHEEN_TINT = _weight("sheen_tint", 0.0, "tints the sheen from white toward the base colour")
CLEARCOAT = _weight(
    "clearcoat", 0.0, "a clear varnish lobe on top (index 1.5, Schlick Fresnel, GTR1 distribution; Mitsuba 3's)"
)
CLEARCOAT_GLOSS = _weight(
    "clearcoat_gloss", 0.0, "glossiness of the clearcoat: its GTR1 α runs from 0.1 (0) to 0.001 (1)"
)
# The scalar weights in the order of the kernel's parameter block (PRINCIPLED_* in kernels/bsdf_principled.cl).
SCALARS = (ROUGHNESS, ANISOTROPIC, METALLIC, SPEC_TRANS, SPEC_TINT, SHEEN, SHEEN_TINT, CLEARCOAT, CLEARCOAT_GLOSS)
PARAMETERS = (BASE_COLOR, *SCALARS[:4], ETA, SPECULAR, *SCALARS[4:], ANISOTROPIC_ROTATION, ANISOTROPIC_DIRECTION)
# α never falls below 0.001 (Mitsuba's clamp): no smooth (delta) case, whatever the roughness.
ALWAYS_ROUGH = True
# The material places its own textures: its scalars' texture indices go into its parameter block, not row fields.
WRITES_OWN_TEXTURES = True


def eta_from_specular(specular: float) -> float:
    """The index whose Schlick F0 = ((η − 1)/(η + 1))² equals 0.08 specular (Burley's specular level)."""
    return 2.0 / (1.0 - np.sqrt(0.08 * specular)) - 1.0


@dataclass(frozen=True)
class PrincipledMaterial(Material):
    """Mitsuba 3's principled BSDF: base colour, roughness, anisotropy, metallic, specular transmission with index
    `eta`, specular tint, sheen, clearcoat; every weight a number or a one-channel texture."""

    base_color: Spectrum  # or a texture
    eta: IndexOfRefraction
    roughness: float = ROUGHNESS.number_default  # each weight: or a one-channel texture
    anisotropic: float = 0.0
    metallic: float = 0.0
    spec_trans: float = 0.0
    spec_tint: float = 0.0
    sheen: float = 0.0
    sheen_tint: float = 0.0
    clearcoat: float = 0.0
    clearcoat_gloss: float = 0.0
    anisotropic_rotation: float = 0.0  # degrees
    # A grey texture of the specular level that sets the index per point (eta then holds its largest value's).
    specular_texture: object = None
    # A raw RGB bitmap turning the anisotropic frame per point by the direction of its (r, g) (kernels'
    # anisotropy_direction.cl), or None.
    anisotropic_direction: object = None

    is_delta = False  # α never falls below 0.001 (Mitsuba's clamp): every lobe has a density

    @property
    def specular(self) -> object:
        """The textured `specular` parameter as the materials' shared code reads it (a number lives in `eta`)."""
        return self.specular_texture

    @property
    def has_transmission(self) -> bool:
        from spectrace.textures import scalar_range

        return scalar_range(self.spec_trans)[1] > 0.0 and scalar_range(self.metallic)[0] < 1.0

    @property
    def is_dispersive(self) -> bool:
        return self.has_transmission and self.eta.model != "constant"


MODEL = PrincipledMaterial


def _index(eta, specular, where: str) -> IndexOfRefraction:
    from spectrace.textures import is_texture, scalar_range

    if is_texture(specular):
        specular = max(scalar_range(specular)[1], 1e-6)
    if specular is not None:
        if eta is not None:
            raise SpectraceError("give eta or specular, not both (specular is the index written another way)", where)
        eta = eta_from_specular(float(specular))
    return index_of_refraction(1.5 if eta is None else eta, where=where)


def _check_eta(ior: IndexOfRefraction, where: str) -> IndexOfRefraction:
    n = ior.at(np.arange(360.0, 831.0, 1.0))
    if not (np.all(n > ETA_RANGE.low) and np.all(n <= ETA_RANGE.high)):
        raise SpectraceError(f"eta must lie in {ETA_RANGE} over 360–830 nm", where=where)
    return ior


def from_spec(spec, resolver, key: str) -> PrincipledMaterial:
    eta = spec.eta if isinstance(spec.eta, (float, str)) else spec.eta.model_dump()
    explicit_eta = eta if "eta" in spec.model_fields_set else None
    where = resolver.where(f"{key}.eta")
    specular = spec.specular
    if specular is not None and not isinstance(specular, (int, float)):
        specular = resolver.number_or_texture(specular, f"{key}.specular", SPECULAR)
    return PrincipledMaterial(
        resolver.spectrum_or_texture(spec.base_color, f"{key}.base_color", "spectrum"),
        _check_eta(_index(explicit_eta, specular, where), where),
        **{p.name: resolver.number_or_texture(getattr(spec, p.name), f"{key}.{p.name}", p) for p in SCALARS},
        anisotropic_rotation=ANISOTROPIC_ROTATION.check(
            spec.anisotropic_rotation, resolver.where(f"{key}.anisotropic_rotation")
        ),
        specular_texture=_texture_or_none(specular),
        anisotropic_direction=_direction(
            None if spec.anisotropic_direction is None else resolver.texture(spec.anisotropic_direction, key),
            resolver.where(f"{key}.anisotropic_direction"),
        ),
    )


def _direction(texture, where: str):
    """A direction texture: a raw 3-channel bitmap (its values data, as a normal map's are), or None."""
    if texture is None:
        return None
    from spectrace.textures.bitmap import BitmapTexture

    if not isinstance(texture, BitmapTexture) or texture.channels != 3:
        raise SpectraceError("anisotropic_direction takes a 3-channel (RGB) `bitmap` texture", where=where)
    if texture.srgb_decoded:
        raise SpectraceError(
            f"anisotropic_direction '{texture.source}' is read as sRGB colours; it holds data: give raw = true",
            where=where,
        )
    return texture


def _texture_or_none(value):
    from spectrace.textures import is_texture

    return value if is_texture(value) else None


def make(
    base_color: SpectrumLike = 0.5,
    roughness: float = 0.5,
    anisotropic: float = 0.0,
    metallic: float = 0.0,
    spec_trans: float = 0.0,
    eta: float | str | dict = ETA.number_default,
    specular: float | Any | None = None,
    spec_tint: float = 0.0,
    sheen: float = 0.0,
    sheen_tint: float = 0.0,
    clearcoat: float = 0.0,
    clearcoat_gloss: float = 0.0,
    anisotropic_rotation: float = 0.0,
    anisotropic_direction: Any = None,
) -> PrincipledMaterial:
    """Mitsuba 3's principled BSDF (docs/materials.md): `base_color` (a reflectance or a texture), `roughness`
    (perceptual: GGX α = max(0.001, roughness²)), `anisotropic`, `metallic`, `spec_trans` (transmission through a
    dielectric of index `eta`: a number, a glass name or coefficients as the dielectric's `ior`; or `specular`, the
    index as a reflectance level, 0.5 for 1.5), `spec_tint`, `sheen`, `sheen_tint`, `clearcoat`, `clearcoat_gloss`:
    each weight a number in [0, 1] or a grey texture; `anisotropic_rotation` (degrees) turns the stretch's
    direction about the normal, and `anisotropic_direction` (a raw RGB bitmap) per point by its (r, g)."""
    values = {
        "roughness": roughness,
        "anisotropic": anisotropic,
        "metallic": metallic,
        "spec_trans": spec_trans,
        "spec_tint": spec_tint,
        "sheen": sheen,
        "sheen_tint": sheen_tint,
        "clearcoat": clearcoat,
        "clearcoat_gloss": clearcoat_gloss,
    }
    if specular is not None:
        specular = number_or_texture(specular, SPECULAR)
    given_eta = None if specular is not None and eta == ETA.number_default else eta
    return PrincipledMaterial(
        reflectance_or_texture(base_color, "base_color"),
        _check_eta(_index(given_eta, specular, "eta"), "eta"),
        **{p.name: number_or_texture(values[p.name], p) for p in SCALARS},
        anisotropic_rotation=ANISOTROPIC_ROTATION.check(anisotropic_rotation, "anisotropic_rotation"),
        specular_texture=_texture_or_none(specular),
        anisotropic_direction=_direction(anisotropic_direction, "anisotropic_direction"),
    )


def base_luminance(base: Spectrum) -> float:
    """CIE 1931 Y of a reflectance relative to that of the perfect white one."""
    from spectrace.spectral.observers import luminance_cd_m2

    return float(luminance_cd_m2(base) / luminance_cd_m2(Spectrum.constant(1.0)))


def is_anisotropic(anisotropic) -> bool:
    """Whether an `anisotropic` weight (a number or a texture) is above 0 anywhere: such a material's row asks for
    its frame along dp/du (Material.tangent_frame), so that its highlight follows the texture coordinates."""
    from spectrace.textures import is_texture, scalar_range

    return bool((scalar_range(anisotropic)[1] if is_texture(anisotropic) else anisotropic) > 0.0)


def write_row(row: np.ndarray, material: PrincipledMaterial, table: SpectrumTable, textures=None) -> None:
    """base_color in the row's reflectance fields, eta in its index fields; the scalar weights in a parameter block
    of the spectrum table (Material.coat_table_offset): for weight k (SCALARS' order) its value at 2k and its
    texture's index at 2k + 1 (NO_TEXTURE when it has none; a float holds these small integers exactly)."""
    write_base_color(row, material.base_color, table, textures)
    write_ior(row, material.eta)
    write_weights(row, material, SCALARS, table, textures)
    if material.specular_texture is not None:
        row["roughness_texture"] = textures.add(material.specular_texture, "float")
    if row["tangent_frame"]:
        row["tangent_rotation"] = np.radians(material.anisotropic_rotation)
        if material.anisotropic_direction is not None:  # the row's k_offset: principled has no k
            row["k_offset"] = textures.add(material.anisotropic_direction, "vector")


def write_base_color(row: np.ndarray, base_color, table: SpectrumTable, textures) -> None:
    """The base colour (a spectrum or a texture) in the row's reflectance fields, as both principled materials
    keep it."""
    from spectrace.textures import is_texture

    if is_texture(base_color):
        row["reflectance_offset"] = table.add(Spectrum.zeros())
        row["reflectance_texture"] = textures.add(base_color, "spectrum")
    else:
        row["reflectance_offset"] = table.add(base_color)


def write_weights(row: np.ndarray, material, scalars, table: SpectrumTable, textures, extra=()) -> None:
    """The parameter block both principled materials keep in the spectrum table (Material.coat_table_offset):
    weight k of `scalars` at 2k and its texture's index at 2k + 1, then the numbers of `extra`, then the base
    colour's luminance; and the row's flags that follow from the weights (transmission, a frame along dp/du)."""
    from spectrace.textures import is_texture, scalar_range

    # The base colour's luminance, for the tints (c_tint = b / lum b): CIE 1931 Y relative to a white reflector's;
    # a texture's is the mean over each path's wavelengths (-1 here).
    block = np.zeros(2 * len(scalars) + len(extra) + 1, np.float32)
    block[2 * len(scalars) : -1] = extra
    block[-1] = -1.0 if is_texture(material.base_color) else base_luminance(material.base_color)
    for k, parameter in enumerate(scalars):
        value = getattr(material, parameter.name)
        if is_texture(value):
            block[2 * k] = scalar_range(value)[1]
            block[2 * k + 1] = textures.add(value, "float")
        else:
            block[2 * k] = value
            block[2 * k + 1] = NO_TEXTURE
    row["coat_table_offset"] = table.add_block(block)
    row["nonlinear"] = int(material.has_transmission)  # the flags' BSDF_TRANSMISSION, from the row alone
    row["tangent_frame"] = int(is_anisotropic(material.anisotropic))


def weight_textures(row: np.ndarray, spectra: np.ndarray, scalars=SCALARS) -> np.ndarray:
    """The texture indices write_weights left in `row`'s parameter block of the uploaded spectrum table, one per
    weight of `scalars` (NO_TEXTURE for a number): textures no `*_texture` field of the row names."""
    offset = int(row["coat_table_offset"])
    if offset < 0:  # no block written (a dummy row)
        return np.full(len(scalars), NO_TEXTURE, np.int64)
    return spectra[offset + 1 : offset + 2 * len(scalars) : 2].astype(np.int64)


def block_textures(row: np.ndarray, spectra: np.ndarray) -> np.ndarray:
    """The textures this material keeps outside its row's fields (WRITES_OWN_TEXTURES): its weights'."""
    return weight_textures(row, spectra, SCALARS)


def from_mitsuba(importer, bsdf, properties) -> dict | None:
    """Mitsuba's `principled`: the same parameters under the same names, each weight a number or a texture; its
    sampling rates (which change no expected value) are read and left out, and `flatness` refused unless 0."""
    table = mitsuba_weights(importer, bsdf, properties, NAME, SCALARS)
    if table is None:
        return None
    for rate in ("main_specular_sampling_rate", "clearcoat_sampling_rate", "diffuse_reflectance_sampling_rate"):
        if rate in properties:
            importer.number(importer.resolve(properties[rate]))
    refuse_flatness(importer, bsdf, properties)
    if "eta" in properties:
        table["eta"] = importer.number(importer.resolve(properties["eta"]))
    elif "specular" in properties:
        table["specular"] = importer.number(importer.resolve(properties["specular"]))
    return table


def mitsuba_weights(importer, bsdf, properties, name: str, scalars) -> dict | None:
    """The table of a Mitsuba principled BSDF's base colour (0.5 when absent) and weights (`scalars`, each a number
    in its parameter's range or a texture), as both principled materials read them; None where an input cannot be
    imported (the importer has said why)."""
    base = importer.spectrum(properties["base_color"], "base_color") if "base_color" in properties else {"value": 0.5}
    if base is None:
        return None
    table: dict = {"type": name, "base_color": base}
    for parameter in scalars:
        if parameter.name not in properties:
            continue
        element = importer.resolve(properties[parameter.name])
        if element.tag == "texture":
            value = importer.scalar_texture(element, parameter.name)
        else:
            value = importer.number(element)
            allowed = parameter.range or UNIT
            if not allowed.contains(value):
                raise importer.fail(bsdf, f"{parameter.name} must lie in {allowed}, got {value:g}")
        if value is None:
            return None
        table[parameter.name] = value
    return table


def refuse_flatness(importer, bsdf, properties) -> None:
    """Mitsuba's `flatness` (Hanrahan–Krueger's fake subsurface, blended into Burley's diffuse) has no counterpart
    here: 0 is read, anything else refused rather than rendered without it."""
    if "flatness" in properties and importer.number(importer.resolve(properties["flatness"])) != 0.0:
        raise importer.fail(bsdf, "flatness (the fake subsurface term) is not supported; 0 is")


def to_mitsuba(material: PrincipledMaterial, exporter) -> dict:
    """Mitsuba's `principled` with the same parameters; `twosided` unless it transmits (spectrace's reflects on
    both faces). Mitsuba takes one index for every wavelength, so a dispersive eta is refused, as are textures."""
    from spectrace.textures import is_texture

    if material.eta.dispersive:
        raise exporter.refuse("a principled material with a dispersive eta")
    if material.specular_texture is not None or any(is_texture(getattr(material, p.name)) for p in SCALARS):
        raise exporter.refuse("a principled material with a textured weight is not exported yet")
    if material.anisotropic_rotation != 0.0 or material.anisotropic_direction is not None:
        raise exporter.refuse("a principled material with an anisotropic_rotation or direction (Mitsuba's has none)")
    entry: dict = {
        "type": NAME,
        "base_color": exporter.spectrum(material.base_color),
        "eta": float(material.eta.at(550.0)),
    }
    entry |= {p.name: float(getattr(material, p.name)) for p in SCALARS}
    if material.has_transmission:
        return entry
    return {"type": "twosided", "bsdf": entry}
