"""pbrt-v4's camera, film, pixel filter, sampler and integrator as spectrace's camera, film, sampler and
integrator tables.

- Handedness: pbrt's camera has image right = up × forward; spectrace's (as Mitsuba's) forward × up. The whole scene
  is mirrored through x = 0 when the camera's own transform does not already mirror (exported scenes often start
  with `Scale -1 1 1`), so the image is pbrt's (`camera` sets the context's world transform that every mapping
  places things with). spectrace keeps a mirrored mesh's fronts where its winding put them, as pbrt does.
- Field of view: pbrt's `fov` spans the shorter image axis; it becomes spectrace's fov on that axis.
- Depth: pbrt's `maxdepth` counts bounces (1 = direct light); spectrace's max_depth counts segments: maxdepth + 1.
"""

from __future__ import annotations

import math

import numpy as np

from spectrace.errors import SpectraceError
from spectrace.interop.pbrt.context import Context
from spectrace.interop.pbrt.graphics_state import Entity
from spectrace.interop.pbrt.parser import Location, error, shown
from spectrace.pixel_filters import PixelFilter

# Unbiased integrators that converge to the path tracer's image.
_SAME_IMAGE_INTEGRATORS = ("bdpt", "mlt", "sppm", "lightpath", "randomwalk")
PBRT_DEFAULT_FILM = (1280, 720)
PBRT_DEFAULT_FOV = 90.0
PBRT_DEFAULT_MAXDEPTH = 5
PBRT_DEFAULT_SPP = 16
_MIRROR = np.diag([-1.0, 1.0, 1.0, 1.0])


def camera(context: Context, data: dict) -> None:
    scene = context.scene
    camera = scene.camera or Entity("Camera", "perspective", [], Location(context.source, 1))
    if camera.kind not in ("perspective", "orthographic", "spherical"):
        raise error(
            camera.location,
            f"camera '{shown(camera.kind)}': spectrace imports pbrt's perspective, orthographic and spherical "
            '(mapping "equirect") cameras',
        )
    if camera.kind == "spherical" and (mapping := context.string(camera, "mapping") or "equalarea") != "equirect":
        raise error(
            camera.location,
            f"spherical camera mapping '{shown(mapping)}' (pbrt-v4's default is equalarea): spectrace imports "
            'only "equirect", as its equirectangular camera',
        )
    width, height = PBRT_DEFAULT_FILM
    film = scene.film
    if film is not None:
        if film.kind not in ("rgb", "gbuffer", "spectral"):
            raise error(film.location, f"film '{shown(film.kind)}' (pbrt-v4 has rgb, gbuffer and spectral)")
        width = context.integer(film, "xresolution", width, low=1)
        height = context.integer(film, "yresolution", height, low=1)
        if (filename := context.string(film, "filename")) is not None:
            context.notes.append(f"{film.location}: the output file name '{shown(filename)}' is not imported")
    world_from_camera = np.linalg.inv(scene.camera_from_world)
    linear = world_from_camera[:3, :3]
    # pbrt's image right is the camera's +x = up × forward for a proper rotation; spectrace's is forward × up.
    # pbrt's spherical camera turns the other way: its longitude runs from +x toward +z, i.e. from right to
    # left as seen from inside, where spectrace's equirectangular runs left to right (see spherical_camera).
    mirrors = np.linalg.det(linear) > 0
    if camera.kind == "spherical":
        mirrors = not mirrors
    context.world = _MIRROR if mirrors else np.eye(4)
    gram = linear.T @ linear
    if not np.allclose(gram, np.eye(3) * gram[0, 0], rtol=1e-4, atol=1e-6 * gram[0, 0]):
        context.warn(
            camera.location,
            "the camera transform scales or shears unevenly: only its position and axes are imported",
        )
    if scene.camera_medium:
        context.warn(camera.location, f"the camera's medium '{shown(scene.camera_medium)}' not imported")
    origin = context.point(world_from_camera, [0.0, 0.0, 0.0])
    forward = context.direction(world_from_camera, [0.0, 0.0, 1.0])
    up = context.direction(world_from_camera, [0.0, 1.0, 0.0])
    aspect = context.one(camera, "frameaspectratio", width / height)
    # pbrt's default screen window spans [-1, 1] along the frame's shorter side.
    default_window = [-aspect, aspect, -1.0, 1.0] if aspect > 1.0 else [-1.0, 1.0, -1.0 / aspect, 1.0 / aspect]
    window = camera.find("screenwindow")
    lens_radius = context.one(camera, "lensradius", 0.0)
    focus = context.one(camera, "focaldistance", 1e6)  # pbrt-v4's default
    if camera.kind == "spherical":
        data["camera"] = spherical_camera(context, camera, world_from_camera, origin, up)
    elif camera.kind == "orthographic":
        x0, x1, y0, y1 = context.floats(camera, "screenwindow", default_window) or default_window
        if not (x1 > x0 and y1 > y0):
            raise error(camera.location, "screenwindow must have x0 < x1 and y0 < y1")
        if not math.isclose((x1 - x0) / (y1 - y0), width / height, rel_tol=1e-4):
            context.warn(
                camera.location,
                "the screen window's aspect ratio differs from the film's: the window's width is kept",
            )
        # An off-centre window moves the view's centre in the camera's plane (pbrt's camera x is image right).
        centre = context.point(world_from_camera, [(x0 + x1) / 2.0, (y0 + y1) / 2.0, 0.0])
        data["camera"] = {
            "type": "orthographic",
            "origin": centre,
            "target": (np.asarray(centre) + np.asarray(forward)).tolist(),
            "up": up,
            "view_width": x1 - x0,
        }
        if lens_radius > 0.0:
            context.warn(camera.location, '"lensradius" not imported: spectrace\'s orthographic camera is sharp')
    else:
        if window is not None:
            context.warn(window.location, '"screenwindow" not imported (the image spans pbrt\'s default window)')
        fov = context.one(camera, "fov", PBRT_DEFAULT_FOV)
        if not 0.0 < fov < 180.0:
            raise error(camera.location, f"fov must lie in (0, 180) degrees, got {fov:g}")
        data["camera"] = {
            "origin": origin,
            "target": (np.asarray(origin) + np.asarray(forward)).tolist(),
            "up": up,
            "fov": fov,
            # pbrt's fov spans the shorter side of the frame.
            "fov_axis": "y" if aspect > 1.0 else "x",
        }
        if lens_radius > 0.0:
            if not focus > 0.0:
                raise error(camera.location, f"focaldistance must be > 0, got {focus:g}")
            data["camera"] = {
                "type": "thinlens",
                **data["camera"],
                "aperture_radius": lens_radius,
                "focus_distance": focus,
            }
    data["film"] = {
        "width": width,
        "height": height,
        "filter": pixel_filter(
            context,
        ),
    }
    # pbrt-v4's sensor scales the image by ISO/100 times the shutter's open time; spectrace's film exposure
    # (stops) scales its RGB the same way.
    iso = context.one(film, "iso", 100.0) if film is not None else 100.0
    ratio = iso / 100.0 * (context.one(camera, "shutterclose", 1.0) - context.one(camera, "shutteropen", 0.0))
    if not ratio > 0:
        raise error(camera.location, "iso and the shutter times give no exposure")
    if ratio != 1.0:
        data["film"]["exposure"] = math.log2(ratio)


def spherical_camera(context: Context, camera: Entity, world_from_camera: np.ndarray, origin, up) -> dict:
    """pbrt-v4's spherical camera with mapping "equirect" as spectrace's equirectangular camera. pbrt-v4
    (cameras.cpp, SphericalCamera::GenerateRay) sends film position (u, v) in [0, 1]² along θ = π v, φ = 2π u,
    camera direction (sin θ cos φ, cos θ, sin θ sin φ): row 0 toward the camera's +y, the image's centre
    (φ = π) along its −x, φ growing from +x toward +z. spectrace's (kernels/camera.cl) sends (u, v) along
    θ = π v, φ' = 2π u − π, sin θ sin φ' right + cos θ up + sin θ cos φ' forward. The two agree with up = the
    camera's +y, forward = its −x and right = forward × up = its −z, which holds when the world is mirrored
    exactly when the perspective camera's is not (camera())."""
    if context.one(camera, "lensradius", 0.0) > 0.0:
        context.warn(camera.location, '"lensradius" not imported: the spherical camera is a pinhole')
    if camera.find("screenwindow") is not None:
        context.warn(camera.location, '"screenwindow" not imported: the spherical camera covers the whole sphere')
    forward = (-np.asarray(context.direction(world_from_camera, [1.0, 0.0, 0.0]))).tolist()
    return {
        "type": "equirectangular",
        "origin": origin,
        "target": (np.asarray(origin) + np.asarray(forward)).tolist(),
        "up": up,
    }


def pixel_filter(context: Context) -> dict:
    """pbrt-v4's PixelFilter; its default, as pbrt-v4's, is the Gaussian of σ = 0.5 and radius 1.5."""
    entity = context.scene.pixel_filter
    kind = entity.kind if entity is not None else "gaussian"
    defaults = {"box": 0.5, "gaussian": 1.5, "mitchell": 2.0, "triangle": 2.0}
    if kind not in defaults:
        assert entity is not None
        context.warn(entity.location, f"pixel filter '{shown(kind)}' not imported: a Gaussian filter used")
        kind = "gaussian"
    radius = defaults[kind]
    if entity is not None and kind == entity.kind:
        radius = context.one(entity, "xradius", radius)
        if context.one(entity, "yradius", radius) != radius:
            context.warn(entity.location, "yradius differs from xradius: spectrace's filters take one radius (x's)")
    if kind == "box":
        if radius != 0.5:
            assert entity is not None
            context.warn(entity.location, "a box filter's radius other than 0.5 is not imported")
        return {"type": "box"}
    if kind == "triangle":
        table: dict = {"type": "tent", "radius": radius}
    elif kind == "gaussian":
        sigma = context.one(entity, "sigma", 0.5) if entity is not None else 0.5
        table = {"type": "gaussian", "stddev": sigma, "radius": radius}
    else:
        b = context.one(entity, "B", 1.0 / 3.0) if entity is not None else 1.0 / 3.0
        c = context.one(entity, "C", 1.0 / 3.0) if entity is not None else 1.0 / 3.0
        table = {"type": "mitchell", "radius": radius, "b": b, "c": c}
    try:  # the filters' own ranges and rules (spectrace.pixel_filters), at the file's line
        PixelFilter(**table)
    except SpectraceError as exc:
        assert entity is not None  # pbrt's default filter is valid
        raise error(entity.location, f"{exc.message} ({exc.where}, imported from PixelFilter)") from None
    return table


def sampler(context: Context, data: dict) -> None:
    sampler = context.scene.sampler
    spp, settings = PBRT_DEFAULT_SPP, dict[str, object]()
    if sampler is not None:
        spp = context.integer(sampler, "pixelsamples", spp, low=1)
        if (seed := sampler.find("seed", "integer")) is not None:
            settings["seed"] = int(seed.values[0])
        if sampler.kind == "independent":
            settings["type"] = "independent"
        else:
            settings["type"] = "sobol"
            context.notes.append(
                f"{sampler.location}: sampler '{shown(sampler.kind)}' imported as spectrace's Owen-scrambled Sobol"
            )
    data["sampler"] = {**settings, "spp": spp}


def integrator(context: Context, data: dict) -> None:
    integrator = context.scene.integrator
    depth = PBRT_DEFAULT_MAXDEPTH
    if integrator is not None:
        depth = context.integer(integrator, "maxdepth", depth, low=0)
        kind = shown(integrator.kind)
        if integrator.kind in _SAME_IMAGE_INTEGRATORS:
            context.notes.append(f"{integrator.location}: integrator '{kind}' imported as path tracing (same image)")
        elif integrator.kind not in ("volpath", "path", "simplepath", "simplevolpath"):
            context.warn(integrator.location, f"integrator '{kind}' renders another quantity; path tracing imported")
    # pbrt's maxdepth counts bounces (0: emitters only), spectrace's max_depth path segments (1: emitters only).
    data["integrator"] = {"type": "path", "max_depth": depth + 1}
