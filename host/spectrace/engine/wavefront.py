"""The wavefront kernel shape: a renderer that runs its integrator's `wavefront` program (the path integrator's:
path states in device memory, one launch per path segment; spectrace.integrators.path). Which kernel shape is faster
was measured (docs/devices.md, "Kernel shape (measured)"); the megakernel is the default, this one is
`--kernel wavefront`.
"""

from spectrace.device import Device
from spectrace.engine.launch import wavefront_work_group
from spectrace.engine.renderer import Renderer
from spectrace.errors import SpectraceError
from spectrace.integrators import KERNEL_SHAPES
from spectrace.scene.model import Scene


class WavefrontRenderer(Renderer):
    KERNEL_SHAPE = "wavefront"

    def _work_group(self) -> int | None:
        return wavefront_work_group(self.device)


def make_renderer(scene: Scene, device: Device | str | None = None, kernel: str = "megakernel", **options) -> Renderer:
    """A renderer of the chosen kernel shape (KERNEL_SHAPES)."""
    if kernel not in KERNEL_SHAPES:
        raise SpectraceError(f"unknown kernel shape {kernel!r}; choose one of {', '.join(KERNEL_SHAPES)}")
    return (WavefrontRenderer if kernel == "wavefront" else Renderer)(scene, device, **options)
