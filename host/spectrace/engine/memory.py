"""The device memory a render needs, compared with what the device offers before anything is allocated.

A render allocates the scene's read-only arrays (BVH, triangles, materials, lights, spectra, ...), the render
parameters, and per pixel the film, the ray counts and (when asked for) the spectral bands. OpenCL devices limit
both the total (CL_DEVICE_GLOBAL_MEM_SIZE) and each single buffer (CL_DEVICE_MAX_MEM_ALLOC_SIZE).
"""

import dataclasses
from dataclasses import dataclass

import numpy as np

from spectrace.core.contract import RENDER_PARAMS_DTYPE
from spectrace.core.limits import FILM_BYTES_PER_PIXEL, RAY_COUNT_BYTES_PER_PIXEL, format_bytes
from spectrace.device import Device
from spectrace.engine.scene_buffers import SceneBuffers
from spectrace.errors import SpectraceError

SPECTRAL_BAND_BYTES = 4  # one float32 sum per band and pixel


@dataclass(frozen=True)
class DeviceMemoryNeed:
    """Bytes of every device buffer of a render, by name."""

    buffers: dict[str, int]

    @property
    def total_bytes(self) -> int:
        return sum(self.buffers.values())

    @property
    def largest(self) -> tuple[str, int]:
        name = max(self.buffers, key=lambda buffer: self.buffers[buffer])
        return name, self.buffers[name]

    def summary(self) -> str:
        """'film 4.0 GiB, ray counts 1.0 GiB, scene 1.2 MiB': the per-pixel buffers, then the scene as one."""
        per_pixel = {k: v for k, v in self.buffers.items() if not k.startswith("scene ")}
        scene = sum(v for k, v in self.buffers.items() if k.startswith("scene "))
        parts = [f"{name} {format_bytes(size)}" for name, size in per_pixel.items()]
        return ", ".join(parts + [f"scene {format_bytes(scene)}"])


def scene_arrays(buffers: SceneBuffers) -> dict[str, np.ndarray]:
    """Every array of the scene that goes to the device, by name."""
    arrays = {}
    for field in dataclasses.fields(buffers):
        value = getattr(buffers, field.name)
        if isinstance(value, np.ndarray):
            arrays["bvh nodes" if field.name == "nodes" else field.name.replace("_", " ")] = value
    return arrays


def device_memory_need(
    buffers: SceneBuffers,
    pixel_count: int,
    spectral_bins: int = 0,
    response_channels: int = 0,
    aovs: bool = False,
) -> DeviceMemoryNeed:
    need = {
        "film": pixel_count * FILM_BYTES_PER_PIXEL,
        "ray counts": pixel_count * RAY_COUNT_BYTES_PER_PIXEL,
        # allocated even without bands or channels (one float), since the kernel always takes the argument
        "spectral bands": max(pixel_count * spectral_bins, 1) * SPECTRAL_BAND_BYTES,
        "response channels": max(pixel_count * response_channels, 1) * SPECTRAL_BAND_BYTES,
        "scene render parameters": RENDER_PARAMS_DTYPE.itemsize,
        # twelve floats per pixel with AOVs (kernels/aov.cl), else one float4 for the argument
        "AOV sums": pixel_count * 48 if aovs else 16,
    }
    need.update({f"scene {name}": array.nbytes for name, array in scene_arrays(buffers).items()})
    return DeviceMemoryNeed(need)


def device_memory_limits(device: Device) -> tuple[int, int]:
    """(global memory, largest single buffer) in bytes, as the device reports them."""
    return int(device.cl_device.global_mem_size), int(device.cl_device.max_mem_alloc_size)


def check_device_memory(need: DeviceMemoryNeed, device: Device) -> None:
    """Raise SpectraceError, with the amounts, when the render cannot fit on `device`."""
    global_bytes, max_alloc_bytes = device_memory_limits(device)
    key = device.report.key
    advice = "lower --width/--height, or choose another device (`spectrace devices`, --device)"
    if need.total_bytes > global_bytes:
        raise SpectraceError(
            f"the render needs {format_bytes(need.total_bytes)} of device memory "
            f"({need.summary()}) but {key} has {format_bytes(global_bytes)}; {advice}"
        )
    name, size = need.largest
    if size > max_alloc_bytes:
        raise SpectraceError(
            f"the render's {name} buffer needs {format_bytes(size)} but {key} allows at most "
            f"{format_bytes(max_alloc_bytes)} per buffer ({need.summary()}); {advice}"
        )
