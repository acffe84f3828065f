"""The `direct` integrator, the local model (kernels/integrator_direct.cl): emission, direct light at diffuse
surfaces and perfect specular chains, one work-item per pixel (spectrace.integrators.base.PixelPasses)."""

from spectrace.integrators.base import (
    SHARED_PARAMETERS,
    PixelPasses,
    RenderHost,
    Scene,
    glowing_media_problem,
    no_defines,
    no_params,
)

NAME = "direct"
MITSUBA_PLUGINS: tuple[str, ...] = ()
MITSUBA_NONE = (
    "Mitsuba 3's `direct` lights every surface and follows no specular chain, where this integrator lights diffuse "
    "surfaces and follows perfect specular chains: it imports as path tracing with max_depth 2 (path.py)"
)
PBRT_INTEGRATORS: tuple[str, ...] = ()
PBRT_NONE = "pbrt-v4 has no direct-lighting integrator"
PARAMETERS = SHARED_PARAMETERS
PROGRAMS = {"megakernel": "integrator_direct.cl"}
SPLATS = None  # each pixel adds its own samples: tiles and checkpoints as the film's
# Of base.FEATURES, what it refuses in any scene (`problem` says why; it refuses more in some scenes).
REFUSES: tuple[str, ...] = ("glowing media",)
CHECKPOINT_PROBLEM = None
# Its general program costs a few of its scenes' own builds: SPECTRACE_GENERAL_KERNELS=common shares it.
SHARES_GENERAL_PROGRAM = True
defines = no_defines
params = no_params


def problem(scene: Scene, medium_count: int, spectral_bins: int) -> str | None:
    """Why the local model cannot render this scene: a glowing medium, whose emission its paths do not gather."""
    return glowing_media_problem(scene, NAME)


def passes(host: RenderHost, shape: str, spectral_bins: int) -> PixelPasses:
    return PixelPasses(host)
