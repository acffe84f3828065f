"""`principledthin`: the principled material of a sheet with no interior (Mitsuba 3's `principledthin`; a leaf,
paper, a curtain, glTF's thin-walled transmission, Blender's thin walls): Burley's diffuse base and sheen, a GGX
specular reflection, specular transmission straight through the sheet (no bending, no medium behind it) and
Lambertian diffuse transmission `diff_trans`, each weighted by a parameter that takes a number or a grey texture
(docs/materials.md, kernels/bsdf_principledthin.cl).

The parameters it shares with `principled` are the same Parameter objects and mean the same; it has no metallic,
clearcoat or interior, and its `eta` is a number (nothing bends through a thin sheet, so an index that varies with
wavelength would only tint the Fresnel term).
"""

from dataclasses import dataclass

import numpy as np

from spectrace.core.parameters import Parameter, Range, reflectance
from spectrace.materials import principled
from spectrace.materials.base import Material
from spectrace.spectral.spectrum import Spectrum
from spectrace.spectral.spectrum_input import SpectrumLike
from spectrace.spectral.table import SpectrumTable
from spectrace.textures import number_or_texture, reflectance_or_texture

NAME = "principledthin"
MITSUBA_PLUGINS = ("principledthin",)
PBRT_MATERIALS = ()
PBRT_NONE = principled.PBRT_NONE
BASE_COLOR = reflectance(
    0.5,
    "base colour: the diffuse albedo and the tint of the specular and diffuse transmission",
    name="base_color",
    textured=True,
)
DIFF_TRANS = Parameter(
    "diff_trans",
    "float",
    default=0.0,
    range=Range(0.0, 2.0),
    doc="Lambertian transmission (Mitsuba 3's range): the diffuse part's share t = diff_trans/2 leaves through "
    "the other side, 1 − t reflects",
    textured=True,
)
SPEC_TRANS = Parameter(
    "spec_trans",
    "float",
    default=0.0,
    range=principled.UNIT,
    doc="share of the sheet that is specular (half reflection, half transmission straight through), the rest "
    "diffuse; at 0 the sheet has no specular reflection either (Mitsuba 3's model)",
    textured=True,
)
ETA = Parameter(
    "eta",
    "float",
    "dimensionless",
    default=1.5,
    range=principled.ETA_RANGE,
    doc="index of refraction of the sheet relative to the outside: its Fresnel term, and the transmission's "
    "roughness (0.65 eta − 0.35) × roughness",
)
# The scalar weights in the order of the kernel's parameter block (PRINCIPLEDTHIN_* in bsdf_principledthin.cl).
SCALARS = (
    principled.ROUGHNESS,
    principled.ANISOTROPIC,
    SPEC_TRANS,
    principled.SPEC_TINT,
    principled.SHEEN,
    principled.SHEEN_TINT,
    DIFF_TRANS,
)
PARAMETERS = (BASE_COLOR, *SCALARS[:3], ETA, *SCALARS[3:])
ALWAYS_ROUGH = True
WRITES_OWN_TEXTURES = True


@dataclass(frozen=True)
class PrincipledthinMaterial(Material):
    """Mitsuba 3's thin principled BSDF: base colour, roughness, anisotropy, specular transmission through a sheet
    of index `eta`, specular tint, sheen, diffuse transmission; every weight a number or a one-channel texture."""

    base_color: Spectrum  # or a texture
    eta: float = 1.5
    roughness: float = principled.ROUGHNESS.number_default  # each weight: or a one-channel texture
    anisotropic: float = 0.0
    spec_trans: float = 0.0
    spec_tint: float = 0.0
    sheen: float = 0.0
    sheen_tint: float = 0.0
    diff_trans: float = 0.0

    is_delta = False  # α never falls below 0.001: every lobe has a density
    is_dispersive = False  # nothing bends through the sheet

    @property
    def has_transmission(self) -> bool:
        from spectrace.textures import scalar_range

        return scalar_range(self.spec_trans)[1] > 0.0 or scalar_range(self.diff_trans)[1] > 0.0


MODEL = PrincipledthinMaterial


def from_spec(spec, resolver, key: str) -> PrincipledthinMaterial:
    return PrincipledthinMaterial(
        resolver.spectrum_or_texture(spec.base_color, f"{key}.base_color", "spectrum"),
        float(spec.eta),
        **{p.name: resolver.number_or_texture(getattr(spec, p.name), f"{key}.{p.name}", p) for p in SCALARS},
    )


def make(
    base_color: SpectrumLike = 0.5,
    roughness: float = 0.5,
    anisotropic: float = 0.0,
    spec_trans: float = 0.0,
    eta: float = 1.5,
    spec_tint: float = 0.0,
    sheen: float = 0.0,
    sheen_tint: float = 0.0,
    diff_trans: float = 0.0,
) -> PrincipledthinMaterial:
    """Mitsuba 3's thin principled BSDF (docs/materials.md): `base_color` (a reflectance or a texture), `roughness`
    (perceptual, as principled's), `anisotropic`, `spec_trans` (the specular share: half reflection, half
    transmission straight through), `eta` (the sheet's index, a number), `spec_tint`, `sheen`, `sheen_tint`,
    `diff_trans` (0–2, Mitsuba's: the diffuse share that is transmitted is diff_trans/2): each weight a number or
    a grey texture."""
    values = {
        "roughness": roughness,
        "anisotropic": anisotropic,
        "spec_trans": spec_trans,
        "spec_tint": spec_tint,
        "sheen": sheen,
        "sheen_tint": sheen_tint,
        "diff_trans": diff_trans,
    }
    return PrincipledthinMaterial(
        reflectance_or_texture(base_color, "base_color"),
        ETA.check(eta),
        **{p.name: number_or_texture(values[p.name], p) for p in SCALARS},
    )


def write_row(row: np.ndarray, material: PrincipledthinMaterial, table: SpectrumTable, textures=None) -> None:
    """base_color in the row's reflectance fields; the scalar weights in a parameter block of the spectrum table
    (Material.coat_table_offset): weight k (SCALARS' order) at 2k, its texture's index at 2k + 1 (NO_TEXTURE when
    it has none), then eta and the base colour's luminance (-1 for a texture: the path's mean)."""
    principled.write_base_color(row, material.base_color, table, textures)
    principled.write_weights(row, material, SCALARS, table, textures, extra=(material.eta,))


def block_textures(row: np.ndarray, spectra: np.ndarray) -> np.ndarray:
    """The textures this material keeps outside its row's fields (WRITES_OWN_TEXTURES): its weights'."""
    return principled.weight_textures(row, spectra, SCALARS)


def from_mitsuba(importer, bsdf, properties) -> dict | None:
    """Mitsuba's `principledthin`: the same parameters under the same names, each weight a number or a texture
    (`eta` a number); its sampling rates (which change no expected value) are read and left out, and `flatness`
    (Hanrahan–Krueger's fake subsurface) is refused when not 0."""
    table = principled.mitsuba_weights(importer, bsdf, properties, NAME, SCALARS)
    if table is None:
        return None
    rates = ("specular", "diffuse")
    for rate in [f"{a}_{b}_sampling_rate" for a in rates for b in ("reflectance", "transmittance")]:
        if rate in properties:
            importer.number(importer.resolve(properties[rate]))
    principled.refuse_flatness(importer, bsdf, properties)
    if "eta" in properties:
        table["eta"] = importer.number(importer.resolve(properties["eta"]))
    return table


def to_mitsuba(material: PrincipledthinMaterial, exporter) -> dict:
    """Mitsuba's `principledthin` with the same parameters (it is the same from both faces); textures refused."""
    from spectrace.textures import is_texture

    if any(is_texture(getattr(material, p.name)) for p in SCALARS):
        raise exporter.refuse("a principledthin material with a textured weight is not exported yet")
    entry: dict = {"type": NAME, "base_color": exporter.spectrum(material.base_color), "eta": material.eta}
    return entry | {p.name: float(getattr(material, p.name)) for p in SCALARS}
