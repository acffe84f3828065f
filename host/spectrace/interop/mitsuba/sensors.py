"""The sensor with its film and sampler: the camera (perspective with fov and any fov_axis, or focal_length;
thinlens; orthographic; to_world as lookat, translate, rotate, scale or matrix), hdrfilm width and height,
specfilm (its responses as the film's sensor, a CSV beside the TOML), the reconstruction filter, and the sampler's
sample_count and seed. Mitsuba sensor plugins map to spectrace cameras through the cameras' MITSUBA_PLUGINS, each
camera module's `from_mitsuba` reading its own properties, and rfilters through the pixel filters'."""

from __future__ import annotations

import math
import re

import numpy as np

from spectrace.integrators import INTEGRATORS
from spectrace.interop.mitsuba.context import ImportContext, Properties
from spectrace.interop.mitsuba.plugins import (
    CAMERA_MODULES,
    CAMERA_PLUGINS,
    FILTER_PLUGINS,
    SPECTRUM_PLUGINS,
    SUPPORTED,
)
from spectrace.interop.mitsuba.textures import spectrum_element
from spectrace.interop.mitsuba.transforms import to_world
from spectrace.interop.mitsuba.tree import Element, shown
from spectrace.pixel_filters import PIXEL_FILTERS
from spectrace.spectral.grid import GRID_MAX_NM, GRID_MIN_NM

# hdrfilm properties about the file Mitsuba writes, not the image: nothing to import.
FILM_STORAGE = ("pixel_format", "component_format", "file_format", "banner")
FILM_DIAGONAL_MM = math.hypot(36.0, 24.0)  # Mitsuba's focal_length is in 35 mm film equivalent (36 x 24 mm)
MITSUBA_DEFAULT_FILM = (768, 576)  # hdrfilm's default width and height
MITSUBA_DEFAULT_FOCAL_LENGTH_MM = 50.0  # the perspective sensor's, when neither fov nor focal_length is given


def sensor(ctx: ImportContext, element: Element, data: dict) -> None:
    """The sensor as the [camera] table of `data`, its film as [film] and its sampler as [sampler]."""
    kind = ctx.kind(element)
    if kind not in CAMERA_PLUGINS:
        ctx.unsupported_object(element)
        return
    properties = ctx.properties(element)
    for key, child in properties.items():
        if key.startswith("principal_point_offset"):
            properties.understood(key)
            if ctx.number(child) != 0.0:
                ctx.unsupported_plugin(element, f" with {shown(key)}")
    # Nested or referenced (a scene may declare its film or sampler at the top and refer to it by id).
    film = next(iter(ctx.nested(properties, "film")), None)
    width, height = MITSUBA_DEFAULT_FILM
    ctx.origins["film"] = element
    if film is not None:
        ctx.origins["film"] = film
        if ctx.kind(film) not in SUPPORTED["film"]:
            ctx.unsupported_plugin(film)
        film_properties = ctx.properties(film)
        film_properties.understood(*FILM_STORAGE)
        width = ctx.integer(film_properties["width"], low=1) if "width" in film_properties else width
        height = ctx.integer(film_properties["height"], low=1) if "height" in film_properties else height
        for key in list(film_properties.keys()):
            if key.startswith("crop_"):
                film_properties.understood(key)
                ctx.unsupported_plugin(film, f" with {shown(key)}")
        rfilter = next(iter(ctx.nested(film_properties, "rfilter")), None)
        sensor = specfilm_sensor(ctx, film, film_properties) if ctx.kind(film) == "specfilm" else {}
    else:
        rfilter = None
        sensor = {}
    data["film"] = {"width": width, "height": height, "filter": pixel_filter(ctx, rfilter), **(sensor or {})}
    matrix = to_world(ctx, properties)
    linear = matrix[:3, :3]
    if not np.linalg.det(linear) > 0:
        ctx.unsupported_plugin(element, " with a mirroring or singular to_world")
        return
    origin = matrix[:3, 3]
    forward = linear @ [0.0, 0.0, 1.0]
    up = linear @ [0.0, 1.0, 0.0]
    camera = CAMERA_MODULES[kind].from_mitsuba(
        ctx,
        element,
        properties,
        {
            "type": CAMERA_PLUGINS[kind],
            "origin": origin.tolist(),
            "target": (origin + forward / np.linalg.norm(forward)).tolist(),
            "up": (up / np.linalg.norm(up)).tolist(),
        },
        linear,
        width / height,
    )
    if camera is None:
        return
    data["camera"] = camera
    if "near_clip" in properties:
        data["camera"]["near_clip"] = ctx.number(properties["near_clip"])
        if not data["camera"]["near_clip"] >= 0.0:
            raise ctx.fail(properties["near_clip"], "near_clip must be 0 or more", "value")
    if "far_clip" in properties:
        # Mitsuba's default is 10 000 scene units; spectrace's none, the same for scenes of any usual size.
        far = ctx.number(properties["far_clip"])
        if not far > data["camera"].get("near_clip", 0.0):
            raise ctx.fail(properties["far_clip"], "far_clip must be more than near_clip", "value")
        data["camera"]["far_clip"] = far
    ctx.origins["camera"] = element
    sampler = next(iter(ctx.nested(properties, "sampler")), None)
    # A pinhole has no focus: Mitsuba's perspective sensor takes focus_distance and does nothing with it.
    properties.understood("focus_distance")
    if sampler is not None:
        sampler_properties = ctx.properties(sampler)
        data["sampler"] = {}
        ctx.origins["sampler"] = sampler
        if "sample_count" in sampler_properties:
            data["sampler"]["spp"] = ctx.integer(sampler_properties["sample_count"], low=1)
        if "seed" in sampler_properties:
            data["sampler"]["seed"] = ctx.integer(sampler_properties["seed"], low=0)
        if ctx.kind(sampler) != "independent":
            ctx.notes.append(
                f"{ctx.at(sampler)}: sampler '{shown(sampler.get('type') or '')}' not imported: "
                "spectrace uses its own sampler (same sample count)"
            )


def specfilm_sensor(ctx: ImportContext, film: Element, properties: Properties) -> dict | None:
    """A specfilm's response curves (its named spectra) as the film's sensor: a CSV beside the TOML
    (`side_files`) with one channel per curve, in the file's order (as Mitsuba's film holds them; its EXR
    sorts them by name, as spectrace's does), on a 1 nm grid over their
    wavelengths, each zero outside its own (as Mitsuba evaluates a tabulated spectrum). Both films record
    ∫ L(λ) s(λ) dλ per channel. Curves beyond 360-830 nm widen the film's range there, with the RGB uplifts
    continued (film.extend_rgb), as Mitsuba evaluates its RGB spectra at any wavelength."""
    curves: dict[str, np.ndarray] = {}
    for key in list(dict.keys(properties)):
        child = ctx.resolve(dict.__getitem__(properties, key))
        if child.tag not in ("spectrum", "texture") or (
            child.tag == "texture" and ctx.kind(child) not in SPECTRUM_PLUGINS
        ):
            continue
        properties.understood(key)
        table = spectrum_element(ctx, child)
        if table is None:
            return None
        if "values" in table:
            curves[key] = np.asarray(table["values"], np.float64).reshape(-1, 2)
        elif "value" in table:  # Mitsuba's uniform spectrum spans the visible
            curves[key] = np.array([[GRID_MIN_NM, table["value"]], [GRID_MAX_NM, table["value"]]])
        else:
            ctx.unsupported_plugin(film, f" with the response '{shown(key)}' (a {shown(ctx.kind(child))})")
            return None
        if not re.fullmatch(r"[A-Za-z0-9_.\-]+", key):
            raise ctx.fail(child, f"response name '{shown(key)}' must be letters, digits, '_', '.' or '-'")
    if not curves:
        raise ctx.fail(film, "a specfilm needs at least one response spectrum (Mitsuba requires one)")
    lo = math.floor(min(curve[0, 0] for curve in curves.values()))
    hi = math.ceil(max(curve[-1, 0] for curve in curves.values()))
    if lo < 200 or hi > 2500:
        raise ctx.fail(film, f"its responses span {lo}-{hi} nm; spectrace's film reaches 200-2500 nm")
    grid = np.arange(lo, hi + 1, dtype=np.float64)
    columns = [np.interp(grid, c[:, 0], c[:, 1], left=0.0, right=0.0) for c in curves.values()]
    lines = ["# The response curves of a Mitsuba 3 specfilm, on a 1 nm grid", f"wavelength_nm,{','.join(curves)}"]
    lines += [f"{w:g}," + ",".join(f"{column[i]:.9g}" for column in columns) for i, w in enumerate(grid)]
    name = f"{ctx.side_stem}.sensor.csv"
    ctx.side_files[name] = "\n".join(lines) + "\n"
    sensor: dict = {"sensor": name}
    if lo < GRID_MIN_NM or hi > GRID_MAX_NM:
        sensor |= {"wavelengths": [min(lo, int(GRID_MIN_NM)), max(hi, int(GRID_MAX_NM))], "extend_rgb": True}
        ctx.notes.append(
            f"the specfilm's responses reach {lo}-{hi} nm: the film's range is widened to take them, with RGB "
            "colours continued beyond the visible as Mitsuba does"
        )
    ctx.notes.append(f"the specfilm's responses are the film's sensor, written to {name} beside the scene")
    return sensor


def pixel_filter(ctx: ImportContext, rfilter: Element | None) -> dict:
    """The film's filter, from the filter module whose MITSUBA_PLUGINS name it: Mitsuba 3's own default, its
    Gaussian of σ = 0.5, when the file names none."""
    if rfilter is None:
        return {"type": "gaussian", "stddev": 0.5}
    kind = rfilter.get("type") or ""
    properties = ctx.properties(rfilter)
    if kind in FILTER_PLUGINS:
        return PIXEL_FILTERS[FILTER_PLUGINS[kind]].from_mitsuba(ctx, rfilter, properties)
    *others, last = PIXEL_FILTERS
    ctx.notes.append(
        f"{ctx.at(rfilter)}: reconstruction filter '{shown(kind)}' not imported: spectrace has {', '.join(others)} "
        f"and {last}; a box filter used"
    )
    return {"type": "box"}


def fov_x(ctx: ImportContext, properties: dict[str, Element], aspect: float, element: Element) -> float:
    """Horizontal field of view in degrees, as Mitsuba derives it from fov + fov_axis or focal_length."""
    if "fov" in properties:
        fov = ctx.number(properties["fov"])
        if not 0.0 < fov < 180.0:
            raise ctx.fail(properties["fov"], f"fov must lie in (0, 180) degrees, got {fov:g}", "value")
        axis = ctx.text(properties["fov_axis"]) if "fov_axis" in properties else "x"
    else:
        focal = MITSUBA_DEFAULT_FOCAL_LENGTH_MM
        if "focal_length" in properties:
            focal_element = ctx.resolve(properties["focal_length"])
            text = ctx.required(focal_element, "value").strip().removesuffix("mm")
            focal = ctx.parse_number(text, focal_element, "value")
            if not focal > 0.0:
                raise ctx.fail(focal_element, f"focal_length must be > 0 mm, got {focal:g}", "value")
        fov, axis = math.degrees(2.0 * math.atan(FILM_DIAGONAL_MM / (2.0 * focal))), "diagonal"
    tan_half = math.tan(math.radians(fov) / 2.0)
    if axis == "smaller":
        axis = "y" if aspect > 1.0 else "x"
    elif axis == "larger":
        axis = "x" if aspect > 1.0 else "y"
    if axis == "y":
        tan_half *= aspect
    elif axis == "diagonal":
        tan_half *= aspect / math.hypot(aspect, 1.0)
    elif axis != "x":
        raise ctx.fail(
            properties["fov_axis"],
            f"unknown fov_axis '{shown(axis)}' (x, y, diagonal, smaller or larger)",
            "value",
        )
    return math.degrees(2.0 * math.atan(tan_half))


def whole_pixel_filter(ctx: ImportContext, data: dict) -> None:
    """The integrators that estimate whole pixels (those whose REFUSES names pixel filters: bdpt, sppm): a film
    filter other than the box (Mitsuba's default is a Gaussian) becomes the box with a note, so the import renders."""
    film, integrator = data.get("film"), data.get("integrator", {})
    module = INTEGRATORS.get(integrator.get("type", ""))
    if film is None or module is None or "pixel filters" not in module.REFUSES or film["filter"]["type"] == "box":
        return
    ctx.notes.append(
        f"{ctx.at(ctx.origins['film'])}: integrator '{integrator['type']}' estimates whole pixels: the film's "
        f"{film['filter']['type']} filter is imported as the box filter"
    )
    film["filter"] = {"type": "box"}
