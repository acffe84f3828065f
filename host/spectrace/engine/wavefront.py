"""The path integrator as a wavefront: path states in device memory, one launch per path segment.

Each pass starts one path per pixel (`wavefront_start`), then launches `wavefront_advance` over the queue of live
paths until it is empty; a launch moves every live path one segment on, and a path that ends is added to the film
and replaced by its pixel's next sample (kernels/wavefront_pass.cl). The image is the megakernel's: the same
per-segment function, the same per-pixel order of additions to the film (and to the AOV sums). Which kernel shape
is faster was measured (docs/devices.md, "Kernel shape (measured)"); the megakernel is the default, this one is
`--kernel wavefront`.
"""

import time

import numpy as np
import pyopencl as cl

from spectrace.device import Device
from spectrace.engine.launch import launch_shape, wavefront_work_group
from spectrace.engine.memory import check_device_memory, device_memory_need
from spectrace.engine.opencl_errors import translate_opencl_errors
from spectrace.engine.renderer import Renderer
from spectrace.engine.scene_buffers import render_params
from spectrace.errors import SpectraceError
from spectrace.scene.model import Scene

KERNEL_SHAPES = ("megakernel", "wavefront")
QUEUE_ENTRY_BYTES = 4  # one int (a pixel index) per live path


class WavefrontRenderer(Renderer):
    def _check_scene(self, scene: Scene) -> None:
        if scene.integrator != "path":
            raise SpectraceError(
                f"the wavefront kernel runs the path integrator only, not {scene.integrator!r}",
                where=str(scene.source) if scene.source else None,
            )

    def _allocate(self, spectral_bins: int) -> None:
        ctx = self.device.context
        slot_size = np.zeros(1, np.uint32)
        size_buffer = cl.Buffer(ctx, cl.mem_flags.WRITE_ONLY, 4)
        cl.Kernel(self.program, "wavefront_slot_size")(self.device.queue, (1,), None, size_buffer)
        cl.enqueue_copy(self.device.queue, slot_size, size_buffer)
        need = device_memory_need(
            self.buffers, self.pixel_count, spectral_bins, self.film.response_channels, aovs=bool(self.scene.aovs)
        )
        need.buffers["path slots"] = self.pixel_count * int(slot_size[0])
        need.buffers["path queues"] = 2 * self.pixel_count * QUEUE_ENTRY_BYTES
        check_device_memory(need, self.device)
        self._slots = cl.Buffer(ctx, cl.mem_flags.READ_WRITE, need.buffers["path slots"])
        self._queues = [cl.Buffer(ctx, cl.mem_flags.READ_WRITE, self.pixel_count * QUEUE_ENTRY_BYTES) for _ in range(2)]
        self._queue_lengths = [cl.Buffer(ctx, cl.mem_flags.READ_WRITE, 4) for _ in range(2)]
        self.work_group = wavefront_work_group(self.device)

    def _program_file(self, scene: Scene) -> str:
        return "integrator_path_wavefront.cl"

    def _create_kernels(self) -> cl.Kernel:
        self._start_kernel = cl.Kernel(self.program, "wavefront_start")
        return cl.Kernel(self.program, "wavefront_advance")

    @translate_opencl_errors("running a render pass")
    def run_pass(self, sample_count: int) -> None:
        queue = self.device.queue
        params = render_params(self.scene, self.buffers, self.samples_done, sample_count)
        zero = np.zeros(1, np.int32)
        live = np.zeros(1, np.int32)
        start = time.perf_counter()
        cl.enqueue_copy(queue, self._params, params)
        cl.enqueue_copy(queue, self._queue_lengths[0], zero)
        film = self.film
        self._start_kernel(
            queue,
            *launch_shape(self.pixel_count, self.work_group),
            self._params,
            film.table_buffer,
            film.xyz_buffer,
            film.spectral_buffer,
            film.response_buffer,
            film.aov_buffer,
            self._slots,
            self._queues[0],
            self._queue_lengths[0],
        )
        current = 0
        while True:
            cl.enqueue_copy(queue, live, self._queue_lengths[current])  # blocking: sizes the next launch
            if live[0] == 0:
                break
            following = 1 - current
            cl.enqueue_copy(queue, self._queue_lengths[following], zero)
            self.kernel.set_args(
                self._params,
                *self._scene,
                *film.kernel_arguments(),
                self._slots,
                self._queues[current],
                self._queue_lengths[current],
                self._queues[following],
                self._queue_lengths[following],
            )
            cl.enqueue_nd_range_kernel(queue, self.kernel, *launch_shape(int(live[0]), self.work_group))
            current = following
        queue.finish()
        film.add_pass(sample_count, time.perf_counter() - start)


def make_renderer(scene: Scene, device: Device | str | None = None, kernel: str = "megakernel", **options) -> Renderer:
    """A renderer of the chosen kernel shape (KERNEL_SHAPES)."""
    if kernel not in KERNEL_SHAPES:
        raise SpectraceError(f"unknown kernel shape {kernel!r}; choose one of {', '.join(KERNEL_SHAPES)}")
    return (WavefrontRenderer if kernel == "wavefront" else Renderer)(scene, device, **options)
