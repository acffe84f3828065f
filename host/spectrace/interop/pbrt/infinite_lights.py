"""Several pbrt-v4 `infinite` lights as spectrace's one environment, and pbrt-v4's portals.

pbrt adds its lights, so several infinite lights are one environment whose radiance is their sum. spectrace takes
one environment light: the kernels keep one environment row and one map's sampling tables, and a ray that leaves the
scene is charged that one light's radiance and pdf. Taking several would change the escape path, the MIS pdf and the
light tracer's emission in every integrator for an import-side need, so the importer sums them instead: constants
(the same spectrum up to its scale, or sampled on the wavelength grid) stay a constant light; with an image among
them every light is resampled onto one latitude-longitude grid in spectrace's world (the finest of their
resolutions) and added there.

A portal (pbrt-v4's PortalImageInfiniteLight, lights.h/.cpp) changes the radiance, not only the sampling:
`ImageFromRender` gives no radiance for a direction w with w·n ≤ 0 in the portal's frame (n = (p3 − p0) × (p1 − p0),
the frame's z), and `Le` none for a ray whose direction from its origin misses the portal's rectangle. The portal's
points are world-space (pbrt ignores the light's transform for them); its image is the light's map, turned by the
light's transform as without a portal. An environment light cannot depend on where the ray starts, so the import
keeps the direction test: each portal light's map is zero on the side w·n ≤ 0, which is pbrt's radiance for every
ray that leaves the scene through the portal. Portal lights of the same map and scale are one light whose mask is
the union of their sides: a ray leaving the scene crosses one of several disjoint portals, so pbrt gives it the
map once, where the sum of the masks would count it twice where the sides overlap. Sampling does not use the portal.
"""

from __future__ import annotations

import math

import numpy as np

from spectrace.interop.pbrt.context import Context, unique_name
from spectrace.interop.pbrt.envmap import latitude_longitude_directions, to_latitude_longitude
from spectrace.interop.pbrt.graphics_state import Light
from spectrace.interop.pbrt.parser import error
from spectrace.spectral.colorimetry import XYZ_TO_LINEAR_SRGB, spectrum_to_xyz
from spectrace.spectral.grid import GRID_NM

ENVIRONMENTS = ("constant", "envmap")
# Rows of the map a portal's mask is drawn on when no image light sets the grid (a constant light with a portal):
# the mask's edge is then within half a degree.
PORTAL_ROWS = 256
MAX_ROWS = 2048  # the largest map the importer writes (envmap.py's resampling bound)


def portal_normal(context: Context, light: Light) -> np.ndarray | None:
    """The unit normal, in spectrace's world, of the side a portal light shines from (pbrt's portal frame's z,
    (p3 − p0) × (p1 − p0) of its world-space points), or None without a portal."""
    entity = light.entity
    values = context.floats(entity, "portal", None, "point3", "point")
    if values is None:
        return None
    if len(values) != 12:
        raise error(entity.location, f'"portal" takes 4 points, got {len(values) / 3:g}')
    corners = np.asarray(values, np.float64).reshape(4, 3)
    normal = np.cross(corners[3] - corners[0], corners[1] - corners[0])
    if not np.linalg.norm(normal) > 0:
        raise error(entity.location, '"portal" is degenerate: its first three points lie on a line')
    # A direction d in spectrace's world is W⁻¹ d in pbrt's, so the test (W⁻¹ d)·n is d·(W⁻ᵀ n).
    normal = np.linalg.inv(context.world[:3, :3]).T @ normal
    return normal / np.linalg.norm(normal)


def _spectrum_values(table: dict) -> np.ndarray:
    """A spectrace spectrum table (context.emission's forms) on the 1 nm grid, its scale applied."""
    from spectrace.spectral import library_spectrum, parse_inline_spectrum
    from spectrace.spectral.blackbody import blackbody
    from spectrace.spectral.uplift import uplift_illuminant

    if "blackbody" in table:
        values = blackbody(float(table["blackbody"])).values
    elif "spectrum" in table:
        values = library_spectrum(table["spectrum"]).values
    elif "values" in table:
        values = parse_inline_spectrum(table["values"], where="spectrum").values
    elif "rgb" in table:
        values = uplift_illuminant(table["rgb"]).values
    else:
        values = np.full(GRID_NM.shape, float(table["value"]))
    return np.asarray(values, np.float64) * float(table.get("scale", 1.0))


def _constant_rgb(table: dict) -> tuple[np.ndarray, bool]:
    """A constant light's radiance as an envmap texel (linear sRGB, (1, 1, 1) = D65 at Y = 1), and whether that is
    the light itself: an RGB one is (the map's texels are RGB illuminants too), a spectrum keeps its colour only."""
    radiance = table["radiance"]
    if "rgb" in radiance:
        return np.asarray(radiance["rgb"], np.float64) * float(radiance.get("scale", 1.0)), True
    return XYZ_TO_LINEAR_SRGB @ spectrum_to_xyz(_spectrum_values(radiance)), radiance.get("spectrum") == "cie:D65"


def _sum_constants(tables: list[dict]) -> tuple[dict, bool]:
    """One constant light of the summed radiance, and whether it is a sum of scales (one spectrum) rather than a
    sampled spectrum."""
    shapes = [{k: v for k, v in table["radiance"].items() if k != "scale"} for table in tables]
    if all(shape == shapes[0] for shape in shapes):
        scale = math.fsum(float(table["radiance"].get("scale", 1.0)) for table in tables)
        return {"type": "constant", "radiance": shapes[0] | {"scale": scale}}, True
    total = np.sum([_spectrum_values(table["radiance"]) for table in tables], axis=0)
    return {"type": "constant", "radiance": {"values": [[float(nm), float(v)] for nm, v in zip(GRID_NM, total)]}}, False


def combine(context: Context, entries: list[tuple[Light, dict]]) -> list[tuple[Light, dict]]:
    """The lights' (pbrt light, spectrace table) pairs with their environments (constant, envmap) replaced by one,
    at the place of the first; a lone environment without a portal is left as it is."""
    indices = [i for i, (_, table) in enumerate(entries) if table["type"] in ENVIRONMENTS]
    normals = {i: portal_normal(context, entries[i][0]) for i in indices}
    if len(indices) < 2 and all(normal is None for normal in normals.values()):
        return entries
    lines = ", ".join(str(entries[i][0].entity.location.line) for i in indices)
    where = entries[indices[0]][0].entity.location
    constants = [i for i in indices if entries[i][1]["type"] == "constant" and normals[i] is None]
    images = [i for i in indices if i not in constants]
    if not images:
        table, exact = _sum_constants([entries[i][1] for i in constants])
        message = f"infinite lights (lines {lines}) summed into one constant environment"
        if exact:
            context.notes.append(f"{where}: {message}")
        else:
            context.notes.append(f"{where}: {message}, its spectrum sampled on the 1 nm grid")
        return _replaced(entries, indices, table)

    approximate: list[str] = []
    sources = context.environment_sources
    heights = [sources[_file(entries[i][1])][0].shape[0] for i in images if entries[i][1]["type"] == "envmap"]
    height = min(max(heights, default=PORTAL_ROWS), MAX_ROWS)
    directions = latitude_longitude_directions(height, 2 * height)
    # Each map of the sum, by (its source, transform, scale): portal lights of one map share one mask.
    groups: dict[tuple, list[int]] = {}
    for i in images:
        table = entries[i][1]
        if table["type"] == "envmap":
            _, linear, source = sources[_file(table)]
            key: tuple = ("envmap", source, linear.tobytes(), float(table["scale"]))
        else:
            key = ("constant", repr(table["radiance"]))
        groups.setdefault(key if normals[i] is not None else (*key, i), []).append(i)
    scales = [float(entries[i][1]["scale"]) for i in images if entries[i][1]["type"] == "envmap"]
    scale = max(scales, default=1.0) or 1.0
    total = np.zeros((height, 2 * height, 3), np.float64)
    for members in groups.values():
        first = entries[members[0]][1]
        if first["type"] == "envmap":
            square, linear, _ = sources[_file(first)]
            image = context.files[_file(first)]
            if image.shape[0] != height:
                image = to_latitude_longitude(square, linear, height)
                approximate.append(f"resampled to {2 * height} x {height}")
            contribution = image.astype(np.float64) * (float(first["scale"]) / scale)
        else:
            rgb, exact = _constant_rgb(first)
            if not exact:
                approximate.append("a constant light's spectrum carried as its RGB colour")
            contribution = np.broadcast_to(rgb / scale, total.shape)
        mask = np.zeros(total.shape[:2], bool)
        for i in members:
            normal = normals[i]
            mask |= np.ones(mask.shape, bool) if normal is None else (directions @ normal > 0.0)
        total += contribution * mask[..., None]
    for i in constants:
        rgb, exact = _constant_rgb(entries[i][1])
        if not exact:
            approximate.append("a constant light's spectrum carried as its RGB colour")
        total += rgb / scale
    for i in indices:
        if entries[i][1]["type"] == "envmap":
            context.files.pop(_file(entries[i][1]), None)
    portals = [str(entries[i][0].entity.location.line) for i in indices if normals[i] is not None]
    if portals:
        context.warn(
            where,
            f'"portal" (lines {", ".join(portals)}): the light is kept on the portal\'s side of each direction only '
            "(pbrt's radiance for rays that leave through the portal; pbrt also darkens rays that miss it); "
            "sampling does not use the portal",
        )
    file = unique_name("environment", {name.rsplit(".", 1)[0] for name in context.files}) + ".exr"
    context.files[file] = total.astype(np.float32)
    message = f"infinite lights (lines {lines}) summed into one environment map"
    if approximate:
        context.warn(where, f"{message}: {'; '.join(sorted(set(approximate)))}")
    elif len(indices) > 1:
        context.notes.append(f"{where}: {message}")
    # Texels as pbrt's image lights' (RGBIlluminantSpectrum), where the summed constants' colours go too.
    table = {"type": "envmap", "file": f"{context.mesh_folder}/{file}", "scale": scale, "texel_spectra": "smooth"}
    return _replaced(entries, indices, table)


def _file(table: dict) -> str:
    return table["file"].rsplit("/", 1)[-1]


def _replaced(entries: list[tuple[Light, dict]], indices: list[int], table: dict) -> list[tuple[Light, dict]]:
    kept = [entry for i, entry in enumerate(entries) if i not in indices[1:]]
    first = indices[0]
    return [(light, table) if light is entries[first][0] else (light, old) for light, old in kept]
