"""pbrt-v4's homogeneous and `uniformgrid` media (MakeNamedMedium, inside a shape through MediumInterface) as
spectrace's `interior` tables (a uniformgrid's density as an inline grid, placed by the CTM at MakeNamedMedium),
with their emission: `Le` normalised as a light's spectrum and `Lescale` (a number for a homogeneous medium, a grid
for a uniformgrid), or a uniformgrid's `temperature` grid (blackbody emission, after `temperatureoffset` and
`temperaturescale`)."""

from __future__ import annotations

from pathlib import Path

from spectrace.interop.pbrt.context import Context, unique_name
from spectrace.interop.pbrt.graphics_state import Entity, Shape
from spectrace.interop.pbrt.parser import error, shown


def interior_table(context: Context, shape: Shape) -> dict | None:
    """The spectrace `interior` for the named medium inside a shape (MediumInterface's first name)."""
    if shape.outside_medium:
        context.warn(
            shape.entity.location,
            f"outside medium '{shown(shape.outside_medium)}' not imported (spectrace's media fill closed shapes)",
        )
    name = shape.inside_medium
    if not name:
        return None
    if name not in context.scene.media:
        raise error(shape.entity.location, f"MediumInterface names '{shown(name)}', which no MakeNamedMedium defined")
    if name not in context.interior_of:
        context.interior_of[name] = medium_table(context, context.scene.media[name])
    return context.interior_of[name]


def medium_table(context: Context, medium: Entity) -> dict:
    from spectrace.interop.pbrt.subsurface import preset_name
    from spectrace.spectral.media_presets import medium_presets

    context.read.add(id(medium))
    kind = context.string(medium, "type", "")
    if kind not in ("homogeneous", "uniformgrid", "nanovdb", "cloud"):
        raise error(
            medium.location,
            f"medium '{shown(kind or '')}': spectrace imports homogeneous, uniformgrid, nanovdb and cloud media",
        )
    if kind == "cloud":
        return _cloud(context, medium)
    table: dict = {}
    if kind == "uniformgrid":
        table["density"] = _uniform_grid(context, medium)
    elif kind == "nanovdb" and not context.absent(medium, "filename", "the homogeneous medium"):
        table["density"] = _nanovdb(context, medium)
    if (preset := context.string(medium, "preset")) is not None:
        # pbrt's named media (Jensen et al. 2001, Narasimhan et al. 2006) are the same measurements as spectrace's
        # presets, in 1/mm (pbrt: per scene unit times scale; spectrace: per mm times scale, its millimetres per
        # scene unit: the same numbers).
        if preset_name(preset) not in medium_presets():
            raise error(
                medium.location, f"medium preset '{shown(preset)}' (spectrace has {', '.join(medium_presets())})"
            )
        table["preset"] = preset_name(preset)
    else:
        # pbrt's coefficients default to 1 per scene unit, spectrace's to 0.
        table["sigma_a"] = context.spectrum(medium, "sigma_a", "medium") or {"value": 1.0}
        table["sigma_s"] = context.spectrum(medium, "sigma_s", "medium") or {"value": 1.0}
    scale = context.one(medium, "scale", 1.0)
    if not scale > 0:
        raise error(medium.location, f"a medium's scale must be > 0, got {scale:g}")
    if scale != 1.0:
        table["scale"] = scale
    if (g := context.one(medium, "g", 0.0)) != 0.0:
        table["g"] = g
    if kind == "nanovdb":
        # pbrt-v4's NanoVDB medium glows where it has a temperature grid: Lescale times the normalised black body
        scale = context.one(medium, "Lescale", 1.0)
        if "temperature_file" in table.get("density", {}) and scale > 0.0:
            table["emission"] = {"value": scale}
    else:
        _emission(context, medium, kind, table)
    return table


def _cloud(context: Context, medium: Entity) -> dict:
    """A cloud medium (cloud.py) as a density grid tabulated over its box p0–p1, written beside the TOML; pbrt-v4
    reads no preset, scale or emission for it (left unread, so reported as not imported)."""
    from spectrace.interop.pbrt.cloud import cloud_resolution, finest_frequency, tabulate_cloud

    density = context.one(medium, "density", 1.0)
    wispiness = context.one(medium, "wispiness", 1.0)
    frequency = context.one(medium, "frequency", 5.0)
    p0, p1 = _box(context, medium)
    if any(high <= low for low, high in zip(p0, p1, strict=True)):
        raise error(medium.location, f"a cloud medium's box p0 {p0} – p1 {p1} is empty")
    resolution, capped = cloud_resolution(p0, p1, wispiness, frequency)
    cells = finest_frequency(wispiness, frequency)
    shape = "×".join(map(str, resolution))
    note = ""
    if capped:
        samples = min(n / ((high - low) * cells) for n, low, high in zip(resolution, p0, p1, strict=True))
        note = f": capped, {samples:.2g} samples a cell of its finest noise ({cells:.3g} cells a unit), not 4"
    context.warn(
        medium.location,
        f"cloud medium '{shown(medium.name)}' tabulated as a {shape} density grid (trilinear between samples){note}",
    )
    values = tabulate_cloud(p0, p1, resolution, density, wispiness, frequency)
    name = unique_name(f"cloud_{medium.name}", {Path(n).stem for n in context.files}) + ".vol"
    context.files[name] = values
    matrix = context.world @ context.scene.world_from_medium[medium.name]
    table: dict = {
        "sigma_a": context.spectrum(medium, "sigma_a", "medium") or {"value": 1.0},
        "sigma_s": context.spectrum(medium, "sigma_s", "medium") or {"value": 1.0},
        "density": {
            "file": f"{context.mesh_folder}/{name}",
            "box": [p0, p1],
            "transform": [{"matrix": matrix.tolist()}],
        },
    }
    if (g := context.one(medium, "g", 0.0)) != 0.0:
        table["g"] = g
    return table


def _nanovdb(context: Context, medium: Entity) -> dict:
    """A nanovdb medium's grids (its `gridname`, default density, and `temperaturename`, default temperature, when
    the file has it) read from its file, placed by the grid's own map and the CTM at MakeNamedMedium."""
    from spectrace.geometry.nanovdb import nanovdb_grid, read_nanovdb

    path = context.file_path(medium, "filename")
    if path is None:
        raise error(medium.location, 'a nanovdb medium needs "string filename"')
    grid = context.string(medium, "gridname", "density") or "density"
    temperature = context.string(medium, "temperaturename", "temperature") or "temperature"
    grids = read_nanovdb(path, where=str(medium.location))
    nanovdb_grid(path, grid, where=str(medium.location))  # the density grid is there (or the file's only one)
    matrix = context.world @ context.scene.world_from_medium[medium.name]
    table: dict = {"file": context.relative(path), "transform": [{"matrix": matrix.tolist()}]}
    if grid != "density":
        table["grid"] = grid
    offset = context.one(medium, "temperatureoffset", context.one(medium, "temperaturecutoff", 0.0))
    scale = context.one(medium, "temperaturescale", 1.0)
    if temperature in grids:
        if temperature != "temperature":
            raise error(medium.location, f"temperaturename '{shown(temperature)}': spectrace reads 'temperature'")
        table["temperature_file"] = table["file"]
        if offset != 0.0:
            table["temperature_offset"] = offset
        if scale != 1.0:
            table["temperature_scale"] = scale
    return table


def _emission(context: Context, medium: Entity, kind: str, table: dict) -> None:
    """pbrt-v4's medium emission into `table`: Le (an illuminant spectrum divided by its photometric integral, as a
    light's) times Lescale, a number for a homogeneous medium and a grid of nx·ny·nz values for a uniformgrid; or a
    uniformgrid's temperature grid, (T − temperatureoffset) · temperaturescale kelvin of normalised blackbody
    emission (times its Lescale grid). A zero Le glows nowhere, as in pbrt."""
    le = medium.find("Le", "rgb", "spectrum", "blackbody", "float")
    temperature = context.floats(medium, "temperature") if kind == "uniformgrid" else None
    if le is not None and temperature is not None:
        raise error(medium.location, 'a medium takes "Le" or "temperature", not both (as in pbrt-v4)')
    zero = le is not None and le.type in ("rgb", "float") and not any(float(v) for v in le.values)
    glows = temperature is not None or (le is not None and not zero)
    if kind != "uniformgrid":
        scale = context.one(medium, "Lescale", 1.0)
        if glows:
            table["emission"] = context.emission(medium, "Le", scale)
        return
    count = len(table["density"]["values"])
    grids = {"Lescale": context.floats(medium, "Lescale"), "temperature": temperature}
    for name, values in grids.items():
        if values is not None and len(values) != count:
            parameter = medium.find(name)
            raise error(
                parameter.location if parameter else medium.location,
                f'"float {name}" has {len(values)} values; nx·ny·nz = {count}',
            )
    offset = context.one(medium, "temperatureoffset", context.one(medium, "temperaturecutoff", 0.0))
    temperature_scale = context.one(medium, "temperaturescale", 1.0)
    if not glows:
        return
    if temperature is not None:
        table["density"]["temperature_values"] = [(t - offset) * temperature_scale for t in temperature]
    else:
        table["emission"] = context.emission(medium, "Le", 1.0)
    if grids["Lescale"] is not None:
        table["density"]["emission_values"] = grids["Lescale"]


def _box(context: Context, medium: Entity) -> tuple[list[float], list[float]]:
    """A grid medium's box, p0 to p1 (default the unit cube), as pbrt-v4 takes two corners: their smallest and
    largest coordinates, whichever corner holds them (so a box given from its far corner is not mirrored)."""
    p0 = context.vector(medium, "p0", [0.0, 0.0, 0.0])
    p1 = context.vector(medium, "p1", [1.0, 1.0, 1.0])
    return [min(a, b) for a, b in zip(p0, p1, strict=True)], [max(a, b) for a, b in zip(p0, p1, strict=True)]


def _uniform_grid(context: Context, medium: Entity) -> dict:
    """A uniformgrid's `density` (nx·ny·nz values, x fastest) over the box p0–p1 of the medium's space, as
    spectrace's inline grid; the CTM at MakeNamedMedium places it. pbrt-v4 fades the density to 0 over the
    outermost half voxel, spectrace holds the face's value there (docs/media.md)."""
    resolution = [context.integer(medium, axis, 1, low=1) for axis in ("nx", "ny", "nz")]
    density = context.floats(medium, "density")
    if density is None:
        raise error(
            medium.location, 'a uniformgrid medium needs "float density" (spectrace imports no temperature grid)'
        )
    count = resolution[0] * resolution[1] * resolution[2]
    if len(density) != count:
        parameter = medium.find("density")
        raise error(
            parameter.location if parameter else medium.location,
            f'"float density" has {len(density)} values; nx·ny·nz = {count}',
        )
    p0, p1 = _box(context, medium)
    matrix = context.world @ context.scene.world_from_medium[medium.name]
    return {
        "values": density,
        "resolution": resolution,
        "box": [p0, p1],
        "transform": [{"matrix": matrix.tolist()}],
    }
