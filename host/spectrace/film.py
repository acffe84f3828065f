"""The film on the host: the device buffers the render kernels add pixel samples to (kernels/film.cl), clearing
them, reading them back into an `Image`, and their saved state, the whole of a render's progress that a checkpoint
stores (spectrace.engine.checkpoint writes and reads the file; what goes in it and back to the device is here).

Per pixel the film holds four float32 sums (X, Y, Z and the count of non-finite samples left out), a uint32 count
of rays traced, when asked for, `spectral_bins` float32 band sums over `spectral_range_nm`, one float32 sum per
channel of the film's response (spectrace.spectral.film_response: more observers, a measured sensor) and, when any AOV
is asked for, the AOV_FLOATS_PER_PIXEL float32 AOV sums of kernels/aov.cl (albedo XYZ and ΣY², normal, position
and depth, the emission sampled and expected).
Together with the number of samples per pixel added so far they are the entire state of a render: the samplers are
counter-based and every pixel adds its samples in sample order, so restoring them continues the render bit for bit.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pyopencl as cl

from spectrace.aovs import AOV_FLOATS_PER_PIXEL, aov_images, with_companions
from spectrace.core import limits
from spectrace.device import Device
from spectrace.engine.memory import SPECTRAL_BAND_BYTES
from spectrace.engine.opencl_errors import translate_opencl_errors
from spectrace.errors import SpectraceError
from spectrace.image import Image, SpectralBands
from spectrace.spectral.film_response import WAVELENGTH_LIMITS_NM, FilmResponse

SPECTRAL_LIMITS_NM = (360.0, 830.0)  # the wavelengths the renders sample
# Saved-state buffers: element type, and elements per pixel (None: a positive whole number of them, the bands).
STATE_LAYOUT = {
    "film": (np.float32, 4),
    "ray_counts": (np.uint32, 1),
    "spectral_film": (np.float32, None),
    "aov_film": (np.float32, AOV_FLOATS_PER_PIXEL),
    "response_film": (np.float32, None),
}


@dataclass
class RenderState:
    """The film's accumulation buffers (host copies, by name) and how many samples per pixel they hold."""

    samples_done: int
    render_seconds: float
    buffers: dict[str, np.ndarray]


def spectral_range(scene) -> tuple[float, float]:
    """The wavelengths a scene's spectral bands span by default: its film's (film.wavelengths), the range its samples
    are drawn from, so no band lies where no sample falls and none of the film's range goes without a band."""
    response = getattr(scene, "film_response", None)
    lo, hi = response.wavelengths if response is not None else SPECTRAL_LIMITS_NM
    return float(lo), float(hi)


def spectral_bins_problem(bins: int, range_nm: tuple[float, float]) -> str | None:
    """Why `bins` equal bands cannot span `range_nm`, or None: at most one band per nanometre of the 1 nm grid the
    spectra are tabulated on (its nodes: hi - lo + 1), as 471 bands over the default 360-830 nm."""
    lo, hi = range_nm
    most = int(hi - lo) + 1
    if bins > most:
        return (
            f"{bins} bands over the film's {lo:g}-{hi:g} nm would be narrower than the 1 nm grid the spectra are "
            f"tabulated on: give at most {most} (film.wavelengths sets the range)"
        )
    return None


def spectral_defines(bins: int, range_nm: tuple[float, float]) -> dict[str, int | float]:
    """Kernel defines that make kernels/film.cl accumulate `bins` equal bands over `range_nm` (none for 0 bins)."""
    if bins <= 0:
        return {}
    lo, hi = range_nm
    if not (WAVELENGTH_LIMITS_NM[0] <= lo < hi <= WAVELENGTH_LIMITS_NM[1]):
        raise SpectraceError(
            f"spectral range must lie within {WAVELENGTH_LIMITS_NM[0]:g}-{WAVELENGTH_LIMITS_NM[1]:g} nm, got {lo}-{hi}"
        )
    if problem := spectral_bins_problem(bins, range_nm):
        raise SpectraceError(problem, where="--spectral-bins")
    return {"SPECTRAL_BINS": int(bins), "SPECTRAL_MIN_NM": float(lo), "SPECTRAL_MAX_NM": float(hi)}


# A render fails, rather than give its image, when at least this fraction of its samples were NaN or infinite and
# dropped: the image then holds less than half of the light it should, wherever the rest would have gone, so it is no
# picture of the scene (an image of every sample dropped is black). A few dropped samples (a rare overflow on a long
# path) only warn. The cause is an input whose numbers overflow 32-bit floats or divide by zero.
DROPPED_FAIL_FRACTION = 0.5
# An emitter's radiance, times the CMFs over the wavelength pdf (up to about 1e3 together) and a path's throughput,
# overflows 32-bit floats (3.4e38) from about here on: the likeliest input when samples are dropped.
_OVERFLOWING_EMISSION = 1e30


def dropped_samples_problem(dropped: int, samples: int, scene=None) -> str | None:
    """Why a render of `samples` samples, `dropped` of them non-finite, has no image to give (see
    DROPPED_FAIL_FRACTION), naming the scene's likeliest input at fault; or None."""
    if samples <= 0 or dropped < DROPPED_FAIL_FRACTION * samples:
        return None
    share = "every one" if dropped >= samples else f"{dropped} ({100.0 * dropped / samples:.0f} %)"
    cause = likely_non_finite_input(scene) if scene is not None else None
    cause = cause or "look for numbers in the scene that overflow 32-bit floats (above about 1e38) or divide by zero"
    source = f" of {scene.source}" if scene is not None and getattr(scene, "source", None) else ""
    return (
        f"{share} of the render's {samples} samples{source} came out NaN or infinite and was dropped, so the image "
        f"would be black or too dark; {cause}"
    )


def likely_non_finite_input(scene) -> str | None:
    """The input of `scene` that most likely makes its samples non-finite, as a phrase, or None: a pixel filter or a
    film response whose device numbers are not finite, else an emitter bright enough to overflow 32-bit floats."""
    pixel_filter = getattr(scene, "pixel_filter", None)
    if pixel_filter is not None:
        with np.errstate(all="ignore"):
            try:
                numbers = np.concatenate([pixel_filter.device_shape(), pixel_filter.device_cdf()])
            except (ArithmeticError, ValueError):
                numbers = np.array([np.nan])
        if not np.all(np.isfinite(numbers)):
            return f"the pixel filter (film.filter, {pixel_filter.type}) has no finite weights"
    response = getattr(scene, "film_response", None)
    if response is not None and not response.is_default:
        with np.errstate(all="ignore"):
            table = response.device_table()
        if not np.all(np.isfinite(table)):
            return "the film's observers or sensor have no finite wavelength pdf over film.wavelengths"
    brightest, name = 0.0, ""
    for shape in getattr(scene, "shapes", ()):
        if shape.emitter is not None and np.size(shape.emitter.radiance.values):
            peak = float(np.max(np.abs(shape.emitter.radiance.values)))
            if not peak <= brightest:
                brightest, name = peak, f"the emitter of shape '{shape.name}'"
    for index, light in enumerate(getattr(scene, "lights", ())):
        scale = float(getattr(light, "scale", 1.0))
        for value in vars(light).values() if hasattr(light, "__dict__") else ():
            array = getattr(value, "values", value)
            if isinstance(array, np.ndarray) and array.size and array.dtype.kind == "f":
                with np.errstate(over="ignore"):
                    peak = float(np.max(np.abs(array))) * (scale if value is getattr(light, "rgb", None) else 1.0)
                if not peak <= brightest:
                    brightest, name = peak, f"light {index} ({type(light).__name__})"
    if not brightest <= _OVERFLOWING_EMISSION:
        return f"{name} reaches {brightest:.3g} W/(m² sr nm), which overflows 32-bit floats on the way to the film"
    return None


def state_problem(state: RenderState, width: int, height: int) -> str | None:
    """Why `state` cannot be the saved state of a width x height film, or None (any number of spectral bands and
    response channels)."""
    if not 0 <= state.samples_done <= limits.MAX_SPP:
        return f"sample count {state.samples_done} is outside 0..{limits.MAX_SPP}"
    if not (np.isfinite(state.render_seconds) and state.render_seconds >= 0):
        return f"render time {state.render_seconds} s is not a finite non-negative number"
    pixels = width * height
    for name in ("film", "ray_counts"):
        if name not in state.buffers:
            return f"the {name} buffer is missing"
    for name, array in state.buffers.items():
        if name not in STATE_LAYOUT:
            return f"unknown buffer '{name}'"
        dtype, per_pixel = STATE_LAYOUT[name]
        shape = (pixels, per_pixel) if per_pixel and per_pixel > 1 else (pixels,)
        if per_pixel is None:
            fits = array.ndim == 1 and array.size > 0 and array.size % pixels == 0
            needs = f"a positive multiple of {pixels} values"
        else:
            fits = array.shape == shape
            needs = f"shape {shape}"
        if array.dtype != dtype or not fits:
            return (
                f"the {name} buffer is {array.dtype} of shape {array.shape}; a {width}x{height} "
                f"film needs {np.dtype(dtype)} of {needs}"
            )
        if array.dtype.kind == "f" and not np.isfinite(array).all():
            return f"the {name} buffer holds {int((~np.isfinite(array)).sum())} NaN or infinite values"
    return None


def state_image(
    state: RenderState,
    width: int,
    height: int,
    spectral_range_nm: tuple[float, float],
    seed: int,
    device: str,
    exposure: float = 0.0,
    extra: dict | None = None,
    aovs: tuple[str, ...] | list[str] = (),
    albedo_scale: np.ndarray | None = None,
    response: FilmResponse | None = None,
) -> Image:
    """The image of a saved state: the mean of its samples per pixel, labelled with how it was made (a film's own
    image, or one merged on the host from tiles rendered elsewhere, spectrace.engine.tiles). `aovs` names the AOVs
    to make from its AOV sums, whose albedo channels `albedo_scale` (the film's CMF weights) turns into means;
    `response` the film's observers or sensor, whose channels it makes from the response sums."""
    film, rays = state.buffers["film"], state.buffers["ray_counts"]
    count = max(state.samples_done, 1)
    xyz = (film[:, :3] / np.float32(count)).reshape(height, width, 3)
    spectral = None
    if "spectral_film" in state.buffers:
        bands = state.buffers["spectral_film"].reshape(height, width, -1)
        lo, hi = spectral_range_nm
        spectral = SpectralBands(np.linspace(lo, hi, bands.shape[2] + 1), bands / np.float32(count))
    channels: dict[str, np.ndarray] = {}
    if response is not None and not response.is_default:
        sums = state.buffers.get("response_film", np.zeros(0, np.float32))  # absent: a film without channels
        responses = sums.reshape(height, width, -1) / np.float32(count)
        xyz, channels = response.outputs(xyz, responses)
    images = {}
    if aovs:
        scale = np.ones(3, np.float32) if albedo_scale is None else albedo_scale
        every = aov_images(state.buffers["aov_film"], film, state.samples_done, scale, (height, width))
        images = {name: every[name] for name in with_companions(aovs)}
    return Image(
        aovs=images,
        channels=channels,
        spectral=spectral,
        xyz=xyz,
        spp=state.samples_done,
        seed=seed,
        device=device,
        render_seconds=state.render_seconds,
        dropped_samples=int(film[:, 3].astype(np.float64).sum()),  # float32 would round totals above 2^24
        rays_traced=int(rays.astype(np.uint64).sum()),
        exposure=exposure,
        extra=extra or {},
    )


class Film:
    """The device film of one render and the count of samples per pixel it holds."""

    def __init__(
        self,
        device: Device,
        width: int,
        height: int,
        spectral_bins: int = 0,
        spectral_range_nm: tuple[float, float] = SPECTRAL_LIMITS_NM,
        aovs: Sequence[str] = (),
        albedo_scale: np.ndarray | None = None,
        response: FilmResponse | None = None,
    ):
        """aovs: names from AOV_NAMES kept beside the image (their kernels built with aov_defines(aovs));
        albedo_scale: albedo_channel_scale of the render's CMF table."""
        self.device = device
        self.aovs = tuple(aovs)
        self.albedo_scale = np.ones(3, np.float32) if albedo_scale is None else np.asarray(albedo_scale, np.float32)
        self.response = response or FilmResponse()
        self.response_channels = len(self.response.channel_names)
        self.width = width
        self.height = height
        self.pixel_count = width * height
        self.spectral_bins = spectral_bins
        self.spectral_range_nm = spectral_range_nm
        ctx = device.context
        rw = cl.mem_flags.READ_WRITE
        self.xyz_buffer = cl.Buffer(ctx, rw, self.pixel_count * limits.FILM_BYTES_PER_PIXEL)
        self.ray_count_buffer = cl.Buffer(ctx, rw, self.pixel_count * limits.RAY_COUNT_BYTES_PER_PIXEL)
        # Allocated even without bands (one float), since the kernels always take the argument.
        self.spectral_buffer = cl.Buffer(ctx, rw, max(self.pixel_count * spectral_bins, 1) * SPECTRAL_BAND_BYTES)
        # Likewise one float4 without AOVs.
        aov_floats = self.pixel_count * AOV_FLOATS_PER_PIXEL if self.aovs else 4
        self.aov_buffer = cl.Buffer(ctx, rw, aov_floats * 4)
        self.response_buffer = cl.Buffer(ctx, rw, max(self.pixel_count * self.response_channels, 1) * 4)
        self.samples_done = 0
        self.render_seconds = 0.0
        self.reset()

    @translate_opencl_errors("clearing the film")
    def reset(self) -> None:
        queue = self.device.queue
        cl.enqueue_fill_buffer(queue, self.xyz_buffer, np.zeros(1, np.float32), 0, self.xyz_buffer.size)
        cl.enqueue_fill_buffer(queue, self.ray_count_buffer, np.zeros(1, np.uint32), 0, self.ray_count_buffer.size)
        cl.enqueue_fill_buffer(queue, self.spectral_buffer, np.zeros(1, np.float32), 0, self.spectral_buffer.size)
        cl.enqueue_fill_buffer(queue, self.aov_buffer, np.zeros(1, np.float32), 0, self.aov_buffer.size)
        cl.enqueue_fill_buffer(queue, self.response_buffer, np.zeros(1, np.float32), 0, self.response_buffer.size)
        queue.finish()
        self.samples_done = 0
        self.render_seconds = 0.0

    def add_pass(self, sample_count: int, seconds: float) -> None:
        """Record a finished pass that added `sample_count` samples to every pixel in `seconds`."""
        self.render_seconds += seconds
        self.samples_done += sample_count

    @translate_opencl_errors("reading the film")
    def read(self) -> tuple[np.ndarray, np.ndarray]:
        """(pixels, 4) float32 sums of X, Y, Z and dropped samples, and (pixels,) uint32 rays traced."""
        film = np.empty((self.pixel_count, 4), np.float32)
        rays = np.empty(self.pixel_count, np.uint32)
        cl.enqueue_copy(self.device.queue, film, self.xyz_buffer)
        cl.enqueue_copy(self.device.queue, rays, self.ray_count_buffer)
        self.device.queue.finish()
        return film, rays

    @translate_opencl_errors("reading the spectral film")
    def read_spectral(self) -> np.ndarray:
        """(height, width, bins) band sums; divide by samples_done for the band-averaged radiance."""
        bands = np.empty(self.pixel_count * self.spectral_bins, np.float32)
        cl.enqueue_copy(self.device.queue, bands, self.spectral_buffer)
        self.device.queue.finish()
        return bands.reshape(self.height, self.width, self.spectral_bins)

    @translate_opencl_errors("reading the AOV film")
    def read_aovs(self) -> np.ndarray:
        """(pixels, 12) AOV sums (kernels/aov.cl's layout); divide by samples_done for the means."""
        sums = np.empty((self.pixel_count, AOV_FLOATS_PER_PIXEL), np.float32)
        cl.enqueue_copy(self.device.queue, sums, self.aov_buffer)
        self.device.queue.finish()
        return sums

    @translate_opencl_errors("reading the response film")
    def read_responses(self) -> np.ndarray:
        """(height, width, channels) response sums; divide by samples_done for the means."""
        sums = np.empty(self.pixel_count * self.response_channels, np.float32)
        cl.enqueue_copy(self.device.queue, sums, self.response_buffer)
        self.device.queue.finish()
        return sums.reshape(self.height, self.width, self.response_channels)

    def image(self, seed: int, device: str, exposure: float = 0.0, extra: dict | None = None) -> Image:
        """The mean of the samples so far per pixel, labelled with how it was made."""
        return state_image(
            self.save_state(),
            self.width,
            self.height,
            self.spectral_range_nm,
            seed,
            device,
            exposure,
            extra,
            aovs=self.aovs,
            albedo_scale=self.albedo_scale,
            response=self.response,
        )

    def _state_buffers(self) -> dict[str, cl.Buffer]:
        """The device buffers that accumulate samples: with samples_done, the whole state of the render."""
        buffers = {"film": self.xyz_buffer, "ray_counts": self.ray_count_buffer}
        if self.spectral_bins > 0:
            buffers["spectral_film"] = self.spectral_buffer
        if self.aovs:
            buffers["aov_film"] = self.aov_buffer
        if self.response_channels > 0:
            buffers["response_film"] = self.response_buffer
        return buffers

    def save_state(self) -> RenderState:
        """Host copies of the accumulation buffers and the sample count: restore_state() on the film of a render of
        the same scene and seed continues this render exactly."""
        film, rays = self.read()
        buffers = {"film": film, "ray_counts": rays}
        if self.spectral_bins > 0:
            buffers["spectral_film"] = self.read_spectral().reshape(-1)
        if self.aovs:
            buffers["aov_film"] = self.read_aovs()
        if self.response_channels > 0:
            buffers["response_film"] = self.read_responses().reshape(-1)
        return RenderState(self.samples_done, self.render_seconds, buffers)

    def _pixel_bytes(self, name: str, buffer: cl.Buffer) -> tuple[np.dtype, int]:
        """A saved-state buffer's element type and its values per pixel."""
        dtype = np.dtype(STATE_LAYOUT[name][0])
        return dtype, buffer.size // (self.pixel_count * dtype.itemsize)

    @translate_opencl_errors("clearing part of the film")
    def reset_pixels(self, begin: int, end: int) -> None:
        """Start the render again for pixels [begin, end) only (a tile of a split render, spectrace.engine.tiles):
        clearing a whole large film for each small tile would cost more than the tile."""
        queue = self.device.queue
        for name, buffer in self._state_buffers().items():
            dtype, per_pixel = self._pixel_bytes(name, buffer)
            row = per_pixel * dtype.itemsize
            cl.enqueue_fill_buffer(queue, buffer, np.zeros(1, dtype), begin * row, (end - begin) * row)
        queue.finish()
        self.samples_done = 0
        self.render_seconds = 0.0

    @translate_opencl_errors("reading part of the film")
    def read_state_pixels(self, begin: int, end: int) -> dict[str, np.ndarray]:
        """Host copies of every accumulation buffer's values of pixels [begin, end), as (end - begin, values per
        pixel) arrays by buffer name: a tile of a split render (spectrace.engine.tiles), read without the rest."""
        queue = self.device.queue
        pixels = {}
        for name, buffer in self._state_buffers().items():
            dtype, per_pixel = self._pixel_bytes(name, buffer)
            values = np.empty((end - begin, per_pixel), dtype)
            cl.enqueue_copy(queue, values, buffer, src_offset=begin * per_pixel * dtype.itemsize)
            pixels[name] = values
        queue.finish()
        return pixels

    @translate_opencl_errors("restoring the film from a checkpoint")
    def restore_state(self, state: RenderState, where: str | None = None) -> None:
        """Upload a saved state of a film of this size (one state_problem passes, as every checkpoint read has):
        what is left to check is that it holds exactly this film's buffers, the spectral bands at this film's
        band count."""
        targets = self._state_buffers()
        if set(state.buffers) != set(targets):
            raise SpectraceError(
                f"the saved state holds {', '.join(sorted(state.buffers)) or 'nothing'} but this "
                f"render accumulates {', '.join(sorted(targets))}",
                where=where,
            )
        for name, array in state.buffers.items():
            if array.nbytes != targets[name].size:
                raise SpectraceError(
                    f"saved {name} holds {array.nbytes} bytes, this render needs {targets[name].size}", where=where
                )
        queue = self.device.queue
        for name, array in state.buffers.items():
            cl.enqueue_copy(queue, targets[name], np.ascontiguousarray(array))
        queue.finish()
        self.samples_done = int(state.samples_done)
        self.render_seconds = float(state.render_seconds)
