"""`plastic`: a diffuse base under a clear dielectric coat, smooth or rough (GGX or Beckmann), its internal
scattering linear or not in the base's albedo (docs/materials.md, kernels/bsdf_plastic.cl)."""

from dataclasses import dataclass

import numpy as np

from spectrace.core.contract import IOR_CONSTANT, MICROFACET_DISTRIBUTIONS
from spectrace.core.parameters import (
    DEFAULT_DISTRIBUTION,
    REQUIRED,
    Parameter,
    Range,
    check_distribution,
    distribution,
    reflectance,
    roughness,
)
from spectrace.errors import SpectraceError
from spectrace.materials.coat import rough_coat
from spectrace.materials.opaque import Opaque, smooth_everywhere
from spectrace.spectral import spectrum_input
from spectrace.spectral.spectrum import Spectrum
from spectrace.spectral.spectrum_input import SpectrumLike
from spectrace.spectral.table import SpectrumTable
from spectrace.textures import number_or_texture, reflectance_or_texture

NAME = "plastic"
MITSUBA_PLUGINS = ("plastic", "roughplastic")
PBRT_MATERIALS: tuple[str, ...] = ()
PBRT_NONE = "pbrt-v4's coateddiffuse is the stochastic layered model (coateddiffuse.py); pbrt-v4 has no plastic"
# Above 4 the coat's hemispherical Fresnel average leaves the range its quadrature is exact for (docs/materials.md).
IOR = Parameter(
    "ior",
    "float",
    "dimensionless",
    default=1.5,
    range=Range(1.0, 4.0, low_open=True),
    doc="index of refraction of the clear coat relative to the outside",
)
ROUGHNESS = roughness(0.0, "microfacet α of the coat")
NONLINEAR = Parameter(
    "nonlinear",
    "bool",
    default=False,
    doc="light reflected back down by the coat meets the base again, so the albedo ρ becomes "
    "ρ (1 − F_dr)/(1 − ρ F_dr) (Mitsuba 3's `nonlinear`: deeper colours)",
)
COAT_TRANSMISSIONS = ("smooth", "rough")
COAT_TRANSMISSION = Parameter(
    "coat_transmission",
    "coat_transmission",
    default="smooth",
    default_doc='`"smooth"`',
    type_doc='`"smooth"` or `"rough"`',
    doc="how light crosses a rough coat to the base and back: by the smooth interface's 1 − F, or by the rough "
    "interface's own transmittance, which loses what single scattering loses (Mitsuba 3's roughplastic); "
    "`rough` needs a number `roughness`",
)
SPECULAR_REFLECTANCE = reflectance(
    None,
    "multiplies the coat's reflection (Mitsuba 3's specular_reflectance; a clear coat leaves it out)",
    name="specular_reflectance",
    default_doc="none (1)",
)
PARAMETERS = (
    reflectance(REQUIRED, "albedo of the diffuse base under the coat", textured=True),
    IOR,
    ROUGHNESS,
    distribution(),
    NONLINEAR,
    COAT_TRANSMISSION,
    SPECULAR_REFLECTANCE,
)


@dataclass(frozen=True)
class PlasticMaterial(Opaque):
    """Diffuse base of albedo `reflectance` under a clear coat of index `ior` relative to the outside, smooth or
    rough (α `roughness` of the microfacet `distribution`); `nonlinear`: the internal scattering depends on the
    albedo; `specular_reflectance` tints the coat's reflection when given."""

    reflectance: Spectrum  # or a texture (spectrace.textures)
    ior: float = IOR.number_default
    roughness: float = ROUGHNESS.number_default  # or a one-channel texture
    distribution: str = DEFAULT_DISTRIBUTION
    nonlinear: bool = False
    coat_transmission: str = "smooth"
    specular_reflectance: Spectrum | None = None

    is_delta = False  # the base is diffuse whatever the coat


MODEL = PlasticMaterial


def from_spec(spec, resolver, key: str) -> PlasticMaterial:
    return PlasticMaterial(
        resolver.spectrum_or_texture(spec.reflectance, f"{key}.reflectance", "spectrum"),
        ior=spec.ior,
        roughness=resolver.number_or_texture(spec.roughness, f"{key}.roughness", ROUGHNESS),
        distribution=spec.distribution,
        nonlinear=spec.nonlinear,
        coat_transmission=spec.coat_transmission,
        specular_reflectance=(
            resolver.spectrum(spec.specular_reflectance, f"{key}.specular_reflectance", emission=False)
            if spec.specular_reflectance is not None
            else None
        ),
    )


def coat_problem(coat_transmission: str, roughness) -> str | None:
    """Why a coat's transmission cannot be tabulated, or None: the rough coat's table is made for one α."""
    if coat_transmission == "rough" and not isinstance(roughness, (int, float)):
        return "coat_transmission 'rough' needs a number roughness (its transmittance is tabulated for one α)"
    return None


def check_spec(spec) -> None:
    if problem := coat_problem(spec.coat_transmission, spec.roughness):
        raise ValueError(problem)


SPEC_CHECKS = (check_spec,)


def make(
    reflectance: SpectrumLike,
    ior: float = IOR.number_default,
    roughness: float = ROUGHNESS.number_default,
    distribution: str = DEFAULT_DISTRIBUTION,
    nonlinear: bool = False,
    coat_transmission: str = "smooth",
    specular_reflectance: SpectrumLike | None = None,
) -> PlasticMaterial:
    """A diffuse base of albedo `reflectance` under a clear coat of index `ior` (> 1, relative to the outside),
    smooth or rough (`roughness` = α of the microfacet `distribution`, "ggx" or "beckmann"; a number or a grey
    texture). `nonlinear`: light the coat reflects back down meets the base again, which deepens colours (Mitsuba's
    model of that name). `coat_transmission`: "smooth" (light crosses a rough coat by the smooth interface's
    1 − F) or "rough" (by the rough interface's own transmittance, as Mitsuba's roughplastic; a number
    roughness only). `specular_reflectance` (a reflectance) tints the coat's reflection."""
    if coat_transmission not in COAT_TRANSMISSIONS:
        raise SpectraceError(
            f"coat_transmission must be one of {', '.join(COAT_TRANSMISSIONS)}, got {coat_transmission!r}",
            where="coat_transmission",
        )
    if problem := coat_problem(coat_transmission, roughness):
        raise SpectraceError(problem, where="coat_transmission")
    return PlasticMaterial(
        reflectance_or_texture(reflectance, "reflectance"),
        ior=IOR.check(ior),
        roughness=number_or_texture(roughness, ROUGHNESS),
        distribution=check_distribution(distribution),
        nonlinear=bool(nonlinear),
        coat_transmission=coat_transmission,
        specular_reflectance=(
            spectrum_input.reflectance(specular_reflectance, "specular_reflectance")
            if specular_reflectance is not None
            else None
        ),
    )


def write_row(row: np.ndarray, material: PlasticMaterial, table: SpectrumTable) -> None:
    row["reflectance_offset"] = table.add(material.reflectance)
    row["ior_model"] = IOR_CONSTANT
    row["ior"] = material.ior
    row["alpha"] = material.roughness
    row["distribution"] = MICROFACET_DISTRIBUTIONS.index(material.distribution)
    row["nonlinear"] = int(material.nonlinear)
    if material.specular_reflectance is not None:
        row["transmittance_offset"] = table.add(material.specular_reflectance)
    # A smooth coat's own transmittance is 1 − F: the table is only written for a rough one.
    if material.coat_transmission == "rough" and not smooth_everywhere(material.roughness):
        transmittance, internal = rough_coat(float(material.ior), float(material.roughness), material.distribution)
        row["coat_table_offset"] = table.add_row(transmittance)
        row["coat_internal_reflectance"] = internal


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
    nonlinear = "nonlinear" in properties and importer.boolean(importer.resolve(properties["nonlinear"]))
    ior = importer.ior(bsdf, properties, "int_ior", 1.49) / importer.ior(bsdf, properties, "ext_ior", 1.000277)
    if IOR.range_problem(ior):
        raise importer.fail(
            bsdf, f"int_ior / ext_ior = {ior:.4g}: spectrace's plastic needs a coat index in {IOR.range}"
        )
    roughness = importer.roughness(bsdf, properties) if importer.kind(bsdf) == "roughplastic" else 0.0
    if roughness is None:
        return None
    table = {"type": "plastic", "reflectance": reflectance, "ior": round(ior, 6)}
    if roughness != 0.0:  # a number above 0, or a texture
        table["roughness"] = roughness
        if (kind := importer.distribution(bsdf, properties)) != DEFAULT_DISTRIBUTION:
            table["distribution"] = kind
        if isinstance(roughness, float):
            table["coat_transmission"] = "rough"  # Mitsuba's roughplastic: the rough coat's own transmittance
        else:
            importer.notes.append(
                f"{importer.at(bsdf)}: {bsdf.label()}: with a textured alpha, spectrace's rough plastic passes light "
                "through its coat by the smooth interface's Fresnel terms, Mitsuba's by the rough interface's "
                "(see docs/materials.md), so its diffuse part is brighter"
            )
    if nonlinear:
        table["nonlinear"] = True
    if specular is not None and specular != {"value": 1.0}:
        table["specular_reflectance"] = specular
    return table


def to_mitsuba(material: PlasticMaterial, exporter) -> dict:
    """Mitsuba's `plastic` (a smooth coat) or `roughplastic` (a rough coat crossed by its own transmittance:
    coat_transmission "rough") with the same albedo, coat index, `nonlinear`, α and distribution; `twosided`, as
    spectrace's plastic reflects on both faces. A rough coat crossed by the smooth interface's Fresnel terms has no
    Mitsuba counterpart and is refused, as is a textured roughness."""
    from spectrace.materials.opaque import smooth_everywhere
    from spectrace.textures import is_texture

    if is_texture(material.roughness):
        raise exporter.refuse("a plastic with textured roughness is not exported yet")
    entry: dict = {
        "diffuse_reflectance": exporter.spectrum(material.reflectance),
        "int_ior": float(material.ior),
        "ext_ior": 1.0,
        "nonlinear": bool(material.nonlinear),
    }
    if material.specular_reflectance is not None:
        entry["specular_reflectance"] = exporter.spectrum(material.specular_reflectance)
    if smooth_everywhere(material.roughness):
        entry["type"] = "plastic"
    elif material.coat_transmission == "rough":
        entry |= {"type": "roughplastic", "alpha": float(material.roughness), "distribution": material.distribution}
    else:
        raise exporter.refuse(
            'a rough plastic with coat_transmission "smooth" (Mitsuba\'s roughplastic crosses its coat by the rough '
            "interface's transmittance)"
        )
    return {"type": "twosided", "bsdf": entry}
