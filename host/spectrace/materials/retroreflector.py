"""`retroreflector`: a GGX lobe about the direction light came from (docs/materials.md,
kernels/bsdf_retroreflector.cl)."""

from dataclasses import dataclass

import numpy as np

from spectrace.core.parameters import reflectance, roughness
from spectrace.materials.opaque import RoughOpaque
from spectrace.spectral.spectrum import Spectrum
from spectrace.spectral.spectrum_input import SpectrumLike
from spectrace.spectral.table import SpectrumTable
from spectrace.textures import number_or_texture, reflectance_or_texture

NAME = "retroreflector"
MITSUBA_PLUGINS = ()
MITSUBA_NONE = "Mitsuba 3 has no retroreflecting BSDF"
PBRT_MATERIALS = ()
PBRT_NONE = "pbrt-v4 has no retroreflecting material"
ROUGHNESS = roughness(0.1, "GGX α: the width of the lobe around the direction light came from")
PARAMETERS = (reflectance(1.0, "how much comes back", textured=True), ROUGHNESS)


@dataclass(frozen=True)
class RetroreflectorMaterial(RoughOpaque):
    """Returns light toward where it came from: a GGX lobe of width `roughness` about the incident direction."""

    reflectance: Spectrum  # or a texture (spectrace.textures)
    roughness: float = ROUGHNESS.number_default  # or a one-channel texture


MODEL = RetroreflectorMaterial


def from_spec(spec, resolver, key: str) -> RetroreflectorMaterial:
    return RetroreflectorMaterial(
        resolver.spectrum_or_texture(spec.reflectance, f"{key}.reflectance", "spectrum"),
        roughness=resolver.number_or_texture(spec.roughness, f"{key}.roughness", ROUGHNESS),
    )


def make(
    reflectance: SpectrumLike = PARAMETERS[0].number_default, roughness: float = ROUGHNESS.number_default
) -> RetroreflectorMaterial:
    """Sends light back toward where it came from (road signs): a GGX lobe of width `roughness` (α) about the
    incident direction, scaled by `reflectance` (each a number or spectrum, or a texture)."""
    return RetroreflectorMaterial(
        reflectance_or_texture(reflectance, "reflectance"),
        roughness=number_or_texture(roughness, ROUGHNESS),
    )


def write_row(row: np.ndarray, material: RetroreflectorMaterial, table: SpectrumTable) -> None:
    row["reflectance_offset"] = table.add(material.reflectance)
    row["alpha"] = material.roughness
