"""`plastic`: a diffuse base under a clear dielectric coat, smooth or GGX-rough (docs/materials.md,
kernels/bsdf_plastic.cl)."""

from dataclasses import dataclass

import numpy as np

from spectrace.engine.device_types import IOR_CONSTANT
from spectrace.materials.opaque import Opaque
from spectrace.materials.parameters import REQUIRED, Parameter, Range, reflectance, roughness
from spectrace.spectral import spectrum_input
from spectrace.spectral.spectrum import Spectrum
from spectrace.spectral.spectrum_input import SpectrumLike
from spectrace.spectral.table import SpectrumTable

NAME = "plastic"
MITSUBA_PLUGINS = ("plastic", "roughplastic")
# Above 4 the coat's hemispherical Fresnel average leaves the range its quadrature is exact for (docs/materials.md).
IOR = Parameter(
    "ior",
    "float",
    "dimensionless",
    default=1.5,
    range=Range(1.0, 4.0, low_open=True),
    doc="index of refraction of the clear coat relative to the outside",
)
ROUGHNESS = roughness(0.0, "GGX α of the coat")
PARAMETERS = (reflectance(REQUIRED, "albedo of the diffuse base under the coat", textured=True), IOR, ROUGHNESS)


@dataclass(frozen=True)
class PlasticMaterial(Opaque):
    """Diffuse base of albedo `reflectance` under a clear coat of index `ior` relative to the outside."""

    reflectance: Spectrum  # or a texture (spectrace.textures)
    ior: float = IOR.number_default
    roughness: float = ROUGHNESS.number_default  # or a one-channel texture

    is_delta = False  # the base is diffuse whatever the coat


MODEL = PlasticMaterial


def from_spec(spec, resolver, key: str) -> PlasticMaterial:
    return PlasticMaterial(
        resolver.spectrum_or_texture(spec.reflectance, f"{key}.reflectance", "spectrum"),
        ior=spec.ior,
        roughness=resolver.number_or_texture(spec.roughness, f"{key}.roughness", ROUGHNESS),
    )


def make(
    reflectance: SpectrumLike, ior: float = IOR.number_default, roughness: float = ROUGHNESS.number_default
) -> PlasticMaterial:
    """A diffuse base of albedo `reflectance` under a clear coat of index `ior` (> 1, relative to the outside),
    smooth or GGX-rough (`roughness` = α, a number or a grey texture)."""
    return PlasticMaterial(
        spectrum_input.reflectance_or_texture(reflectance, "reflectance"),
        ior=IOR.check(ior),
        roughness=spectrum_input.number_or_texture(roughness, ROUGHNESS),
    )


def write_row(row: np.ndarray, material: PlasticMaterial, table: SpectrumTable) -> None:
    row["reflectance_offset"] = table.add(material.reflectance)
    row["ior_model"] = IOR_CONSTANT
    row["ior"] = material.ior
    row["alpha"] = material.roughness


def from_mitsuba(importer, bsdf, properties) -> dict | None:
    reflectance = (
        importer.spectrum(properties["diffuse_reflectance"], "diffuse_reflectance")
        if "diffuse_reflectance" in properties
        else {"value": 0.5}
    )
    if reflectance is None:
        return None
    if "specular_reflectance" in properties:
        specular = importer.spectrum(properties["specular_reflectance"], "specular_reflectance")
        if specular is not None and specular != {"value": 1.0}:
            importer.unsupported_plugin(bsdf, " with specular_reflectance other than 1")
            return None
    if "nonlinear" in properties and importer.text(properties["nonlinear"]) == "true":
        importer.unsupported_plugin(bsdf, " with nonlinear = true")
        return None
    ior = importer.ior(bsdf, properties, "int_ior", 1.49) / importer.ior(bsdf, properties, "ext_ior", 1.000277)
    if IOR.range_problem(ior):
        raise importer.fail(
            bsdf, f"int_ior / ext_ior = {ior:.4g}: spectrace's plastic needs a coat index in {IOR.range}"
        )
    roughness = importer.roughness(bsdf, properties) if importer.kind(bsdf) == "roughplastic" else 0.0
    if roughness is None:
        return None
    importer.notes.append(
        f"line {bsdf.line}: {bsdf.label()}: spectrace's plastic couples coat and base "
        "differently from Mitsuba's (an energy-conserving symmetric "
        "coupling instead of internal scattering; see docs/materials.md), so the brightness of "
        "its diffuse part differs"
    )
    table = {"type": "plastic", "reflectance": reflectance, "ior": round(ior, 6)}
    if roughness != 0.0:  # a number above 0, or a texture
        table["roughness"] = roughness
    return table
