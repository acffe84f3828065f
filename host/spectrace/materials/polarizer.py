"""`polarizer`: a linear polariser, a sheet passing light straight through, the field along its axis with
transmittance T(λ) and across it with e·T(λ) (docs/materials.md, kernels/bsdf_polarizer.cl). Unpolarised transport
sees (1 + e)/2 · T; a polarised render (docs/polarization.md) applies its Mueller matrix. What it shares with the
retarder lives in sheet.py."""

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

NAME = "polarizer"
MITSUBA_PLUGINS = ("polarizer",)
PBRT_MATERIALS = ()
PBRT_NONE = "pbrt-v4 does not render polarisation"
ANGLE = axis_parameter("transmission axis", " (Mitsuba 3's polarizer measures its theta the other way: mitsuba_angle)")
TRANSMITTANCE = transmittance_parameter("transmittance along the axis T(λ)")
EXTINCTION = Parameter(
    "extinction",
    "float",
    "dimensionless",
    0.0,
    Range(0.0, 1.0),
    doc="transmittance across the axis over that along it (0: an ideal polariser; 1: a neutral filter)",
)
ABOUT_BEAM = Parameter(
    "angle_about_beam",
    "bool",
    default=False,
    doc="`angle` turns the axis about the beam seen, from the axis normal to the projected dp/dv (Mitsuba 3's "
    "polarizer), instead of within the sheet; the two differ only when the sheet is seen obliquely",
)
PARAMETERS = (ANGLE, TRANSMITTANCE, EXTINCTION, ABOUT_BEAM)


@dataclass(frozen=True)
class PolarizerMaterial(Material):
    """A linear polariser: axis `angle` degrees from dp/du, transmittance T(λ) along it and `extinction`·T across."""

    angle: float = ANGLE.number_default
    transmittance: Spectrum = field(default_factory=lambda: Spectrum.constant(1.0))
    extinction: float = EXTINCTION.number_default
    angle_about_beam: bool = False

    is_delta = True
    has_transmission = True
    is_dispersive = False


MODEL = PolarizerMaterial


from_spec = sheet_from_spec(PolarizerMaterial, PARAMETERS)


def make(
    angle: float = ANGLE.number_default,
    transmittance: SpectrumLike = 1.0,
    extinction: float = EXTINCTION.number_default,
    angle_about_beam: bool = False,
) -> PolarizerMaterial:
    """A linear polariser whose transmission axis lies `angle` degrees from the surface's dp/du toward dp/dv,
    passing T(λ) (`transmittance`, in [0, 1]) along it and `extinction`·T across it (0: ideal);
    `angle_about_beam`: the angle turns the axis about the beam instead (Mitsuba 3's reading)."""
    return make_sheet(
        PolarizerMaterial,
        PARAMETERS,
        angle=angle,
        transmittance=transmittance,
        extinction=extinction,
        angle_about_beam=angle_about_beam,
    )


def write_row(row: np.ndarray, material: PolarizerMaterial, table: SpectrumTable) -> None:
    write_sheet_row(
        row, material.angle, material.extinction, material.transmittance, table, float(material.angle_about_beam)
    )


def mitsuba_angle(theta: float) -> float:
    """The axis angle of Mitsuba 3's polarizer of `theta`: measured, its scalar_spectral_polarized renders of a
    polarizer of theta equal spectrace's of -theta, from either side of the sheet, while the two agree on the
    camera's Stokes basis, on S1..S3 of Fresnel reflections and on its retarder's theta and delta
    (tests/polarization/test_mitsuba_polarized.py). Its own inverse."""
    return 0.0 - theta


def from_mitsuba(importer, bsdf, properties) -> dict | None:
    """Mitsuba 3's polarizer: an ideal linear polariser (extinction 0), theta as mitsuba_angle turns it;
    `polarizing = false` (a plain attenuator) has no counterpart here."""
    if "polarizing" in properties and not importer.boolean(properties["polarizing"]):
        importer.unsupported_plugin(bsdf, " with polarizing = false")
        return None
    sheet = mitsuba_sheet(importer, bsdf, properties, {"type": NAME, "angle_about_beam": True})
    if sheet is not None and "angle" in sheet:
        sheet["angle"] = mitsuba_angle(sheet["angle"])
    return sheet


def to_mitsuba(material: PolarizerMaterial, exporter) -> dict:
    if material.extinction != 0.0:
        raise exporter.refuse(f"a polarizer of extinction {material.extinction:g} (Mitsuba 3's is ideal)")
    return {
        "type": NAME,
        "theta": mitsuba_angle(float(material.angle)),
        "transmittance": exporter.spectrum(material.transmittance),
    }
