"""Media: a shape's interior homogeneous medium (constant or rgb sigma_t and albedo, `scale`, an hg or isotropic
phase) as spectrace's interior; with a null bsdf the shape is the medium's index-matched boundary (shapes.py)."""

from __future__ import annotations

import numpy as np

from spectrace.interop.mitsuba.context import ImportContext, Properties
from spectrace.interop.mitsuba.textures import spectrum
from spectrace.interop.mitsuba.tree import Element


def interior_medium(ctx: ImportContext, properties: Properties) -> dict | None:
    """A shape's `interior` homogeneous medium as spectrace's interior: σs = scale·albedo·σt and
    σa = scale·(1 − albedo)·σt (Mitsuba 3's homogeneous: albedo default 0.75, sigma_t default 1), with its
    Henyey–Greenstein phase (Mitsuba's hg: g default 0.8; isotropic: 0). A constant or rgb sigma_t and a
    constant or rgb albedo, written in place or in a constvolume, are mapped; other coloured coefficients are
    reported."""
    ctx.nested(properties, "medium")  # read here, whatever their names
    if "exterior" in properties:
        ctx.unsupported_plugin(ctx.resolve(properties["exterior"]), " as an exterior medium")
    if "interior" not in properties:
        return None
    medium = ctx.resolve(properties["interior"])
    if ctx.kind(medium) != "homogeneous":
        ctx.unsupported_object(medium)
        return None
    items = ctx.properties(medium)
    items.understood("sample_emitters")  # how Mitsuba samples, not what it renders
    given: dict = {}
    for key, default in (("sigma_t", 1.0), ("albedo", 0.75)):
        value: dict | None = _coefficient(ctx, items[key], key) if key in items else {"value": default}
        # An rgb albedo or sigma_t is uplifted as Mitsuba's spectral variants uplift a reflectance (they refuse
        # an rgb sigma_t outside [0, 1], and so does spectrace); `scale` then multiplies sigma_t.
        if value is None:  # recorded where it was read
            return None
        if set(value) not in ({"value"}, {"rgb"}):
            ctx.unsupported_plugin(medium, f" with a coloured {key}")
            return None
        if "rgb" in value and not all(0.0 <= c <= 1.0 for c in value["rgb"]):
            raise ctx.fail(
                items[key],
                f"a medium's rgb {key} must lie in [0, 1] (as Mitsuba's spectral variants require), got {value['rgb']}",
                "value",
            )
        given[key] = value
    albedo = given["albedo"].get("value", 0.0)
    if albedo > 1.0:
        raise ctx.fail(items["albedo"], f"a medium's albedo must not exceed 1, got {albedo:g}", "value")
    scale = ctx.number(items["scale"]) if "scale" in items else 1.0
    if not scale > 0.0:
        raise ctx.fail(items["scale"], f"a medium's scale must be > 0, got {scale:g}", "value")
    g = 0.0
    phase = next(iter(ctx.nested(items, "phase")), None)
    if phase is not None and ctx.kind(phase) == "hg":
        phase_items = ctx.properties(phase)
        g = ctx.number(phase_items["g"]) if "g" in phase_items else 0.8
    elif phase is not None and ctx.kind(phase) != "isotropic":
        ctx.unsupported_object(phase)
        return None
    if "rgb" in given["albedo"] or "rgb" in given["sigma_t"]:
        return {**_coloured_coefficients(ctx, given["sigma_t"], given["albedo"], scale, medium), "g": g}
    sigma_t = float(given["sigma_t"]["value"]) * scale
    return {"sigma_a": {"value": sigma_t * (1.0 - albedo)}, "sigma_s": {"value": sigma_t * albedo}, "g": g}


def _coefficient(ctx: ImportContext, element: Element, key: str) -> dict | None:
    """A homogeneous medium's sigma_t or albedo: a spectrum written in place, or a `constvolume` holding one (its
    `value`, Mitsuba's default 1), which is what Mitsuba makes of the spectrum written in place; its to_world moves
    nothing that is constant. A volume that varies in space (gridvolume) is recorded as unsupported."""
    resolved = ctx.resolve(element)
    if resolved.tag != "volume":
        return spectrum(ctx, element, key)
    if ctx.kind(resolved) != "constvolume":
        ctx.unsupported_plugin(resolved, f" as a medium's {key} (spectrace's media are homogeneous: constvolume only)")
        return None
    items = ctx.properties(resolved)
    items.understood("to_world")
    return spectrum(ctx, items["value"], key) if "value" in items else {"value": 1.0}


def _coloured_coefficients(ctx: ImportContext, sigma_t: dict, albedo: dict, scale: float, medium: Element) -> dict:
    """σs = σt(λ)·a(λ), σa = σt(λ)·(1 − a(λ)) with σt = scale · sigma_t, each of sigma_t and the albedo a number
    or an rgb in [0, 1] uplifted as Mitsuba uplifts a reflectance (Jakob & Hanika 2019; measured: Mitsuba 3's
    homogeneous medium gives the same σt(λ) and σs(λ) within 0.1 %), tabulated every 5 nm (smooth curves)."""
    from spectrace.spectral.grid import GRID_MAX_NM, GRID_MIN_NM
    from spectrace.spectral.uplift import uplift_reflectance

    wavelengths = np.arange(GRID_MIN_NM, GRID_MAX_NM + 0.5, 5.0)

    def tabulated(value: dict) -> np.ndarray:
        if "value" in value:
            return np.full(len(wavelengths), float(value["value"]))
        spectrum = uplift_reflectance(value["rgb"], where=ctx.where(medium))[0]
        return np.array([float(spectrum.evaluate(w)) for w in wavelengths])

    extinction, albedo_values = scale * tabulated(sigma_t), tabulated(albedo)
    return {
        "sigma_a": {"values": [[float(w), t * (1.0 - a)] for w, t, a in zip(wavelengths, extinction, albedo_values)]},
        "sigma_s": {"values": [[float(w), t * a] for w, t, a in zip(wavelengths, extinction, albedo_values)]},
    }
