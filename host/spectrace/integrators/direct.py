"""The `direct` integrator, the local model (kernels/integrator_direct.cl): emission, direct light at diffuse
surfaces and perfect specular chains, one work-item per pixel (spectrace.integrators.base.PixelPasses)."""

from spectrace.integrators.base import SHARED_PARAMETERS, PixelPasses, RenderHost, no_defines, renders_every_scene

NAME = "direct"
PARAMETERS = SHARED_PARAMETERS
PROGRAMS = {"megakernel": "integrator_direct.cl"}
SPLATS = None  # each pixel adds its own samples: tiles and checkpoints as the film's
# Of base.FEATURES, what it refuses in any scene (`problem` says why; it refuses more in some scenes).
REFUSES: tuple[str, ...] = ()
CHECKPOINT_PROBLEM = None
problem = renders_every_scene
defines = no_defines


def passes(host: RenderHost, shape: str, spectral_bins: int) -> PixelPasses:
    return PixelPasses(host)
