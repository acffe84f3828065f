"""What the materials that only reflect share: their flags, and for those described by one reflectance alone
(diffuse, mirror) the whole host side but the flag is_delta and the API's constructor."""

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from spectrace.materials.base import Material
from spectrace.materials.parameters import SMOOTH_ALPHA
from spectrace.spectral.spectrum import Spectrum
from spectrace.spectral.table import SpectrumTable


class Opaque(Material):
    """Reflects only, with one index for every wavelength."""

    has_transmission = False
    is_dispersive = False


class RoughOpaque(Opaque):
    """A GGX lobe of width `roughness`: delta where it is narrower than the kernels' smooth limit."""

    roughness: float

    @property
    def is_delta(self) -> bool:
        return self.roughness < SMOOTH_ALPHA


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
