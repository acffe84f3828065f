"""`dielectric`: glass, water: Fresnel reflection and Snell refraction into an interior of index n(λ), smooth or
GGX- or Beckmann-rough, dispersive when n depends on λ (docs/materials.md, kernels/bsdf_dielectric.cl,
kernels/ior.cl)."""

from dataclasses import dataclass

import numpy as np

from spectrace.core.contract import IOR_CAUCHY, IOR_CONSTANT, IOR_SELLMEIER, MICROFACET_DISTRIBUTIONS
from spectrace.core.parameters import (
    DEFAULT_DISTRIBUTION,
    Parameter,
    Range,
    check_distribution,
    distribution,
    roughness,
    specular_tint,
)
from spectrace.errors import SpectraceError
from spectrace.materials.base import Material
from spectrace.materials.opaque import smooth_everywhere
from spectrace.spectral.glasses import IOR_RANGE, ROUGH_IOR_GAP, IndexOfRefraction, index_of_refraction
from spectrace.spectral.spectrum import Spectrum
from spectrace.spectral.spectrum_input import SpectrumLike
from spectrace.spectral.table import SpectrumTable
from spectrace.textures import number_or_texture, reflectance_or_texture

NAME = "dielectric"
MITSUBA_PLUGINS = ("dielectric", "roughdielectric")
PBRT_MATERIALS = ("dielectric",)
ROUGHNESS = roughness(0.0, "microfacet α; 0 = polished glass")
# A number, a glass name or Sellmeier/Cauchy coefficients: spectral.glasses.index_of_refraction checks the
# range over the whole grid.
IOR = Parameter(
    "ior",
    "ior",
    "dimensionless",
    default=1.5,
    range=Range(*IOR_RANGE),
    type_doc=f"see below, dimensionless, in {Range(*IOR_RANGE)} over 360–830 nm",
    doc="index of refraction of the interior relative to the exterior, which is air (n = 1); below 1 the "
    "interior is the rarer medium (an air bubble in water), at 1 a smooth surface passes light straight through "
    f"(a rough one needs an index at least {ROUGH_IOR_GAP:g} away from 1); a dispersive `ior` splits white light",
)
PARAMETERS = (
    IOR,
    ROUGHNESS,
    distribution(),
    specular_tint("multiplies both reflection and transmission (an artistic control; clear glass leaves it out)"),
)


@dataclass(frozen=True)
class DielectricMaterial(Material):
    """Glass, water: Fresnel reflection and Snell refraction at an interface to an interior of index `ior` relative
    to the exterior (air), which may depend on the wavelength (dispersion); smooth or GGX-rough. The geometric
    normal (the winding) points to the exterior. `specular_tint` multiplies both lobes when given."""

    ior: IndexOfRefraction
    roughness: float = ROUGHNESS.number_default  # or a one-channel texture
    specular_tint: Spectrum | None = None  # or a texture
    distribution: str = DEFAULT_DISTRIBUTION

    has_transmission = True

    @property
    def is_delta(self) -> bool:
        return smooth_everywhere(self.roughness)

    @property
    def is_dispersive(self) -> bool:
        return self.ior.model != "constant"


MODEL = DielectricMaterial


def from_spec(spec, resolver, key: str) -> DielectricMaterial:
    ior = spec.ior if isinstance(spec.ior, (float, str)) else spec.ior.model_dump()
    tint = (
        resolver.spectrum_or_texture(spec.specular_tint, f"{key}.specular_tint", "spectrum")
        if spec.specular_tint is not None
        else None
    )
    material = DielectricMaterial(
        index_of_refraction(ior, where=resolver.where(f"{key}.ior")),
        roughness=resolver.number_or_texture(spec.roughness, f"{key}.roughness", ROUGHNESS),
        specular_tint=tint,
        distribution=spec.distribution,
    )
    return check_rough_index(material, resolver.where(f"{key}.ior"))


def make(
    ior: float | str | dict = IOR.number_default,
    roughness: float = ROUGHNESS.number_default,
    distribution: str = DEFAULT_DISTRIBUTION,
    specular_tint: SpectrumLike | None = None,
) -> DielectricMaterial:
    """Glass or water: Fresnel reflection and Snell refraction into an interior of index `ior` relative to the
    exterior (air) — a number, a glass name ("BK7", "SF11", "N-SF11"; `spectra/glasses/`), {"sellmeier": [B1, B2, B3,
    C1, C2, C3]} or {"cauchy": [a, b]} (λ in µm) — smooth or rough (`roughness` = α of the microfacet
    `distribution`, "ggx" or "beckmann"). The mesh's winding must
    face the exterior. A dispersive ior splits white light; `specular_tint` (a reflectance or a texture) multiplies
    both lobes; `roughness` may be a grey texture."""
    tint = reflectance_or_texture(specular_tint, "specular_tint") if specular_tint is not None else None
    material = DielectricMaterial(
        index_of_refraction(ior, where="ior"),
        roughness=number_or_texture(roughness, ROUGHNESS),
        specular_tint=tint,
        distribution=check_distribution(distribution),
    )
    return check_rough_index(material, "ior")


def check_rough_index(material: DielectricMaterial, where: str) -> DielectricMaterial:
    """`material`, or a SpectraceError when it is rough and its index comes within ROUGH_IOR_GAP of 1 somewhere in
    360–830 nm (a smooth one passes light straight through there, a rough one has no refraction half vector)."""
    if material.is_delta:
        return material
    n = material.ior.at(np.arange(360.0, 831.0, 1.0))
    if np.any(np.abs(n - 1.0) < ROUGH_IOR_GAP):
        raise SpectraceError(
            f"a rough dielectric's index must differ from 1 by at least {ROUGH_IOR_GAP:g} "
            "(an index-matched rough surface has no refraction; make it smooth: roughness = 0)",
            where=where,
        )
    return material


def write_ior(row: np.ndarray, ior: IndexOfRefraction) -> None:
    """The index's model and coefficients in a Material row (kernels/ior.cl's material_ior reads them); the
    principled material's glass writes its index the same way."""
    if ior.model == "sellmeier":
        row["ior_model"] = IOR_SELLMEIER
        row["ior_coefficients_b"][:3] = ior.coefficients[:3]
        row["ior_coefficients_c"][:3] = ior.coefficients[3:]
    elif ior.model == "cauchy":
        row["ior_model"] = IOR_CAUCHY
        row["ior_coefficients_b"][:2] = ior.coefficients
    else:
        row["ior_model"] = IOR_CONSTANT
        row["ior"] = ior.coefficients[0]


def write_row(row: np.ndarray, material: DielectricMaterial, table: SpectrumTable) -> None:
    write_ior(row, material.ior)
    if material.specular_tint is not None:
        row["reflectance_offset"] = table.add(material.specular_tint)
    row["alpha"] = material.roughness
    row["distribution"] = MICROFACET_DISTRIBUTIONS.index(material.distribution)


def from_mitsuba(importer, bsdf, properties) -> dict | None:
    """Mitsuba's dielectrics have one constant index per side (default bk7 inside, air outside): spectrace's ior
    is their ratio, below 1 when the inside is the rarer medium, 1 (straight through) when they match, as in
    Mitsuba. One tint on both lobes stands for equal specular_reflectance and specular_transmittance."""
    named = importer.NAMED_IOR
    ior = importer.ior(bsdf, properties, "int_ior", named["bk7"]) / importer.ior(
        bsdf, properties, "ext_ior", named["air"]
    )
    if not IOR_RANGE[0] <= ior <= IOR_RANGE[1]:
        raise importer.fail(bsdf, f"int_ior / ext_ior = {ior:.4g}: spectrace's dielectric needs a ratio in {IOR.range}")
    roughness = importer.roughness(bsdf, properties) if importer.kind(bsdf) == "roughdielectric" else 0.0
    if roughness is None:
        return None
    if roughness != 0.0 and abs(ior - 1.0) < ROUGH_IOR_GAP:
        # Mitsuba 3 refuses a roughdielectric of equal indices too.
        raise importer.fail(bsdf, "a roughdielectric with int_ior equal to ext_ior has no refraction")
    tints = {
        key: importer.spectrum(properties[key], key)
        for key in ("specular_reflectance", "specular_transmittance")
        if key in properties
    }
    if None in tints.values():
        return None
    # A tint of exactly 1 is Mitsuba's default, as if it were not written (exporters write it explicitly).
    tints = {key: tint for key, tint in tints.items() if not _is_one(tint)}
    if len(tints) == 1 or (len(tints) == 2 and tints["specular_reflectance"] != tints["specular_transmittance"]):
        importer.unsupported_plugin(bsdf, " with specular_reflectance different from specular_transmittance")
        return None
    table: dict = {"type": "dielectric", "ior": round(ior, 6)}
    if roughness != 0.0:  # a number above 0, or a texture
        table["roughness"] = roughness
        if (kind := importer.distribution(bsdf, properties)) != DEFAULT_DISTRIBUTION:
            table["distribution"] = kind
    if tints:
        table["specular_tint"] = tints["specular_reflectance"]
    return table


def _is_one(tint: dict) -> bool:
    """Whether an imported spectrum is 1 at every wavelength: a number, an rgb (uplifted to exactly 1, as in
    Mitsuba's spectral variants) or a tabulated spectrum; a texture never counts as one."""
    if "value" in tint:
        return float(tint["value"]) == 1.0
    if "rgb" in tint:
        return all(float(c) == 1.0 for c in tint["rgb"])
    if "values" in tint:
        return all(float(pair[1]) == 1.0 for pair in tint["values"])
    return False


def from_pbrt(context, material) -> dict | None:
    return {"type": "dielectric", "ior": context.ior(material)} | context.rough(material)


def to_mitsuba(material: DielectricMaterial, exporter) -> dict:
    """Mitsuba's `dielectric` or `roughdielectric` of the same relative index (int_ior over an ext_ior of 1), α and
    distribution; a tint on both lobes. Mitsuba's dielectrics take one index for every wavelength, so a dispersive
    glass is refused, as is a textured roughness."""
    from spectrace.textures import is_texture

    if material.ior.dispersive:
        raise exporter.refuse(f"a dispersive dielectric ({material.ior.name or 'its index'} varies with wavelength)")
    if is_texture(material.roughness):
        raise exporter.refuse("a dielectric with textured roughness is not exported yet")
    entry: dict = {"int_ior": float(material.ior.at(550.0)), "ext_ior": 1.0}
    if material.specular_tint is not None:
        tint = exporter.spectrum(material.specular_tint)
        entry |= {"specular_reflectance": tint, "specular_transmittance": tint}
    if material.is_delta:
        return {"type": "dielectric"} | entry
    return {
        "type": "roughdielectric",
        "alpha": float(material.roughness),
        "distribution": material.distribution,
    } | entry
