"""`thindielectric`: a thin dielectric sheet (a window pane): specular reflection R' = 2R/(1 + R) of the light
bouncing between its two faces, the rest straight through, undeviated (docs/materials.md,
kernels/bsdf_thindielectric.cl)."""

from dataclasses import dataclass

import numpy as np

from spectrace.core.contract import IOR_CONSTANT
from spectrace.core.parameters import Parameter, Range, reflectance
from spectrace.materials.base import Material
from spectrace.spectral import spectrum_input
from spectrace.spectral.spectrum import Spectrum
from spectrace.spectral.spectrum_input import SpectrumLike
from spectrace.spectral.table import SpectrumTable
from spectrace.textures import reflectance_or_texture

NAME = "thindielectric"
MITSUBA_PLUGINS = ("thindielectric",)
PBRT_MATERIALS = ("thindielectric",)
# Above 4 nothing physical; at 1 the sheet is not there (R = 0, light passes straight through); below 1 the sheet
# is the rarer medium and reflects totally past the critical angle, as Fresnel's equations give.
IOR = Parameter(
    "ior",
    "float",
    "dimensionless",
    default=1.5,
    range=Range(0.25, 4.0),
    doc="index of refraction of the sheet relative to the outside (the same on both sides); below 1 the sheet is "
    "the rarer medium",
)
SPECULAR_REFLECTANCE = reflectance(
    None,
    "multiplies the reflection (an artistic control; clear glass leaves it out)",
    name="specular_reflectance",
    default_doc="none (1)",
    textured=True,
    texture_field="reflectance_texture",
)
SPECULAR_TRANSMITTANCE = reflectance(
    None,
    "multiplies the transmission: a tinted sheet (clear glass leaves it out)",
    name="specular_transmittance",
    default_doc="none (1)",
)
PARAMETERS = (IOR, SPECULAR_REFLECTANCE, SPECULAR_TRANSMITTANCE)


@dataclass(frozen=True)
class ThindielectricMaterial(Material):
    """A thin sheet of index `ior` relative to the outside: reflection R' = 2R/(1 + R) (R the Fresnel reflectance
    of one face), the rest passing straight through; `specular_reflectance` and `specular_transmittance` tint the
    two lobes when given."""

    ior: float = IOR.number_default
    specular_reflectance: Spectrum | None = None  # or a texture
    specular_transmittance: Spectrum | None = None

    is_delta = True
    has_transmission = True
    is_dispersive = False


MODEL = ThindielectricMaterial


def from_spec(spec, resolver, key: str) -> ThindielectricMaterial:
    reflection = (
        resolver.spectrum_or_texture(spec.specular_reflectance, f"{key}.specular_reflectance", "spectrum")
        if spec.specular_reflectance is not None
        else None
    )
    transmission = (
        resolver.spectrum(spec.specular_transmittance, f"{key}.specular_transmittance", emission=False)
        if spec.specular_transmittance is not None
        else None
    )
    return ThindielectricMaterial(spec.ior, specular_reflectance=reflection, specular_transmittance=transmission)


def make(
    ior: float = IOR.number_default,
    specular_reflectance: SpectrumLike | None = None,
    specular_transmittance: SpectrumLike | None = None,
) -> ThindielectricMaterial:
    """A thin dielectric sheet (a window pane) of index `ior` (relative to the outside): specular reflection
    R' = 2R/(1 + R), the rest straight through. `specular_reflectance` (a reflectance or a texture) and
    `specular_transmittance` (a reflectance) tint the two lobes."""
    reflection = (
        reflectance_or_texture(specular_reflectance, "specular_reflectance")
        if specular_reflectance is not None
        else None
    )
    transmission = (
        spectrum_input.reflectance(specular_transmittance, "specular_transmittance")
        if specular_transmittance is not None
        else None
    )
    return ThindielectricMaterial(IOR.check(ior), specular_reflectance=reflection, specular_transmittance=transmission)


def write_row(row: np.ndarray, material: ThindielectricMaterial, table: SpectrumTable) -> None:
    row["ior_model"] = IOR_CONSTANT
    row["ior"] = material.ior
    if material.specular_reflectance is not None:
        row["reflectance_offset"] = table.add(material.specular_reflectance)
    if material.specular_transmittance is not None:
        row["transmittance_offset"] = table.add(material.specular_transmittance)


def from_mitsuba(importer, bsdf, properties) -> dict | None:
    """Mitsuba's thindielectric: one constant index per side (default bk7 inside, air outside), whose ratio is
    spectrace's ior; its two tints."""
    named = importer.NAMED_IOR
    ior = importer.ior(bsdf, properties, "int_ior", named["bk7"]) / importer.ior(
        bsdf, properties, "ext_ior", named["air"]
    )
    if IOR.range_problem(ior):
        raise importer.fail(
            bsdf, f"int_ior / ext_ior = {ior:.4g}: spectrace's thindielectric needs an index in {IOR.range}"
        )
    table: dict = {"type": NAME, "ior": round(ior, 6)}
    for key in ("specular_reflectance", "specular_transmittance"):
        if key in properties:
            element = importer.resolve(properties[key])
            if key == "specular_transmittance" and element.tag == "texture":
                importer.unsupported_plugin(bsdf, " with a textured specular_transmittance")
                return None
            tint = importer.spectrum(properties[key], key)
            if tint is None:
                return None
            table[key] = tint
    return table


def from_pbrt(context, material) -> dict | None:
    """pbrt-v4's ThinDielectricBxDF: R' = R + T²R/(1 − R²), straight through, as here."""
    eta = context.ior(material)
    if not isinstance(eta, (int, float)):
        raise context.error(material.location, "a thindielectric's eta must be a number for spectrace")
    return {"type": "thindielectric", "ior": eta}


def to_mitsuba(material: ThindielectricMaterial, exporter) -> dict:
    entry: dict = {"type": NAME, "int_ior": float(material.ior), "ext_ior": 1.0}
    for key in ("specular_reflectance", "specular_transmittance"):
        value = getattr(material, key)
        if value is not None:
            entry[key] = exporter.spectrum(value)
    return entry
