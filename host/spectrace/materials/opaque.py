"""What the materials that only reflect share: their flags, and for those described by one reflectance alone
(diffuse, mirror) the whole host side but the flag is_delta."""

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from spectrace.materials.parameters import SMOOTH_ALPHA
from spectrace.spectral.spectrum import Spectrum
from spectrace.spectral.table import SpectrumTable


class Opaque:
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

    reflectance: Spectrum


def reflectance_only(model: Callable[[Spectrum], Any]) -> tuple[Callable, Callable, Callable]:
    """`from_spec`, `make` and `write_row` of a material whose one parameter is its reflectance."""

    def from_spec(spec, resolver, key: str):
        return model(resolver.spectrum(spec.reflectance, f"{key}.reflectance", emission=False))

    def make(reflectance: Spectrum):
        return model(reflectance)

    def write_row(row: np.ndarray, material, table: SpectrumTable) -> None:
        row["reflectance_offset"] = table.add(material.reflectance)

    return from_spec, make, write_row
