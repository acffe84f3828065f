"""`diffuse`: Lambertian reflection, f = R(λ)/π, on both faces (docs/materials.md, kernels/bsdf_diffuse.cl)."""

from dataclasses import dataclass

import numpy as np

from spectrace.engine.device_types import MATERIAL_DIFFUSE
from spectrace.materials.parameters import REQUIRED, reflectance
from spectrace.spectral.spectrum import Spectrum
from spectrace.spectral.table import SpectrumTable

NAME = "diffuse"
MITSUBA_PLUGINS = ("diffuse",)
PARAMETERS = (reflectance(REQUIRED, "Lambertian reflection f = R(λ)/π"),)


@dataclass(frozen=True)
class DiffuseMaterial:
    """Lambertian, f = R(λ)/π, reflecting on both faces."""

    reflectance: Spectrum

    is_delta = False
    has_transmission = False
    is_dispersive = False


MODEL = DiffuseMaterial


def from_spec(spec, resolver, key: str) -> DiffuseMaterial:
    return DiffuseMaterial(resolver.spectrum(spec.reflectance, f"{key}.reflectance", emission=False))


def make(reflectance: Spectrum) -> DiffuseMaterial:
    return DiffuseMaterial(reflectance)


def write_row(row: np.ndarray, material: DiffuseMaterial, table: SpectrumTable) -> None:
    row["type"] = MATERIAL_DIFFUSE
    row["reflectance_offset"] = table.add(material.reflectance)


def from_mitsuba(importer, bsdf, properties) -> dict | None:
    reflectance = properties.get("reflectance")
    spectrum = importer.spectrum(reflectance, "reflectance") if reflectance is not None else {"value": 0.5}
    return None if spectrum is None else {"type": "diffuse", "reflectance": spectrum}


def to_mitsuba(material: DiffuseMaterial, exporter) -> dict:
    # Mitsuba's diffuse is black from behind; spectrace's reflects on both faces.
    return {"type": "twosided", "bsdf": {"type": "diffuse", "reflectance": exporter.spectrum(material.reflectance)}}
