"""`mirror`: perfect specular reflection of reflectance R(λ) (docs/materials.md, kernels/bsdf_mirror.cl)."""

from dataclasses import dataclass

import numpy as np

from spectrace.engine.device_types import MATERIAL_MIRROR
from spectrace.materials.parameters import reflectance
from spectrace.spectral.spectrum import Spectrum
from spectrace.spectral.table import SpectrumTable

NAME = "mirror"
MITSUBA_PLUGINS = ()
MITSUBA_NONE = 'Mitsuba 3\'s mirror is a conductor of material "none", which conductor.py imports as a mirror'
PARAMETERS = (reflectance(1.0, "perfect specular reflection scaled by R(λ)"),)


@dataclass(frozen=True)
class MirrorMaterial:
    """Perfect specular reflection of reflectance R(λ)."""

    reflectance: Spectrum

    is_delta = True
    has_transmission = False
    is_dispersive = False


MODEL = MirrorMaterial


def from_spec(spec, resolver, key: str) -> MirrorMaterial:
    return MirrorMaterial(resolver.spectrum(spec.reflectance, f"{key}.reflectance", emission=False))


def make(reflectance: Spectrum) -> MirrorMaterial:
    return MirrorMaterial(reflectance)


def write_row(row: np.ndarray, material: MirrorMaterial, table: SpectrumTable) -> None:
    row["type"] = MATERIAL_MIRROR
    row["reflectance_offset"] = table.add(material.reflectance)
