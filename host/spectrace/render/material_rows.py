"""One Material row (kernels/types.h) per resolved material: its type, parameters and spectrum-table offsets.

Each material class has one function here; adding a BSDF adds one function and one entry in _ROW_WRITERS.
"""

from collections.abc import Callable

import numpy as np

from spectrace.errors import SpectraceError
from spectrace.render.device_types import (
    IOR_CAUCHY,
    IOR_CONSTANT,
    IOR_SELLMEIER,
    MATERIAL_CONDUCTOR,
    MATERIAL_DIELECTRIC,
    MATERIAL_DIFFUSE,
    MATERIAL_DTYPE,
    MATERIAL_MIRROR,
    MATERIAL_NO_SPECTRUM,
    MATERIAL_PLASTIC,
    MATERIAL_RETROREFLECTOR,
)
from spectrace.scene.model import (
    ConductorMaterial,
    DielectricMaterial,
    DiffuseMaterial,
    MirrorMaterial,
    PlasticMaterial,
    RetroreflectorMaterial,
)
from spectrace.spectral.table import SpectrumTable


def _diffuse(row: np.ndarray, material: DiffuseMaterial, table: SpectrumTable) -> None:
    row["type"] = MATERIAL_DIFFUSE
    row["reflectance_offset"] = table.add(material.reflectance)


def _mirror(row: np.ndarray, material: MirrorMaterial, table: SpectrumTable) -> None:
    row["type"] = MATERIAL_MIRROR
    row["reflectance_offset"] = table.add(material.reflectance)


def _conductor(row: np.ndarray, material: ConductorMaterial, table: SpectrumTable) -> None:
    row["type"] = MATERIAL_CONDUCTOR
    row["eta_offset"] = table.add(material.eta)
    row["k_offset"] = table.add(material.k)
    if material.specular_tint is not None:
        row["reflectance_offset"] = table.add(material.specular_tint)
    row["alpha"] = material.roughness


def _plastic(row: np.ndarray, material: PlasticMaterial, table: SpectrumTable) -> None:
    row["type"] = MATERIAL_PLASTIC
    row["reflectance_offset"] = table.add(material.reflectance)
    row["ior_model"] = IOR_CONSTANT
    row["ior"] = material.ior
    row["alpha"] = material.roughness


def _retroreflector(row: np.ndarray, material: RetroreflectorMaterial, table: SpectrumTable) -> None:
    row["type"] = MATERIAL_RETROREFLECTOR
    row["reflectance_offset"] = table.add(material.reflectance)
    row["alpha"] = material.roughness


def _dielectric(row: np.ndarray, material: DielectricMaterial, table: SpectrumTable) -> None:
    row["type"] = MATERIAL_DIELECTRIC
    ior = material.ior
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
    if material.specular_tint is not None:
        row["reflectance_offset"] = table.add(material.specular_tint)
    row["alpha"] = material.roughness


_ROW_WRITERS: dict[type, Callable] = {
    DiffuseMaterial: _diffuse,
    MirrorMaterial: _mirror,
    ConductorMaterial: _conductor,
    PlasticMaterial: _plastic,
    RetroreflectorMaterial: _retroreflector,
    DielectricMaterial: _dielectric,
}


def material_row(material, table: SpectrumTable) -> np.ndarray:
    """The Material row of `material`, adding its spectra to `table`."""
    writer = _ROW_WRITERS.get(type(material))
    if writer is None:
        raise SpectraceError(f"unsupported material {type(material).__name__}")
    row = np.zeros((), MATERIAL_DTYPE)
    row["reflectance_offset"] = row["eta_offset"] = row["k_offset"] = MATERIAL_NO_SPECTRUM
    row["ior"] = 1.0
    writer(row, material, table)
    return row
