"""`retarder`: a linear retarder (a wave plate), a sheet passing light straight through with transmittance T(λ),
delaying the field across its fast axis by the retardance (docs/materials.md, kernels/bsdf_retarder.cl).
Unpolarised transport sees T; a polarised render (docs/polarization.md) applies its Mueller matrix."""

import math
from dataclasses import dataclass, field

import numpy as np

from spectrace.core.parameters import Parameter, Range
from spectrace.materials.base import Material
from spectrace.materials.sheet import (
    axis_parameter,
    make_sheet,
    mitsuba_sheet,
    sheet_from_spec,
    transmittance_parameter,
    write_sheet_row,
)
from spectrace.spectral.spectrum import Spectrum
from spectrace.spectral.spectrum_input import SpectrumLike
from spectrace.spectral.table import SpectrumTable

NAME = "retarder"
MITSUBA_PLUGINS = ("retarder",)
PBRT_MATERIALS = ()
PBRT_NONE = "pbrt-v4 does not render polarisation"
FAST_AXIS = axis_parameter("fast axis", ", as Mitsuba 3's retarder measures its theta")
RETARDANCE = Parameter(
    "retardance",
    "float",
    "degrees",
    90.0,
    Range(-360.0, 360.0),
    doc="phase delay of the field across the fast axis (90: a quarter-wave plate, 180: a half-wave plate), as "
    "Mitsuba 3's delta",
)
TRANSMITTANCE = transmittance_parameter("transmittance T(λ)")
PARAMETERS = (FAST_AXIS, RETARDANCE, TRANSMITTANCE)


@dataclass(frozen=True)
class RetarderMaterial(Material):
    """A linear retarder: fast axis `angle` degrees from dp/du, `retardance` degrees, transmittance T(λ)."""

    angle: float = FAST_AXIS.number_default
    retardance: float = RETARDANCE.number_default
    transmittance: Spectrum = field(default_factory=lambda: Spectrum.constant(1.0))

    is_delta = True
    has_transmission = True
    is_dispersive = False


MODEL = RetarderMaterial


from_spec = sheet_from_spec(RetarderMaterial, PARAMETERS)


def make(
    angle: float = FAST_AXIS.number_default,
    retardance: float = RETARDANCE.number_default,
    transmittance: SpectrumLike = 1.0,
) -> RetarderMaterial:
    """A linear retarder whose fast axis lies `angle` degrees from the surface's dp/du toward dp/dv, delaying the
    field across it by `retardance` degrees (90: a quarter-wave plate), passing T(λ) (`transmittance`)."""
    return make_sheet(RetarderMaterial, PARAMETERS, angle=angle, retardance=retardance, transmittance=transmittance)


def write_row(row: np.ndarray, material: RetarderMaterial, table: SpectrumTable) -> None:
    write_sheet_row(row, material.angle, math.radians(material.retardance), material.transmittance, table)


def from_mitsuba(importer, bsdf, properties) -> dict | None:
    """Mitsuba 3's retarder: delta in degrees (90 by default), theta, its transmittance, all as spectrace's
    (measured with its scalar_spectral_polarized variant: tests/polarization/test_mitsuba_polarized.py)."""
    table: dict = {"type": NAME}
    if "delta" in properties:
        delta = importer.resolve(properties["delta"])
        if delta.tag == "texture":
            importer.unsupported_plugin(bsdf, " with a textured delta")
            return None
        retardance = importer.number(delta)
        if RETARDANCE.range_problem(retardance):
            raise importer.fail(bsdf, f"delta = {retardance:g}: spectrace's retarder needs {RETARDANCE.range} degrees")
        table["retardance"] = retardance
    return mitsuba_sheet(importer, bsdf, properties, table)


def to_mitsuba(material: RetarderMaterial, exporter) -> dict:
    return {
        "type": NAME,
        "theta": float(material.angle),
        "delta": float(material.retardance),
        "transmittance": exporter.spectrum(material.transmittance),
    }
