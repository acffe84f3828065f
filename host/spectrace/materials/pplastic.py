"""`pplastic`: Baek et al. 2018's polarised plastic, as Mitsuba 3's `pplastic`: a rough specular reflection off a
dielectric interface plus a diffuse base whose light crosses that interface twice, added rather than layered
(docs/materials.md, kernels/bsdf_pplastic.cl). A polarised render applies the Fresnel Mueller matrices of both
lobes (docs/polarization.md); an unpolarised one their unpolarised values, as Mitsuba 3's unpolarised variants."""

from dataclasses import dataclass

import numpy as np

from spectrace.core.contract import IOR_CONSTANT, MICROFACET_DISTRIBUTIONS
from spectrace.core.parameters import (
    DEFAULT_DISTRIBUTION,
    SMOOTH_ALPHA,
    Parameter,
    Range,
    check_distribution,
    distribution,
    reflectance,
)
from spectrace.materials.opaque import Opaque
from spectrace.spectral import spectrum_input
from spectrace.spectral.spectrum import Spectrum
from spectrace.spectral.spectrum_input import SpectrumLike
from spectrace.spectral.table import SpectrumTable
from spectrace.textures import number_or_texture, reflectance_or_texture

NAME = "pplastic"
MITSUBA_PLUGINS = ("pplastic",)
PBRT_MATERIALS = ()
PBRT_NONE = "pbrt-v4 does not render polarisation"
# Mitsuba 3's defaults: polypropylene in air, α = 0.1.
IOR = Parameter(
    "ior",
    "float",
    "dimensionless",
    default=1.49,
    range=Range(1.0, 4.0, low_open=True),
    doc="index of refraction of the interface relative to the outside",
)
# The specular lobe is always a microfacet lobe (no delta coat): its α stays above the kernels' smooth limit.
ROUGHNESS = Parameter(
    "roughness",
    "float",
    default=0.1,
    range=Range(SMOOTH_ALPHA, 1.0),
    doc="microfacet α of the specular reflection (a pplastic is never smooth)",
    textured=True,
)
SPECULAR_REFLECTANCE = reflectance(
    None,
    "multiplies the specular reflection (Mitsuba 3's specular_reflectance; physical surfaces leave it out)",
    name="specular_reflectance",
    default_doc="none (1)",
)
# α never falls below the smooth limit: no smooth (delta) case, whatever the roughness.
ALWAYS_ROUGH = True
PARAMETERS = (
    reflectance(0.5, "albedo ρ of the diffuse base", textured=True),
    IOR,
    ROUGHNESS,
    distribution(),
    SPECULAR_REFLECTANCE,
)


@dataclass(frozen=True)
class PPlasticMaterial(Opaque):
    """Diffuse base of albedo `reflectance` seen through an interface of index `ior`, plus that interface's rough
    reflection (α `roughness` of the microfacet `distribution`), tinted by `specular_reflectance` when given."""

    reflectance: Spectrum  # or a texture (spectrace.textures)
    ior: float = IOR.number_default
    roughness: float = ROUGHNESS.number_default  # or a one-channel texture
    distribution: str = DEFAULT_DISTRIBUTION
    specular_reflectance: Spectrum | None = None

    is_delta = False


MODEL = PPlasticMaterial


def from_spec(spec, resolver, key: str) -> PPlasticMaterial:
    return PPlasticMaterial(
        resolver.spectrum_or_texture(spec.reflectance, f"{key}.reflectance", "spectrum"),
        ior=spec.ior,
        roughness=resolver.number_or_texture(spec.roughness, f"{key}.roughness", ROUGHNESS),
        distribution=spec.distribution,
        specular_reflectance=(
            resolver.spectrum(spec.specular_reflectance, f"{key}.specular_reflectance", emission=False)
            if spec.specular_reflectance is not None
            else None
        ),
    )


def make(
    reflectance: SpectrumLike = 0.5,
    ior: float = IOR.number_default,
    roughness: float = ROUGHNESS.number_default,
    distribution: str = DEFAULT_DISTRIBUTION,
    specular_reflectance: SpectrumLike | None = None,
) -> PPlasticMaterial:
    """Baek et al.'s polarised plastic (Mitsuba 3's pplastic): a diffuse base of albedo `reflectance` seen through
    an interface of index `ior` (> 1, relative to the outside), plus that interface's rough reflection
    (`roughness` = α of the microfacet `distribution`, "ggx" or "beckmann"; a number or a grey texture), tinted by
    `specular_reflectance` (a reflectance) when given."""
    return PPlasticMaterial(
        reflectance_or_texture(reflectance, "reflectance"),
        ior=IOR.check(ior),
        roughness=number_or_texture(roughness, ROUGHNESS),
        distribution=check_distribution(distribution),
        specular_reflectance=(
            spectrum_input.reflectance(specular_reflectance, "specular_reflectance")
            if specular_reflectance is not None
            else None
        ),
    )


def write_row(row: np.ndarray, material: PPlasticMaterial, table: SpectrumTable) -> None:
    row["reflectance_offset"] = table.add(material.reflectance)
    row["ior_model"] = IOR_CONSTANT
    row["ior"] = material.ior
    row["alpha"] = material.roughness
    row["distribution"] = MICROFACET_DISTRIBUTIONS.index(material.distribution)
    if material.specular_reflectance is not None:
        row["transmittance_offset"] = table.add(material.specular_reflectance)


def from_mitsuba(importer, bsdf, properties) -> dict | None:
    reflectance = (
        importer.spectrum(properties["diffuse_reflectance"], "diffuse_reflectance")
        if "diffuse_reflectance" in properties
        else {"value": 0.5}
    )
    if reflectance is None:
        return None
    specular = None
    if "specular_reflectance" in properties:
        if importer.resolve(properties["specular_reflectance"]).tag == "texture":
            importer.unsupported_plugin(bsdf, " with a textured specular_reflectance")
            return None
        specular = importer.spectrum(properties["specular_reflectance"], "specular_reflectance")
        if specular is None:
            return None
    ior = importer.ior(bsdf, properties, "int_ior", 1.49) / importer.ior(bsdf, properties, "ext_ior", 1.000277)
    if IOR.range_problem(ior):
        raise importer.fail(bsdf, f"int_ior / ext_ior = {ior:.4g}: spectrace's pplastic needs an index in {IOR.range}")
    roughness = importer.roughness(bsdf, properties)
    if roughness is None:
        return None
    if isinstance(roughness, float) and ROUGHNESS.range_problem(roughness):
        raise importer.fail(bsdf, f"alpha = {roughness:g}: spectrace's pplastic needs an alpha in {ROUGHNESS.range}")
    table = {
        "type": NAME,
        "reflectance": reflectance,
        "ior": round(ior, 6),
        "roughness": roughness,
        "distribution": importer.distribution(bsdf, properties),
    }
    if specular is not None and specular != {"value": 1.0}:
        table["specular_reflectance"] = specular
    return table


def to_mitsuba(material: PPlasticMaterial, exporter) -> dict:
    """Mitsuba's `pplastic` with the same albedo, index, α and distribution; one-sided, as Mitsuba's is, so
    spectrace's two-sided reflection goes into a `twosided`."""
    from spectrace.textures import is_texture

    if is_texture(material.roughness):
        raise exporter.refuse("a pplastic with textured roughness is not exported yet")
    entry: dict = {
        "type": NAME,
        "diffuse_reflectance": exporter.spectrum(material.reflectance),
        "int_ior": float(material.ior),
        "ext_ior": 1.0,
        "alpha": float(material.roughness),
        "distribution": material.distribution,
    }
    if material.specular_reflectance is not None:
        entry["specular_reflectance"] = exporter.spectrum(material.specular_reflectance)
    return {"type": "twosided", "bsdf": entry}
