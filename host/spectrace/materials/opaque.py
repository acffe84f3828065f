"""What the materials that only reflect share: their flags, and for those described by one reflectance alone
(diffuse, mirror) the whole host side but the flag is_delta and the API's constructor."""

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from spectrace.core.parameters import SMOOTH_ALPHA
from spectrace.materials.base import Material
from spectrace.spectral.spectrum import Spectrum
from spectrace.spectral.table import SpectrumTable


class Opaque(Material):
    """Reflects only, with one index for every wavelength."""

    has_transmission = False
    is_dispersive = False


def smooth_everywhere(roughness) -> bool:
    """A GGX lobe of width `roughness` (a number or a one-channel texture) is a delta lobe at every point: its
    largest α is below the kernels' smooth limit (kernels/microfacet.cl, ggx_lobe_flags)."""
    from spectrace.textures import scalar_range

    return scalar_range(roughness)[1] < SMOOTH_ALPHA


class RoughOpaque(Opaque):
    """A GGX lobe of width `roughness` (a number or a texture): delta where it is narrower than the kernels' smooth
    limit; only delta lobes when it is that narrow everywhere."""

    roughness: float

    @property
    def is_delta(self) -> bool:
        return smooth_everywhere(self.roughness)


@dataclass(frozen=True)
class ReflectanceOnly(Opaque):
    """A material described by its reflectance R(λ) alone; a subclass states is_delta."""

    reflectance: Spectrum  # or, where the parameter table says textured, a texture (spectrace.textures)


def reflectance_only(model: Callable[[Spectrum], Any]) -> tuple[Callable, Callable]:
    """`from_spec` and `write_row` of a material whose one parameter is its reflectance."""

    def from_spec(spec, resolver, key: str):
        return model(resolver.spectrum_or_texture(spec.reflectance, f"{key}.reflectance", "spectrum"))

    def write_row(row: np.ndarray, material, table: SpectrumTable) -> None:
        row["reflectance_offset"] = table.add(material.reflectance)

    return from_spec, write_row
