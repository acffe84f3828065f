"""Progressive rendering on an OpenCL device: upload the scene once, then run passes of samples into the film."""

import time
from collections.abc import Callable

import numpy as np
import pyopencl as cl

from spectrace.device import Device, open_device
from spectrace.errors import SpectraceError
from spectrace.geometry.bvh4 import traversal_defines
from spectrace.image import Image, SpectralBands
from spectrace.engine.checkpoint import RenderState
from spectrace.engine.device_types import SCENE_KERNEL_BUFFERS
from spectrace.engine.launch import launch_shape, render_work_group
from spectrace.engine.memory import check_device_memory, device_memory_need
from spectrace.engine.opencl_errors import translate_opencl_errors
from spectrace.engine.scene_buffers import SceneBuffers, build_scene_buffers, render_params
from spectrace.engine.scene_features import scene_feature_defines
from spectrace.scene import limits
from spectrace.scene.model import SAMPLER_TYPES, Scene

ProgressCallback = Callable[[int, int], None]  # (samples done, samples total)

# Aim for passes of about this long: short enough for a live progress bar and prompt Ctrl-C, long enough that
# launch overhead does not matter.
TARGET_PASS_SECONDS = 0.5

INTEGRATOR_PROGRAMS = {"path": "integrator_path.cl", "direct": "integrator_direct.cl"}


def sampler_defines(sampler: str) -> dict[str, int]:
    """Build defines selecting the sampler of kernels/rng.cl (the independent one needs none)."""
    if sampler not in SAMPLER_TYPES:
        raise SpectraceError(f"unknown sampler '{sampler}' (use {' or '.join(SAMPLER_TYPES)})")
    return {"SAMPLER_SOBOL": 1} if sampler == "sobol" else {}


def upload_scene(context: cl.Context, buffers: SceneBuffers) -> list[cl.Buffer]:
    """Read-only device copies of the scene's buffers in the order every scene kernel takes them after the
    RenderParams buffer (SCENE_KERNEL_BUFFERS; kernels/scene.cl's SCENE_KERNEL_PARAMS)."""
    flags = cl.mem_flags.READ_ONLY | cl.mem_flags.COPY_HOST_PTR
    return [cl.Buffer(context, flags, hostbuf=np.ascontiguousarray(getattr(buffers, name)))
            for name in SCENE_KERNEL_BUFFERS]


class Renderer:
    @translate_opencl_errors("setting up the render")
    def __init__(self, scene: Scene, device: Device | str | None = None, spectral_bins: int = 0,
                 spectral_range_nm: tuple[float, float] = (360.0, 830.0), specialise: bool = True):
        """spectral_bins > 0 also accumulates that many equal wavelength bands over spectral_range_nm (the band-
        averaged radiance per pixel, W/(m² sr nm)), for spectral EXR output. specialise=False builds the kernels
        that handle every scene instead of ones carrying only this scene's features (for comparisons)."""
        self.scene = scene
        problem = (limits.render_settings_problem(scene.width, scene.height, scene.spp)
                   or limits.scene_settings_problem(scene) or limits.scene_geometry_problem(scene))
        if problem:
            raise SpectraceError(problem, where=str(scene.source) if scene.source else None)
        self.device = device if isinstance(device, Device) else open_device(device)
        self.buffers: SceneBuffers = build_scene_buffers(scene)
        # Refuse before allocating anything: a failed allocation deep in the driver says far less.
        check_device_memory(device_memory_need(self.buffers, scene.width * scene.height, spectral_bins), self.device)
        self.spectral_bins = spectral_bins
        self.spectral_range_nm = spectral_range_nm
        defines = sampler_defines(scene.sampler) | traversal_defines()
        if specialise:
            defines |= scene_feature_defines(self.buffers)
        if spectral_bins > 0:
            lo, hi = spectral_range_nm
            if not (360.0 <= lo < hi <= 830.0):
                raise SpectraceError(f"spectral range must lie within 360-830 nm, got {lo}-{hi}")
            defines |= {"SPECTRAL_BINS": int(spectral_bins), "SPECTRAL_MIN_NM": float(lo), "SPECTRAL_MAX_NM": float(hi)}
        self.program = self.device.build_program(self._program_file(scene), defines=defines or None)
        self.kernel = self._create_kernels()
        # Work-items per group of the pass launches (None: the runtime's choice); `spectrace bench` varies it.
        self.work_group = render_work_group(self.device)
        ctx = self.device.context
        ro = cl.mem_flags.READ_ONLY | cl.mem_flags.COPY_HOST_PTR
        b = self.buffers
        self._params = cl.Buffer(ctx, cl.mem_flags.READ_ONLY, render_params(scene, self.buffers, 0, 0).nbytes)
        self._scene = upload_scene(ctx, b)
        self._cmf = cl.Buffer(ctx, ro, hostbuf=np.ascontiguousarray(b.cmf))
        self.pixel_count = scene.width * scene.height
        self._film = cl.Buffer(ctx, cl.mem_flags.READ_WRITE, self.pixel_count * 16)
        self._ray_counts = cl.Buffer(ctx, cl.mem_flags.READ_WRITE, self.pixel_count * 4)
        self._spectral_film = cl.Buffer(ctx, cl.mem_flags.READ_WRITE, max(self.pixel_count * spectral_bins, 1) * 4)
        self.samples_done = 0
        self.render_seconds = 0.0
        self.reset()

    def _program_file(self, scene: Scene) -> str:
        return INTEGRATOR_PROGRAMS[scene.integrator]

    def _create_kernels(self) -> cl.Kernel:
        return cl.Kernel(self.program, "render_pass")

    @translate_opencl_errors("clearing the film")
    def reset(self) -> None:
        queue = self.device.queue
        cl.enqueue_fill_buffer(queue, self._film, np.float32(0), 0, self.pixel_count * 16)
        cl.enqueue_fill_buffer(queue, self._ray_counts, np.uint32(0), 0, self.pixel_count * 4)
        cl.enqueue_fill_buffer(queue, self._spectral_film, np.float32(0), 0, self._spectral_film.size)
        queue.finish()
        self.samples_done = 0
        self.render_seconds = 0.0

    @translate_opencl_errors("running a render pass")
    def run_pass(self, sample_count: int) -> None:
        """Add `sample_count` samples per pixel, continuing the sample sequence where the last pass stopped."""
        queue = self.device.queue
        params = render_params(self.scene, self.buffers, self.samples_done, sample_count)
        start = time.perf_counter()
        cl.enqueue_copy(queue, self._params, params)
        self.kernel.set_args(self._params, *self._scene, self._cmf, self._film, self._ray_counts, self._spectral_film)
        global_size, local_size = launch_shape(self.pixel_count, self.work_group)
        cl.enqueue_nd_range_kernel(queue, self.kernel, global_size, local_size)
        queue.finish()
        self.render_seconds += time.perf_counter() - start
        self.samples_done += sample_count

    def render(self, spp: int | None = None, pass_spp: int | None = None,
               progress: ProgressCallback | None = None, should_stop: Callable[[], bool] | None = None) -> Image:
        """Render until `spp` samples per pixel (default: the scene's). Passes adapt their size to about
        TARGET_PASS_SECONDS unless pass_spp fixes it; the image does not depend on the pass sizes.
        `should_stop` is asked between passes; when it says True the image of the samples done so far is returned."""
        total = spp if spp is not None else self.scene.spp
        if problem := limits.spp_problem(total):
            raise SpectraceError(problem)
        chunk = pass_spp or 1
        while self.samples_done < total and not (should_stop is not None and should_stop()):
            count = min(chunk, total - self.samples_done)
            start = time.perf_counter()
            self.run_pass(count)
            elapsed = time.perf_counter() - start
            if pass_spp is None and elapsed > 0:
                chunk = max(1, min(4 * chunk, int(count * TARGET_PASS_SECONDS / elapsed)))
            if progress is not None:
                progress(self.samples_done, total)
        return self.image()

    @translate_opencl_errors("reading the film")
    def read_film(self) -> tuple[np.ndarray, np.ndarray]:
        film = np.empty((self.pixel_count, 4), np.float32)
        rays = np.empty(self.pixel_count, np.uint32)
        cl.enqueue_copy(self.device.queue, film, self._film)
        cl.enqueue_copy(self.device.queue, rays, self._ray_counts)
        self.device.queue.finish()
        return film, rays

    @translate_opencl_errors("reading the spectral film")
    def read_spectral_film(self) -> np.ndarray:
        """(height, width, bins) band sums; divide by samples_done for the band-averaged radiance."""
        bands = np.empty(self.pixel_count * self.spectral_bins, np.float32)
        cl.enqueue_copy(self.device.queue, bands, self._spectral_film)
        self.device.queue.finish()
        return bands.reshape(self.scene.height, self.scene.width, self.spectral_bins)

    def image(self) -> Image:
        film, rays = self.read_film()
        count = max(self.samples_done, 1)
        xyz = (film[:, :3] / np.float32(count)).reshape(self.scene.height, self.scene.width, 3)
        spectral = None
        if self.spectral_bins > 0:
            lo, hi = self.spectral_range_nm
            spectral = SpectralBands(np.linspace(lo, hi, self.spectral_bins + 1),
                                     self.read_spectral_film() / np.float32(count))
        return Image(
            spectral=spectral,
            xyz=xyz,
            spp=self.samples_done,
            seed=self.scene.seed,
            device=self.device.report.key,
            render_seconds=self.render_seconds,
            dropped_samples=int(film[:, 3].astype(np.float64).sum()),  # float32 would round totals above 2^24
            rays_traced=int(rays.astype(np.uint64).sum()),
            exposure=self.scene.exposure,
            extra={"max_depth": self.scene.max_depth, "width": self.scene.width, "height": self.scene.height,
                   "sampler": self.scene.sampler},
        )

    def _state_buffers(self) -> dict[str, cl.Buffer]:
        """The device buffers that accumulate samples: with samples_done, the whole state of the render."""
        buffers = {"film": self._film, "ray_counts": self._ray_counts}
        if self.spectral_bins > 0:
            buffers["spectral_film"] = self._spectral_film
        return buffers

    def save_state(self) -> RenderState:
        """Host copies of the accumulation buffers and the sample count: restore_state() on a renderer of the same
        scene and seed continues this render exactly (the sampler is counter-based; see render.checkpoint)."""
        film, rays = self.read_film()
        buffers = {"film": film, "ray_counts": rays}
        if self.spectral_bins > 0:
            buffers["spectral_film"] = self.read_spectral_film().reshape(-1)
        return RenderState(self.samples_done, self.render_seconds, buffers)

    @translate_opencl_errors("restoring the film from a checkpoint")
    def restore_state(self, state: RenderState, where: str | None = None) -> None:
        """Upload a saved state; it must hold exactly this renderer's buffers, sizes and types."""
        targets = self._state_buffers()
        if set(state.buffers) != set(targets):
            raise SpectraceError(f"the saved state holds {', '.join(sorted(state.buffers)) or 'nothing'} but this "
                                 f"render accumulates {', '.join(sorted(targets))}", where=where)
        expected_types = {"film": np.float32, "ray_counts": np.uint32, "spectral_film": np.float32}
        for name, array in state.buffers.items():
            if array.dtype != expected_types[name] or array.nbytes != targets[name].size:
                raise SpectraceError(f"saved {name} is {array.dtype} x {array.size}, this render needs "
                                     f"{np.dtype(expected_types[name])} of {targets[name].size} bytes", where=where)
        if not 0 <= state.samples_done <= limits.MAX_SPP:
            raise SpectraceError(f"saved sample count {state.samples_done} is out of range", where=where)
        queue = self.device.queue
        for name, array in state.buffers.items():
            cl.enqueue_copy(queue, targets[name], np.ascontiguousarray(array))
        queue.finish()
        self.samples_done = int(state.samples_done)
        self.render_seconds = float(state.render_seconds)
