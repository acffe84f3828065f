"""`polarizer`: a linear polariser, a sheet passing light straight through, the field along its axis with
transmittance T(λ) and across it with e·T(λ) (docs/materials.md, kernels/bsdf_polarizer.cl). Unpolarised transport
sees (1 + e)/2 · T; a polarised render (docs/polarization.md) applies its Mueller matrix. The keys the retarder
shares (its axis angle, its transmittance) and their Mitsuba mapping live here."""

import math
from dataclasses import dataclass, field

import numpy as np

from spectrace.core.parameters import Parameter, Range, reflectance
from spectrace.materials.base import Material
from spectrace.spectral import spectrum_input
from spectrace.spectral.spectrum import Spectrum
from spectrace.spectral.spectrum_input import SpectrumLike
from spectrace.spectral.table import SpectrumTable

NAME = "polarizer"
MITSUBA_PLUGINS = ("polarizer",)
PBRT_MATERIALS = ()
PBRT_NONE = "pbrt-v4 does not render polarisation"
ANGLE = Parameter(
    "angle",
    "float",
    "degrees",
    0.0,
    Range(-360.0, 360.0),
    doc="of the transmission axis from the surface's dp/du (its u direction) toward dp/dv (Mitsuba 3's polarizer "
    "measures its theta the other way: mitsuba_angle)",
)
TRANSMITTANCE = reflectance(1.0, "transmittance along the axis T(λ)", name="transmittance")
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


def from_spec(spec, resolver, key: str) -> PolarizerMaterial:
    return PolarizerMaterial(
        spec.angle,
        resolver.spectrum(spec.transmittance, f"{key}.transmittance", emission=False),
        spec.extinction,
        bool(spec.angle_about_beam),
    )


def make(
    angle: float = ANGLE.number_default,
    transmittance: SpectrumLike = 1.0,
    extinction: float = EXTINCTION.number_default,
    angle_about_beam: bool = False,
) -> PolarizerMaterial:
    """A linear polariser whose transmission axis lies `angle` degrees from the surface's dp/du toward dp/dv,
    passing T(λ) (`transmittance`, in [0, 1]) along it and `extinction`·T across it (0: ideal);
    `angle_about_beam`: the angle turns the axis about the beam instead (Mitsuba 3's reading)."""
    return PolarizerMaterial(
        ANGLE.check(angle),
        spectrum_input.reflectance(transmittance, "transmittance"),
        EXTINCTION.check(extinction),
        bool(angle_about_beam),
    )


def write_sheet_row(
    row: np.ndarray, angle_degrees: float, second: float, transmittance: Spectrum, table, third: float = 0.0
) -> None:
    """The row of a polarising sheet (kernels/bsdf_polarizer.cl, bsdf_retarder.cl): its axis angle, second number
    (extinction, retardance in radians) and third (the polariser's angle_about_beam) in ior_coefficients_b, its
    transmittance, and a frame along dp/du."""
    row["ior_coefficients_b"] = (math.radians(angle_degrees), second, third, 0.0)
    row["transmittance_offset"] = table.add(transmittance)
    row["tangent_frame"] = 1


def write_row(row: np.ndarray, material: PolarizerMaterial, table: SpectrumTable) -> None:
    write_sheet_row(
        row, material.angle, material.extinction, material.transmittance, table, float(material.angle_about_beam)
    )


def mitsuba_sheet(importer, bsdf, properties, table: dict) -> dict | None:
    """The keys a Mitsuba polarizer and retarder share: theta (degrees, a number) and transmittance."""
    if "theta" in properties:
        theta = importer.resolve(properties["theta"])
        if theta.tag == "texture":
            importer.unsupported_plugin(bsdf, " with a textured theta")
            return None
        angle = importer.number(theta)
        if ANGLE.range_problem(angle):
            raise importer.fail(bsdf, f"theta = {angle:g}: spectrace's {table['type']} needs an angle in {ANGLE.range}")
        table["angle"] = angle
    if "transmittance" in properties:
        if importer.resolve(properties["transmittance"]).tag == "texture":
            importer.unsupported_plugin(bsdf, " with a textured transmittance")
            return None
        tint = importer.spectrum(properties["transmittance"], "transmittance")
        if tint is None:
            return None
        table["transmittance"] = tint
    return table


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
