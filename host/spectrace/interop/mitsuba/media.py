"""Media: a shape's interior homogeneous medium (constant or rgb sigma_t and albedo, `scale`, an hg or isotropic
phase) as spectrace's interior, its albedo also a `gridvolume` (a grid of density 1 that fills all space, clamped
or repeated as the volume's wrap_mode), and a heterogeneous one whose sigma_t (one channel, or three: a colour
uplifted per voxel) and albedo are `gridvolume`s as a density grid; with a null bsdf the shape is the medium's
index-matched boundary (shapes.py)."""

from __future__ import annotations

import numpy as np

from spectrace.interop.mitsuba.context import ImportContext, Properties
from spectrace.interop.mitsuba.textures import spectrum
from spectrace.interop.mitsuba.transforms import to_world
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
    if ctx.kind(medium) not in ("homogeneous", "heterogeneous"):
        ctx.unsupported_object(medium)
        return None
    items = ctx.properties(medium)
    # How Mitsuba samples, not what it renders (has_spectral_extinction: whether its majorant may vary with λ).
    items.understood("sample_emitters", "sample_emitted", "has_spectral_extinction")
    homogeneous = ctx.kind(medium) == "homogeneous"
    grids: dict[str, dict] = {}
    for key in ("albedo",) if homogeneous else ("sigma_t", "albedo"):
        volume = ctx.resolve(items[key]) if key in items else None
        if volume is not None and volume.tag == "volume" and ctx.kind(volume) == "gridvolume":
            grid = _grid_volume(ctx, volume, key, fills_space=homogeneous)
            if grid is None:
                return None
            grids[key] = grid
    given: dict = {}
    for key, default in (("sigma_t", 1.0), ("albedo", 0.75)):
        value: dict | None = {"value": 1.0} if key in grids else None
        if value is None:
            value = _coefficient(ctx, items[key], key) if key in items else {"value": default}
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
    density = grids["albedo"] if homogeneous and grids else _density_table(ctx, grids, medium)
    if density is None and grids:
        return None
    if ctx.kind(medium) == "heterogeneous" and not grids:
        density = _constant_box(ctx, ctx.resolve(items["sigma_t"]) if "sigma_t" in items else None)
    extra = {"density": density} if density is not None else {}
    if "rgb" in given["albedo"] or "rgb" in given["sigma_t"]:
        return {**_coloured_coefficients(ctx, given["sigma_t"], given["albedo"], scale, medium), "g": g, **extra}
    sigma_t = float(given["sigma_t"]["value"]) * scale
    return {"sigma_a": {"value": sigma_t * (1.0 - albedo)}, "sigma_s": {"value": sigma_t * albedo}, "g": g, **extra}


def _grid_volume(ctx: ImportContext, volume: Element, key: str, fills_space: bool = False) -> dict | None:
    """A `gridvolume` as spectrace's grid keys: its file, and its to_world (after the file's own box when
    use_grid_bbox is set, else the unit box, as Mitsuba 3 places it). One channel or three (an RGB grid uplifted
    per voxel), trilinear. A heterogeneous medium ends at its sigma_t volume's box, whose lookups are clamped; a
    homogeneous medium's albedo volume (`fills_space`) is looked up everywhere, clamped or repeated as its
    wrap_mode says (`outside`)."""
    from spectrace.geometry.grid_volume import read_vol

    items = ctx.properties(volume)
    items.understood("raw", "accel")  # raw: whether colour data is uplifted, which one channel has none of
    if "filter_type" in items and ctx.choice(items["filter_type"], ("trilinear", "nearest")) != "trilinear":
        ctx.unsupported_plugin(volume, " with filter_type nearest")
        return None
    wrap = ctx.choice(items["wrap_mode"], ("clamp", "repeat", "mirror")) if "wrap_mode" in items else "clamp"
    if wrap == "mirror" or (wrap != "clamp" and not fills_space):
        where = "" if fills_space else " in a heterogeneous medium"
        ctx.unsupported_plugin(volume, f" with wrap_mode {wrap}{where}")
        return None
    filename = ctx.child(items, "filename", volume)
    file = ctx.input_file(filename, "volume file")
    values, p0, p1 = read_vol(ctx.find_file(filename, ctx.required(filename, "value")), where=ctx.where(filename))
    if values.shape[3] not in (1, 3):
        ctx.unsupported_plugin(volume, f" with {values.shape[3]} channels as a medium's {key} (one or three)")
        return None
    if values.shape[3] == 3 and "raw" in items and ctx.boolean(items["raw"]):
        ctx.unsupported_plugin(volume, " with raw colour data (Mitsuba 3 evaluates only uplifted colour as spectra)")
        return None
    table: dict = {"albedo_file": file, "outside": wrap} if fills_space else {"file": file}
    if "use_grid_bbox" in items and ctx.boolean(items["use_grid_bbox"]):
        table["box"] = [[float(v) for v in p0], [float(v) for v in p1]]
    matrix = to_world(ctx, items)
    if not np.array_equal(matrix, np.eye(4)):
        table["transform"] = [{"matrix": matrix.tolist()}]
    return table


def _constant_box(ctx: ImportContext, volume: Element | None) -> dict:
    """A heterogeneous medium of constant sigma_t fills only its volume's box (Mitsuba 3 bounds the medium by
    sigma_t's bounding box: a constvolume's unit box moved by its to_world; a spectrum written in place, the unit
    box): a grid of one voxel of density 1 there."""
    table: dict = {"values": [1.0], "resolution": [1, 1, 1]}
    if volume is not None and volume.tag == "volume":
        matrix = to_world(ctx, ctx.properties(volume))
        if not np.array_equal(matrix, np.eye(4)):
            table["transform"] = [{"matrix": matrix.tolist()}]
    return table


def _density_table(ctx: ImportContext, grids: dict[str, dict], medium: Element) -> dict | None:
    """spectrace's `density` from a heterogeneous medium's grids: sigma_t's grid is the density, albedo's the
    albedo grid, which needs sigma_t's grid in the same place."""
    if not grids:
        return None
    if "sigma_t" not in grids:
        ctx.unsupported_plugin(medium, " with an albedo grid but a constant sigma_t")
        return None
    density = dict(grids["sigma_t"])
    if "albedo" in grids:
        albedo = grids["albedo"]
        if {k: v for k, v in albedo.items() if k != "file"} != {k: v for k, v in density.items() if k != "file"}:
            ctx.unsupported_plugin(medium, " whose albedo grid is placed unlike its sigma_t grid")
            return None
        density["albedo_file"] = albedo["file"]  # sigma_t's is a file too: a constant one makes no albedo grid
    return density


def _coefficient(ctx: ImportContext, element: Element, key: str) -> dict | None:
    """A homogeneous medium's sigma_t or albedo: a spectrum written in place, or a `constvolume` holding one (its
    `value`, Mitsuba's default 1), which is what Mitsuba makes of the spectrum written in place; its to_world moves
    nothing that is constant. A volume that varies in space (gridvolume) is recorded as unsupported."""
    resolved = ctx.resolve(element)
    if resolved.tag != "volume":
        return spectrum(ctx, element, key)
    if ctx.kind(resolved) != "constvolume":
        ctx.unsupported_plugin(
            resolved, f" as a homogeneous medium's {key} (constvolume only; a heterogeneous medium takes a gridvolume)"
        )
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
