"""pbrt-v4's camera, film, pixel filter, sampler and integrator as spectrace's camera, film, sampler and
integrator tables.

- Handedness: pbrt's camera has image right = up × forward; spectrace's (as Mitsuba's) forward × up. The whole scene
  is mirrored through x = 0 when the camera's own transform does not already mirror (exported scenes often start
  with `Scale -1 1 1`), so the image is pbrt's (`camera` sets the context's world transform that every mapping
  places things with). spectrace keeps a mirrored mesh's fronts where its winding put them, as pbrt does.
- Each camera's own parameters are mapped by the camera modules that name its type in PBRT_CAMERAS (their
  `from_pbrt(context, camera, view)`, `view` what pbrt's cameras share), each filter's by the pixel filter module
  naming it in PBRT_FILTERS.
- The integrator is mapped by the integrator module naming it in PBRT_INTEGRATORS (path: pbrt's path tracers and
  the integrators of the same image).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from spectrace.cameras import CAMERAS
from spectrace.errors import SpectraceError
from spectrace.integrators import INTEGRATORS
from spectrace.interop.pbrt.context import Context
from spectrace.interop.pbrt.graphics_state import Entity
from spectrace.interop.pbrt.parser import Location, Parameter, error, shown
from spectrace.pixel_filters import PIXEL_FILTERS, PixelFilter

PBRT_DEFAULT_FILM = (1280, 720)
PBRT_DEFAULT_SPP = 16
_MIRROR = np.diag([-1.0, 1.0, 1.0, 1.0])


# pbrt-v4 camera type -> the camera modules whose from_pbrt maps it (their PBRT_CAMERAS), in the registry's order.
# pbrt's perspective camera is two of spectrace's (perspective, and thinlens for one with a lens): each module's
# from_pbrt returns None for the other's.
_CAMERAS: dict[str, list] = {}
for _module in CAMERAS.values():
    for _kind in _module.PBRT_CAMERAS:
        _CAMERAS.setdefault(_kind, []).append(_module)


@dataclass(frozen=True)
class View:
    """What every pbrt camera's mapping reads beside its own parameters (each camera module's from_pbrt): the
    camera's placement in spectrace's world, the film's size and aspect, and the parameters pbrt-v4's projective
    cameras share."""

    world_from_camera: np.ndarray
    origin: list[float]
    forward: list[float]
    up: list[float]
    width: int
    height: int
    aspect: float  # pbrt's frameaspectratio, the film's by default
    default_window: list[float]  # pbrt's screen window: [-1, 1] along the frame's shorter side
    window: Parameter | None  # the screenwindow parameter, where given
    lens_radius: float
    focus: float


def _imported_cameras() -> str:
    kinds = [kind + "".join(getattr(m, "PBRT_CONDITION", "") for m in _CAMERAS[kind][:1]) for kind in _CAMERAS]
    return f"{', '.join(kinds[:-1])} and {kinds[-1]}"


def camera(context: Context, data: dict) -> None:
    scene = context.scene
    camera = scene.camera or Entity("Camera", "perspective", [], Location(context.source, 1))
    if camera.kind not in _CAMERAS:
        raise error(
            camera.location, f"camera '{shown(camera.kind)}': spectrace imports pbrt's {_imported_cameras()} cameras"
        )
    modules = _CAMERAS[camera.kind]
    # The modules that say which of a type's cameras they map (pbrt_maps: the spherical camera's mapping) decide the
    # world's mirror below; where none takes it, the first module's from_pbrt says why.
    modules = [m for m in modules if getattr(m, "pbrt_maps", None) is None or m.pbrt_maps(context, camera)] or modules
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
    # pbrt's image right is the camera's +x = up × forward for a proper rotation; spectrace's is forward × up. A
    # camera whose image runs the other way round (PBRT_MIRRORED: the spherical) takes the other world.
    mirrors = np.linalg.det(linear) > 0
    if any(getattr(module, "PBRT_MIRRORED", False) for module in modules):
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
    aspect = context.one(camera, "frameaspectratio", width / height)
    view = View(
        world_from_camera=world_from_camera,
        origin=context.point(world_from_camera, [0.0, 0.0, 0.0]),
        forward=context.direction(world_from_camera, [0.0, 0.0, 1.0]),
        up=context.direction(world_from_camera, [0.0, 1.0, 0.0]),
        width=width,
        height=height,
        aspect=aspect,
        default_window=[-aspect, aspect, -1.0, 1.0] if aspect > 1.0 else [-1.0, 1.0, -1.0 / aspect, 1.0 / aspect],
        window=camera.find("screenwindow"),
        lens_radius=context.one(camera, "lensradius", 0.0),
        focus=context.one(camera, "focaldistance", 1e6),  # pbrt-v4's default
    )
    table = next(t for module in modules if (t := module.from_pbrt(context, camera, view)) is not None)
    data["camera"] = table
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


# pbrt-v4 filter type -> the filter module that maps it (spectrace.pixel_filters, each module's PBRT_FILTERS).
_FILTERS = {kind: module for module in PIXEL_FILTERS.values() for kind in module.PBRT_FILTERS}


def pixel_filter(context: Context) -> dict:
    """pbrt-v4's PixelFilter, from the filter module whose PBRT_FILTERS name it; its default, as pbrt-v4's, is the
    Gaussian of σ = 0.5 and radius 1.5. Another filter is replaced by that Gaussian with a warning."""
    entity = context.scene.pixel_filter
    kind = entity.kind if entity is not None else "gaussian"
    mapped = kind in _FILTERS
    if not mapped:
        assert entity is not None
        context.warn(entity.location, f"pixel filter '{shown(kind)}' not imported: a Gaussian filter used")
        kind = "gaussian"

    def radius(default: float) -> float:
        """pbrt's xradius (every pbrt filter's), or `default` where the file gave no filter or another one."""
        if entity is None or not mapped:
            return default
        value = context.one(entity, "xradius", default)
        if context.one(entity, "yradius", value) != value:
            context.warn(entity.location, "yradius differs from xradius: spectrace's filters take one radius (x's)")
        return value

    table = _FILTERS[kind].from_pbrt(context, entity, radius)
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


# pbrt-v4 integrator type -> the integrator module that maps it (spectrace.integrators, each module's
# PBRT_INTEGRATORS); pbrt-v4's default is volpath.
_INTEGRATORS: dict[str, Any] = {kind: module for module in INTEGRATORS.values() for kind in module.PBRT_INTEGRATORS}
PBRT_DEFAULT_INTEGRATOR = "volpath"


def integrator(context: Context, data: dict) -> None:
    """The [integrator] table, from the module that maps pbrt's integrator; another (ambientocclusion, aov) renders
    another quantity: pbrt's default is imported, with a warning."""
    entity = context.scene.integrator
    kind = entity.kind if entity is not None else PBRT_DEFAULT_INTEGRATOR
    module = _INTEGRATORS.get(kind, _INTEGRATORS[PBRT_DEFAULT_INTEGRATOR])
    data["integrator"] = module.from_pbrt(context, entity)
    if entity is not None and kind not in _INTEGRATORS:
        context.warn(entity.location, f"integrator '{shown(kind)}' renders another quantity; path tracing imported")
