"""render(): the one-call entry point of the Python API."""

from spectrace.device import Device
from spectrace.image import Image
from spectrace.engine.renderer import ProgressCallback, Renderer
from spectrace.scene.model import Scene


def render(scene: Scene, spp: int | None = None, device: Device | str | None = None,
           progress: ProgressCallback | None = None, pass_spp: int | None = None) -> Image:
    """Render `scene` to `spp` samples per pixel (default: the scene's) on `device` (a Device, a selection
    string such as "pocl" or "gpu", or None for the automatic choice)."""
    return Renderer(scene, device).render(spp=spp, pass_spp=pass_spp, progress=progress)
