"""`plastic`: a diffuse base under a clear dielectric coat, smooth or GGX-rough (docs/materials.md,
kernels/bsdf_plastic.cl)."""

from dataclasses import dataclass

import numpy as np

from spectrace.materials.parameters import REQUIRED, Parameter, Range, reflectance, roughness
from spectrace.render.device_types import IOR_CONSTANT, MATERIAL_PLASTIC
from spectrace.spectral.spectrum import Spectrum
from spectrace.spectral.table import SpectrumTable

NAME = "plastic"
# Above 4 the coat's hemispherical Fresnel average leaves the range its quadrature is exact for (docs/materials.md).
IOR = Parameter("ior", "float", "dimensionless", default=1.5, range=Range(1.0, 4.0, low_open=True),
                doc="index of refraction of the clear coat relative to the outside")
ROUGHNESS = roughness(0.0, "GGX α of the coat")
PARAMETERS = (reflectance(REQUIRED, "albedo of the diffuse base under the coat"), IOR, ROUGHNESS)


@dataclass(frozen=True)
class PlasticMaterial:
    """Diffuse base of albedo `reflectance` under a clear coat of index `ior` relative to the outside."""

    reflectance: Spectrum
    ior: float = IOR.default
    roughness: float = ROUGHNESS.default

    is_delta = False  # the base is diffuse whatever the coat
    has_transmission = False
    is_dispersive = False


MODEL = PlasticMaterial


def from_spec(spec, resolver, key: str) -> PlasticMaterial:
    return PlasticMaterial(resolver.spectrum(spec.reflectance, f"{key}.reflectance", emission=False), ior=spec.ior,
                           roughness=spec.roughness)


def make(reflectance: Spectrum, ior: float = IOR.default, roughness: float = ROUGHNESS.default) -> PlasticMaterial:
    return PlasticMaterial(reflectance, ior=IOR.check(ior), roughness=ROUGHNESS.check(roughness))


def write_row(row: np.ndarray, material: PlasticMaterial, table: SpectrumTable) -> None:
    row["type"] = MATERIAL_PLASTIC
    row["reflectance_offset"] = table.add(material.reflectance)
    row["ior_model"] = IOR_CONSTANT
    row["ior"] = material.ior
    row["alpha"] = material.roughness
