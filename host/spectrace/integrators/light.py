"""The `light` integrator, light tracing (kernels/integrator_light.cl): what it refuses, its launches of light paths
and the deterministic addition of their splats to the film, which BDPT's passes share (spectrace.integrators.bdpt).

A light path's connections to the camera land in arbitrary pixels, so the kernel (kernels/integrator_light.cl) does
not add them to the film: each work-item writes its splats as records (pixel, XYZ) into slots of its own, and the
host adds every record to the film in the order (sample index, work-item, record). Float sums then come out the same
whatever the split into passes, as the path tracer's do, with no atomics (OpenCL 1.2 has no float atomics, and the
64-bit integer ones an order-free fixed-point film would need are an extension). BDPT's work-items also write each
of their pixels' own estimates (all its strategies but the light-to-camera one) to a row per pixel, which the host
adds to the film before the sample's records: fewer records to add one by one.

Each pixel sample runs as many light paths as the film has pixels, so samples per pixel mean the same work as for
the path tracer (Mitsuba 3's ptracer counts alike) and the film is divided by the samples done as always.
"""

from __future__ import annotations

import numpy as np

from spectrace.integrators.base import (
    SHARED_PARAMETERS,
    RenderHost,
    Scene,
    no_defines,
    no_params,
)

NAME = "light"
# Mitsuba 3's particle tracer, with the same max_depth and rr_depth meaning.
MITSUBA_PLUGINS = ("ptracer",)
PBRT_INTEGRATORS: tuple[str, ...] = ()
PBRT_NONE = "pbrt-v4's lightpath converges to the path tracer's image and imports as path (path.py)"
PARAMETERS = SHARED_PARAMETERS
PROGRAMS = {"megakernel": "integrator_light.cl"}
SPLATS = "splats"  # its camera connections land in any pixel: whole films only
# Of base.FEATURES, what it refuses in any scene (`problem` says why; it refuses more in some scenes).
REFUSES: tuple[str, ...] = ("AOVs", "film responses", "hidden area lights")
CHECKPOINT_PROBLEM = None
# Its general program costs a few of its scenes' own builds: SPECTRACE_GENERAL_KERNELS=common shares it.
SHARES_GENERAL_PROGRAM = True
defines = no_defines
params = no_params

# Splat record slots per light path and launch: a path longer than this is launched again for its later records
# (rare: Russian roulette ends most paths sooner), so memory stays bounded for unbounded max_depth.
MAX_RECORD_SLOTS = 16
# The cameras a point can connect to (kernels/camera_importance.cl).
LIGHT_TRACED_CAMERAS = ("perspective", "thinlens", "orthographic", "equirectangular", "equalarea")
# Cameras over the whole sphere, whose film wraps at its edges (a wider filter's spread would have to follow).
SPHERICAL_CAMERAS = ("equirectangular", "equalarea")
RECORD_BYTES = 16 + 4  # float4 XYZ + int pixel
BAND_RECORD_BYTES = 16 + 16  # with spectral bands: float4 lane values + int4 lane bands


def scene_sphere(scene: Scene) -> np.ndarray:
    """A sphere (centre, radius) holding every shape, slightly enlarged: distant and environment light paths start
    on a disk outside it."""
    points = [shape.mesh.vertices for shape in scene.shapes if len(shape.mesh.vertices)]
    if not points:
        return np.array([0.0, 0.0, 0.0, 1.0], np.float32)
    everything = np.concatenate(points)
    lo, hi = everything.min(axis=0), everything.max(axis=0)
    centre = 0.5 * (lo + hi)
    radius = 0.5 * float(np.linalg.norm(hi - lo))
    radius = radius * 1.01 + 1e-3 * max(1.0, float(np.abs(centre).max()))
    return np.array([*centre, radius], np.float32)


def _has_environment(scene: Scene) -> bool:
    from spectrace.lights import LIGHTS

    models = tuple(module.MODEL for module in LIGHTS.values() if getattr(module, "IS_ENVIRONMENT", False))
    return any(isinstance(light, models) for light in scene.lights)


def filter_spread(pixel_filter, film: np.ndarray, width: int, height: int) -> tuple[np.ndarray, np.ndarray]:
    """The pixels (row-major) each splat at film position (x, y) adds to, and the weights f(dx) f(dy) / (∫f)², shaped
    (splats, k²): a pixel's value is ∫ f(x − x_pixel) L(x) dx / (∫f)², which a camera path's filter-sampled
    position estimates and a splat's weight in that pixel does too. 0 weight for pixels off the film."""
    radius = pixel_filter.support
    k = int(np.floor(2.0 * radius)) + 2
    first = np.floor(film - radius).astype(np.int64)  # (splats, 2): the lowest pixel column and row it may reach
    offsets = np.arange(k)
    columns = first[:, 0:1] + offsets  # (splats, k)
    rows = first[:, 1:2] + offsets
    wx = pixel_filter.evaluate(film[:, 0:1] - (columns + 0.5)) * ((columns >= 0) & (columns < width))
    wy = pixel_filter.evaluate(film[:, 1:2] - (rows + 0.5)) * ((rows >= 0) & (rows < height))
    weight = (wy[:, :, None] * wx[:, None, :]) / pixel_filter.integral() ** 2
    pixel = np.clip(rows, 0, height - 1)[:, :, None] * width + np.clip(columns, 0, width - 1)[:, None, :]
    return pixel.reshape(len(film), k * k), weight.reshape(len(film), k * k)


def add_in_order(target: np.ndarray, index: np.ndarray, values: np.ndarray) -> None:
    """target[index[k]] += values[k] for k = 0, 1, ... in that order (np.add.at's float sums). A C-contiguous 2-D
    target is added to as its flattened elements, since np.add.at's fast path is for 1-D arrays (measured 2.8 times
    faster on BDPT's records than on the rows); each element still adds its values one after another, so the bits
    are the same. Other targets take np.add.at as they are."""
    if target.ndim == 1 or not target.flags.c_contiguous or len(index) == 0:
        np.add.at(target, index, values)
        return
    width = target.shape[1]
    flat = (index.astype(np.intp)[:, None] * width + np.arange(width)).ravel()
    np.add.at(target.reshape(-1), flat, values.reshape(-1))


def problem(scene: Scene, medium_count: int, spectral_bins: int) -> str | None:
    """Why the light tracer cannot render this scene as asked, or None."""
    return splatting_problem(scene, NAME)


def passes(host: RenderHost, shape: str, spectral_bins: int) -> LightPasses:
    depth_slots = host.scene.max_depth + 1 if host.scene.max_depth > 0 else MAX_RECORD_SLOTS
    return LightPasses(host, spectral_bins, "light_pass", min(depth_slots, MAX_RECORD_SLOTS))


def splatting_problem(scene: Scene, name: str) -> str | None:
    """Why integrator `name` (the light tracer, or BDPT, whose light-to-camera joins are its splats) cannot render
    this scene, or None."""
    camera_type = scene.camera.type
    if camera_type not in LIGHT_TRACED_CAMERAS:
        known = ", ".join(LIGHT_TRACED_CAMERAS)
        return f"integrator '{name}' supports the {known} cameras, not {camera_type!r}"
    if camera_type in SPHERICAL_CAMERAS and scene.pixel_filter.type != "box":
        # A wider filter's spread would have to wrap around the image's seam and poles (filter_spread does not).
        return (
            f"integrator '{name}' takes the {camera_type} camera with the box filter only, not a "
            f"{scene.pixel_filter.type} filter; use film.filter = \"box\" or 'path'"
        )
    if scene.pixel_filter.type != "box" and _has_environment(scene):
        return (
            f"integrator '{name}' cannot apply a {scene.pixel_filter.type} filter to an environment seen directly "
            "(its own camera rays sample the box); use film.filter = \"box\" or 'path'"
        )
    if not scene.film_response.is_default:
        return f"integrator '{name}' renders the default CIE 1931 film only (no observers, sensor or wavelengths yet)"
    if scene.aovs:
        return f"integrator '{name}' does not record AOVs yet; leave film.aovs out or use 'path'"
    if scene.hide_emitters and any(shape.emitter is not None for shape in scene.shapes):
        return (
            f"integrator '{name}' cannot hide area lights from the camera (hide_emitters); "
            "use hide_environment or 'path'"
        )
    return None


class LightPasses:
    """Passes of light paths whose camera connections are splat records (kernel `kernel`, `capacity` record slots
    per path and launch). BDPT's (`own_rows`) also write each pixel's own estimate to a row per pixel, and run one
    light subpath per group of `pixels_per_path` pixels (kernels/bdpt.cl's trace_bdpt)."""

    def __init__(
        self,
        host: RenderHost,
        spectral_bins: int,
        kernel: str,
        capacity: int,
        own_rows: bool = False,
        pixels_per_path: int = 1,
    ):
        self.host = host
        scene = host.scene
        self.capacity = capacity
        self.own_rows = own_rows
        pixels = host.pixel_count
        self.pixel_filter = scene.pixel_filter if scene.pixel_filter.type != "box" else None
        record_bytes = RECORD_BYTES + (BAND_RECORD_BYTES if spectral_bins else 0) + (8 if self.pixel_filter else 0)
        host.check_memory({"splat records": pixels * capacity * record_bytes + (pixels * 16 if own_rows else 0)})
        self.spectral_bins = spectral_bins
        self._kernel = host.kernel(kernel)
        self._splat_xyz = host.buffer(pixels * capacity * 16)
        self._splat_pixel = host.buffer(pixels * capacity * 4)
        self._splat_counts = host.buffer(pixels * 4)
        band_slots = pixels * capacity if spectral_bins else 1
        self._splat_band_value = host.buffer(band_slots * 16)
        self._splat_band = host.buffer(band_slots * 16)
        self._splat_film = host.buffer((pixels * capacity if self.pixel_filter else 1) * 8)
        self._items = host.buffer(pixels * 4)
        self._own_xyz = host.buffer((pixels if own_rows else 1) * 16)
        self.work_items = -(-pixels // pixels_per_path)
        self._sphere = scene_sphere(scene)
        # hide_emitters without area lights hides the environment alone (Mitsuba's), as hide_environment does.
        self._hide_environment = np.int32(scene.hide_environment or getattr(scene, "hide_emitters", False))

    def reset(self) -> None:
        pass

    def _launch(self, sample_index: int, items: np.ndarray, begin: int) -> tuple[np.ndarray, ...]:
        """Runs the light paths of `items` for one pixel sample, keeping their records begin .. begin + capacity − 1:
        (pixel, xyz, band values, bands, film positions) of the slots in order (0 rows for what the render does
        not record: bands without spectral bins, positions with the box filter), and each path's record count."""
        host = self.host
        count, capacity = len(items), self.capacity
        host.upload(self._items, np.ascontiguousarray(items, np.int32))
        host.launch(
            self._kernel,
            count,
            *host.scene_arguments(),
            host.cmf_buffer,
            self._sphere,
            self._hide_environment,
            np.int32(sample_index),
            self._items,
            np.int32(count),
            np.int32(begin),
            np.int32(capacity),
            self._splat_xyz,
            self._splat_pixel,
            self._splat_counts,
            self._splat_band_value,
            self._splat_band,
            self._splat_film,
            self._own_xyz,
            host.film.ray_count_buffer,
        )
        pixel = np.empty(count * capacity, np.int32)
        xyz = np.empty((count * capacity, 4), np.float32)
        counts = np.empty(count, np.int32)
        host.download(pixel, self._splat_pixel)
        host.download(xyz, self._splat_xyz)
        host.download(counts, self._splat_counts)
        band_rows = count * capacity if self.spectral_bins else 0
        band_value = np.empty((band_rows, 4), np.float32)
        band = np.empty((band_rows, 4), np.int32)
        if band_rows:
            host.download(band_value, self._splat_band_value)
            host.download(band, self._splat_band)
        film = np.empty((count * capacity if self.pixel_filter else 0, 2), np.float32)
        if len(film):
            host.download(film, self._splat_film)
        host.finish()
        return pixel, xyz, band_value, band, film, counts

    def _sample_splats(self, sample_index: int) -> list[np.ndarray]:
        """Every splat of one pixel sample's light paths, in the order (work-item, record): pixel, xyz, and (0 rows
        when not recorded) each record's lane values, bands and film position."""
        capacity = self.capacity
        items = np.arange(self.work_items, dtype=np.int32)
        begin = 0
        parts = []
        while len(items):
            *columns, counts = self._launch(sample_index, items, begin)
            used = columns[0] >= 0
            kept = [column[used] if len(column) else column for column in columns]
            following = items[counts > begin + capacity]
            if begin == 0 and not len(following):
                return kept  # the usual case: every path's records fitted in one launch
            record = np.tile(np.arange(begin, begin + capacity), len(items))
            owner = np.repeat(items, capacity)
            parts.append([owner[used], record[used], *kept])
            items = following
            begin += capacity
        owner, record, *columns = (np.concatenate(column) for column in zip(*parts, strict=True))
        order = np.lexsort((record, owner))
        return [column[order] if len(column) else column for column in columns]

    def run_pass(self, sample_count: int) -> None:
        """Adds `sample_count` pixel samples' light paths to the renderer's film."""
        host = self.host
        film = host.film
        pixels = host.pixel_count
        with host.render_pass(sample_count) as done:
            sums = np.empty((pixels, 4), np.float32)
            host.download(sums, film.xyz_buffer)
            bins = self.spectral_bins
            bands = np.empty(pixels * bins, np.float32)
            if bins:
                host.download(bands, film.spectral_buffer)
            own = np.empty((pixels, 4), np.float32) if self.own_rows else None
            for sample_index in range(done, done + sample_count):
                pixel, xyz, band_value, band, position = self._sample_splats(sample_index)
                if own is not None:
                    # BDPT's pixels' own estimates (every strategy but t = 1), one per pixel, before the sample's
                    # splats.
                    host.download(own, self._own_xyz)
                    sums += own
                if self.pixel_filter is not None:
                    # Each splat spread over the pixels its filter covers; the dropped-sample count stays in its own.
                    np.add.at(sums[:, 3], pixel, xyz[:, 3])
                    pixel, weight = filter_spread(
                        self.pixel_filter, position.astype(np.float64), host.scene.width, host.scene.height
                    )
                    xyz = (xyz[:, None, :3] * weight[..., None]).astype(np.float32)
                    band_value = band_value[:, None, :] * weight[..., None] if bins else band_value
                    band = np.repeat(band[:, None, :], weight.shape[1], axis=1) if bins else band
                    nonzero = weight != 0.0
                    pixel, xyz = pixel[nonzero], xyz[nonzero]
                    if bins:
                        band_value, band = band_value[nonzero].astype(np.float32), band[nonzero]
                    np.add.at(sums[:, :3], pixel, xyz)  # strided rows: kept as they were
                else:
                    # One record after another in this order: the same float sums every time.
                    add_in_order(sums, pixel, xyz)
                if bins:
                    # Record by record, lane by lane within one, as add_to_spectral_film adds a camera path's lanes.
                    inside = band >= 0
                    np.add.at(bands, (pixel[:, None] * bins + band)[inside], band_value[inside])
            host.upload(film.xyz_buffer, sums)
            if bins:
                host.upload(film.spectral_buffer, bands)
            host.finish()


def from_mitsuba(importer, element, properties, settings: dict) -> dict:
    """Mitsuba's particle tracer: how many light paths one of its passes runs changes the scheduling, not the
    image."""
    settings["type"] = NAME
    properties.understood("samples_per_pass")
    return settings


def to_mitsuba(scene: Scene) -> dict:
    return {"type": "ptracer"}
