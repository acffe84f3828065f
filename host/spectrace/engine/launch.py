"""How kernels are launched on each kind of device: work-group sizes chosen by measurement, not by the runtime.

Intel's CPU runtime (2026.2) may vectorise a work-group of 16 or more work-items 16 wide. On the path-tracing
megakernel, whose work-items diverge after the first bounce, that ran 3.6x slower than groups of at most 8, which it
runs narrower (Cornell box, 256x256, 4 spp, 2 cores: 0.37 vs 1.34 M samples/s; PoCL 3.1 on the same machine: 1.11
to 1.20 M samples/s whatever the size). Since the kernels grew media and more materials its vectoriser leaves the
path tracer scalar at any size (forcing 16 wide is again 3.6x slower), so groups of 8 cost nothing and keep that
from coming back (docs/devices.md, "Kernel shape (measured)"). The 16-wide build of the sensor kernel also returned
wrong values in lanes 12-15 (PoCL is right on the same source), so sensors run in groups of one there.

PoCL compiles a kernel anew for every work-group size it runs it with (each path-tracing megakernel ~5.5 CPU-s),
and left to choose, it picks a size from the number of work-items, so every film size was one more compile. Its
render passes run in groups of a fixed size instead: on the Cornell box (256x256, 4 spp, depth 8, PoCL 3.1, 7
alternating repeats) groups of 32, 64, 128 and PoCL's own choice took 0.452, 0.447, 0.448 and 0.454 CPU-s a pass.
"""

import math

from spectrace.device import Device
from spectrace.device.discovery import POCL_PYPI, POCL_SYSTEM

INTEL_CPU_RENDER_GROUP = 8
POCL_RENDER_GROUP = 32
WAVEFRONT_GROUP = 32  # wavefront groups of 8, 16 and 32 ran within 5% of each other on PoCL and Intel's runtime


def _is_intel_cpu(device: Device) -> bool:
    return "intel" in device.report.runtime.lower() and device.report.device_type == "CPU"


def is_pocl(device: Device) -> bool:
    return device.report.runtime in (POCL_SYSTEM[1], POCL_PYPI[1])


def render_work_group(device: Device) -> int | None:
    """Work-items per group for render passes; None lets the runtime choose."""
    if _is_intel_cpu(device):
        return INTEL_CPU_RENDER_GROUP
    return POCL_RENDER_GROUP if is_pocl(device) else None


def wavefront_work_group(device: Device) -> int:
    """Work-items per group for the wavefront's launches. Always fixed: their sizes follow the number of live paths,
    and PoCL compiles the kernel anew for every local size it would pick for them."""
    return render_work_group(device) or WAVEFRONT_GROUP


def meter_work_group(device: Device, items: int) -> int | None:
    """Work-items per group for the sensor kernel, which has no bounds check: a group that divides `items` on
    PoCL, so that a few sizes serve every count (and so a few compiles)."""
    if _is_intel_cpu(device):
        return 1
    return math.gcd(items, POCL_RENDER_GROUP) if is_pocl(device) else None


def launch_shape(items: int, group: int | None) -> tuple[tuple[int], tuple[int] | None]:
    """(global, local) sizes covering `items` work-items; kernels ignore the padding items past `items`."""
    if group is None:
        return (items,), None
    return (-(-items // group) * group,), (group,)
