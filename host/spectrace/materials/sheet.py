"""What the polarising sheets (polarizer.py, retarder.py) share: each is a sheet passing light straight through, with
an axis at an angle in the surface's frame, a transmittance T(λ) and one number of its own, so their parameter
tables, `from_spec`, the API's checks, their rows and their Mitsuba keys are made here."""

import math
from collections.abc import Callable
from typing import Any

import numpy as np

from spectrace.core.parameters import Parameter, Range, reflectance
from spectrace.spectral import spectrum_input
from spectrace.spectral.spectrum import Spectrum

# Either sense of turning, up to a whole turn.
AXIS_RANGE = Range(-360.0, 360.0)


def axis_parameter(axis: str, mitsuba: str) -> Parameter:
    """The `angle` of the sheet's `axis` (e.g. "transmission axis"), in degrees from dp/du toward dp/dv; `mitsuba`
    says how Mitsuba 3's theta relates to it."""
    return Parameter(
        "angle",
        "float",
        "degrees",
        0.0,
        AXIS_RANGE,
        doc=f"of the {axis} from the surface's dp/du (its u direction) toward dp/dv{mitsuba}",
    )


def transmittance_parameter(doc: str) -> Parameter:
    """The sheet's `transmittance` T(λ), in [0, 1], 1 by default."""
    return reflectance(1.0, doc, name="transmittance")


def sheet_from_spec(model: Callable[..., Any], parameters: tuple[Parameter, ...]) -> Callable[..., Any]:
    """`from_spec` of a sheet whose dataclass `model` takes `parameters` by name: spectra resolved (a bad one named
    by its key), numbers as the schema validated them."""

    def from_spec(spec, resolver, key: str):
        return model(
            **{
                p.name: resolver.spectrum(getattr(spec, p.name), f"{key}.{p.name}", emission=False)
                if p.type == "spectrum"
                else getattr(spec, p.name)
                for p in parameters
            }
        )

    return from_spec


def make_sheet(model: Callable[..., Any], parameters: tuple[Parameter, ...], **values: Any) -> Any:
    """The API's sheet of `model` from `values` by parameter name, each checked (a bad one names its key)."""
    checked: dict[str, Any] = {}
    for p in parameters:
        value = values[p.name]
        if p.type == "spectrum":
            checked[p.name] = spectrum_input.reflectance(value, p.name)
        elif p.type == "bool":
            checked[p.name] = bool(value)
        else:
            checked[p.name] = p.check(value)
    return model(**checked)


def write_sheet_row(
    row: np.ndarray, angle_degrees: float, second: float, transmittance: Spectrum, table, third: float = 0.0
) -> None:
    """The row of a polarising sheet (kernels/bsdf_polarizer.cl, bsdf_retarder.cl): its axis angle, second number
    (extinction, retardance in radians) and third (the polariser's angle_about_beam) in ior_coefficients_b, its
    transmittance, and a frame along dp/du."""
    row["ior_coefficients_b"] = (math.radians(angle_degrees), second, third, 0.0)
    row["transmittance_offset"] = table.add(transmittance)
    row["tangent_frame"] = 1


def mitsuba_sheet(importer, bsdf, properties, table: dict) -> dict | None:
    """The keys a Mitsuba polarizer and retarder share: theta (degrees, a number) and transmittance."""
    if "theta" in properties:
        theta = importer.resolve(properties["theta"])
        if theta.tag == "texture":
            importer.unsupported_plugin(bsdf, " with a textured theta")
            return None
        angle = importer.number(theta)
        if not AXIS_RANGE.contains(angle):
            raise importer.fail(bsdf, f"theta = {angle:g}: spectrace's {table['type']} needs an angle in {AXIS_RANGE}")
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
