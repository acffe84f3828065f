"""The film of one render as the engine sees it: `FilmSetup`, the one object it asks for the film's kernel
defines, its device buffers (`Film`) and their kernel arguments, and which turns the film's sums back into an
`Image`. The engine never looks inside: what the film integrates against (colour matching functions, several of
them, a sensor, spectral bands, AOVs) is the film's own business, so a new kind of film output changes this
package and kernels/film.cl, not the renderer."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pyopencl as cl

from spectrace.core import limits
from spectrace.core.contract import TEXEL_BANDS, TEXEL_RGB, TEXEL_SIGMOID
from spectrace.device import Device
from spectrace.engine.memory import SPECTRAL_BAND_BYTES
from spectrace.engine.opencl_errors import translate_opencl_errors
from spectrace.errors import SpectraceError
from spectrace.film.aovs import albedo_channel_scale, aov_defines, aov_floats_per_pixel
from spectrace.film.image import Image
from spectrace.film.response import FilmResponse
from spectrace.film.state import (
    STATE_LAYOUT,
    RenderState,
    spectral_defines,
    spectral_range,
    state_image,
)
from spectrace.spectral.grid import GRID_MAX_NM, GRID_MIN_NM


@dataclass(frozen=True)
class FilmSetup:
    """A width x height film responding as `response`, keeping `spectral_bins` bands over `spectral_range_nm` and
    the AOVs `aovs`; `table` is the film table the kernels read as `cmf` (kernels/film.cl)."""

    width: int
    height: int
    response: FilmResponse
    table: np.ndarray
    spectral_bins: int = 0
    spectral_range_nm: tuple[float, float] = (360.0, 830.0)
    aovs: tuple[str, ...] = ()

    @classmethod
    def of(
        cls,
        scene,
        scene_cmf: np.ndarray,
        spectral_bins: int = 0,
        spectral_range_nm: tuple[float, float] | None = None,
    ) -> FilmSetup:
        """The film of `scene`. `scene_cmf`: the scene buffers' CIE 1931 table, which is the default film's own
        (other films bring theirs, whose first rows are the film's own XYZ curves on its grid).
        `spectral_range_nm` None: the film's wavelengths, which the samples span."""
        response = scene.film_response
        table = scene_cmf if response.is_default else response.device_table()
        return cls(
            scene.width,
            scene.height,
            response,
            table,
            spectral_bins,
            spectral_range(scene) if spectral_range_nm is None else spectral_range_nm,
            tuple(scene.aovs),
        )

    @property
    def response_channels(self) -> int:
        return len(self.response.channel_names)

    @property
    def albedo_scale(self) -> np.ndarray:
        """The albedo AOV's channel scale (spectrace.film.aovs) for the film's XYZ rows of the table."""
        return albedo_channel_scale(self.table[: self.response.grid_nm.size])

    @property
    def beyond_the_visible(self) -> bool:
        """The film's wavelengths reach past the common grid (GRID_MIN_NM-GRID_MAX_NM, the visible)."""
        lo, hi = self.response.wavelengths
        return self.response.has_own_grid and (lo < GRID_MIN_NM or hi > GRID_MAX_NM)

    def check_scene_spectra(self, textures: np.ndarray, light_images: bool, source: object = None) -> None:
        """Refuse a scene whose spectra stop short of a film range beyond the visible (the spectrum table refuses
        tabulated spectra that do). The textures' RGB texels (`textures`: the scene buffers' texture rows) are
        sigmoids of λ and the emitter pictures' (`light_images`) weight basis spectra from the table, so they hold
        on any range inside the visible; beyond it they follow the rule of RGB spectra (continued only with
        film.extend_rgb), and a spectral texture must have bands as far as the film goes."""
        if not self.beyond_the_visible:
            return
        lo, hi = self.response.wavelengths
        where = str(source) if source else None
        rgb = bool(np.any(np.isin(textures["texel_format"], (TEXEL_SIGMOID, TEXEL_RGB))))
        if (rgb or light_images) and not self.response.extend_rgb:
            raise SpectraceError(
                f"film.wavelengths {lo:g}-{hi:g} nm: textures and emitter pictures hold RGB colours, defined for the "
                f"visible ({GRID_MIN_NM:g}-{GRID_MAX_NM:g} nm) only; film.extend_rgb = true continues them (as it "
                "does RGB spectra)",
                where=where,
            )
        for texture in textures[textures["texel_format"] == TEXEL_BANDS]:
            first = float(texture["band_first_nm"])
            last = first + float(texture["band_step_nm"]) * (int(texture["channels"]) - 1)
            if (lo < GRID_MIN_NM and first > lo) or (hi > GRID_MAX_NM and last < hi):
                raise SpectraceError(
                    f"film.wavelengths {lo:g}-{hi:g} nm: a spectral texture's bands span {first:g}-{last:g} nm; beyond "
                    f"the visible the film's range needs measured bands",
                    where=where,
                )

    def defines(self) -> dict[str, int | float]:
        """Kernel defines of this film: its spectral bands, AOVs and response (none for the default film)."""
        return (
            spectral_defines(self.spectral_bins, self.spectral_range_nm)
            | aov_defines(self.aovs)
            | self.response.defines()
        )

    def write_params(self, params: np.ndarray) -> None:
        """Sets the film's run-time values in `params` (a RenderParams array of one): the sizes kernels/film.cl
        reads there rather than from build defines, so that one program serves every film of a kind."""
        lo, hi = self.spectral_range_nm
        params["spectral_bins"] = self.spectral_bins
        params["spectral_min_nm"] = lo
        params["spectral_max_nm"] = hi
        params["film_responses"] = self.response_channels

    def metadata(self) -> dict[str, str]:
        """What the film responded to, for the image's metadata (nothing for the default film)."""
        return self.response.metadata()

    def create(self, device: Device) -> Film:
        """The device film: its buffers allocated and cleared on `device` (a spectrace.device.Device)."""
        return Film(device, self)

    def image(
        self, state: RenderState, seed: int, device: str, exposure: float = 0.0, extra: dict | None = None
    ) -> Image:
        """The image of a saved state of this film (see spectrace.film.state.state_image)."""
        return state_image(
            state,
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


class Film:
    """The device film of one render (its FilmSetup's buffers on a device) and the count of samples per pixel it
    holds."""

    def __init__(self, device: Device, setup: FilmSetup):
        self.device = device
        self.setup = setup
        self.aovs = setup.aovs
        self.response = setup.response
        self.response_channels = setup.response_channels
        self.width = setup.width
        self.height = setup.height
        self.pixel_count = setup.width * setup.height
        self.spectral_bins = setup.spectral_bins
        self.spectral_range_nm = setup.spectral_range_nm
        ctx = device.context
        rw = cl.mem_flags.READ_WRITE
        self.table_buffer = cl.Buffer(
            ctx, cl.mem_flags.READ_ONLY | cl.mem_flags.COPY_HOST_PTR, hostbuf=np.ascontiguousarray(setup.table)
        )
        self.xyz_buffer = cl.Buffer(ctx, rw, self.pixel_count * limits.FILM_BYTES_PER_PIXEL)
        self.ray_count_buffer = cl.Buffer(ctx, rw, self.pixel_count * limits.RAY_COUNT_BYTES_PER_PIXEL)
        # Allocated even without bands (one float), since the kernels always take the argument.
        self.spectral_buffer = cl.Buffer(ctx, rw, max(self.pixel_count * self.spectral_bins, 1) * SPECTRAL_BAND_BYTES)
        # Likewise one float4 without AOVs.
        self.aov_floats_per_pixel = aov_floats_per_pixel(self.aovs)
        aov_floats = self.pixel_count * self.aov_floats_per_pixel if self.aovs else 4
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

    def kernel_arguments(self) -> tuple[cl.Buffer, ...]:
        """The film's arguments of a per-pixel pass kernel, in the order they follow the scene's
        (kernels/render_pass.cl's render_pass): the film table, XYZ sums, ray counts, bands, responses, AOVs."""
        return (
            self.table_buffer,
            self.xyz_buffer,
            self.ray_count_buffer,
            self.spectral_buffer,
            self.response_buffer,
            self.aov_buffer,
        )

    def add_pass(self, sample_count: int, seconds: float) -> None:
        """Record a finished pass that added `sample_count` samples to every pixel in `seconds`."""
        self.render_seconds += seconds
        self.samples_done += sample_count

    def _read(self, buffer: cl.Buffer, shape: tuple[int, ...], dtype: type = np.float32) -> np.ndarray:
        values: np.ndarray = np.empty(shape, dtype)
        cl.enqueue_copy(self.device.queue, values, buffer)
        self.device.queue.finish()
        return values

    @translate_opencl_errors("reading the film")
    def read(self) -> tuple[np.ndarray, np.ndarray]:
        """(pixels, 4) float32 sums of X, Y, Z and dropped samples, and (pixels,) uint32 rays traced."""
        return self._read(self.xyz_buffer, (self.pixel_count, 4)), self._read(
            self.ray_count_buffer, (self.pixel_count,), np.uint32
        )

    @translate_opencl_errors("reading the spectral film")
    def read_spectral(self) -> np.ndarray:
        """(height, width, bins) band sums; divide by samples_done for the band-averaged radiance."""
        return self._read(self.spectral_buffer, (self.height, self.width, self.spectral_bins))

    @translate_opencl_errors("reading the AOV film")
    def read_aovs(self) -> np.ndarray:
        """(pixels, floats per pixel) AOV sums (kernels/aov.cl's layout); divide by samples_done for the means."""
        return self._read(self.aov_buffer, (self.pixel_count, self.aov_floats_per_pixel))

    @translate_opencl_errors("reading the response film")
    def read_responses(self) -> np.ndarray:
        """(height, width, channels) response sums; divide by samples_done for the means."""
        return self._read(self.response_buffer, (self.height, self.width, self.response_channels))

    def image(self, seed: int, device: str, exposure: float = 0.0, extra: dict | None = None) -> Image:
        """The mean of the samples so far per pixel, labelled with how it was made."""
        return self.setup.image(self.save_state(), seed, device, exposure, extra)

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
