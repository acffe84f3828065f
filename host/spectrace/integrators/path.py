"""The `path` integrator, unidirectional path tracing with next-event estimation and MIS, in either kernel shape
(docs/devices.md, "Kernel shape (measured)"): the megakernel (kernels/integrator_path.cl, one work-item per pixel,
spectrace.integrators.base.PixelPasses) or the wavefront (kernels/integrator_path_wavefront.cl, `--kernel
wavefront`): path states in device memory, one launch per path segment.

The wavefront is this integrator's second program, not an integrator of its own: it renders the same estimator to
the same bits from the same scene keys and refuses the same scenes, so a scene's `type = "path"` names both and the
kernel shape is a renderer's choice. Each of its passes starts one path per pixel (`wavefront_start`), then launches
`wavefront_advance` over the queue of live paths until it is empty; a launch moves every live path one segment on,
and a path that ends is added to the film and replaced by its pixel's next sample (kernels/wavefront_pass.cl). The
image is the megakernel's: the same per-segment function, the same per-pixel order of additions to the film (and to
the AOV sums).
"""

import numpy as np

from spectrace.core.parameters import Parameter
from spectrace.integrators.base import (
    SHARED_PARAMETERS,
    PixelPasses,
    RenderHost,
    no_defines,
    no_params,
    renders_every_scene,
)

NAME = "path"
# Mitsuba 3's path tracers, and its `direct` as path tracing with max_depth 2 (emitters seen directly and direct
# light, as Mitsuba's direct integrator renders them at every surface, which spectrace's `direct` does not).
MITSUBA_PLUGINS = ("path", "direct", "volpath", "volpathmis")
# pbrt-v4's path tracers, and its unbiased integrators that converge to the same image (imported as this one, with a
# note); pbrt-v4's default is volpath.
PBRT_INTEGRATORS = ("volpath", "path", "simplepath", "simplevolpath", "bdpt", "mlt", "sppm", "lightpath", "randomwalk")
_PBRT_SAME_IMAGE = ("bdpt", "mlt", "sppm", "lightpath", "randomwalk")
PBRT_DEFAULT_MAXDEPTH = 5
COUNT_THIN_PASSES = Parameter(
    "count_thin_passes",
    "bool",
    default=True,
    doc="a pass straight through a thindielectric counts toward max_depth (false: Mitsuba 3's volpath, where it "
    "does not)",
)
POLARIZED = Parameter(
    "polarized",
    "bool",
    default=False,
    doc="polarised transport: paths carry Stokes vectors and Mueller matrices ([polarization.md](polarization.md)); "
    "polarising materials, Stokes AOVs and camera.polarizer_angle imply it",
)
PARAMETERS = (*SHARED_PARAMETERS, COUNT_THIN_PASSES, POLARIZED)
PROGRAMS = {"megakernel": "integrator_path.cl", "wavefront": "integrator_path_wavefront.cl"}
SPLATS = None  # each pixel adds its own samples: tiles and checkpoints as the film's
# Of base.FEATURES, what it refuses in any scene (`problem` says why; it refuses more in some scenes).
REFUSES: tuple[str, ...] = ()
CHECKPOINT_PROBLEM = None
# Its general program costs a few of its scenes' own builds: SPECTRACE_GENERAL_KERNELS=common shares it.
SHARES_GENERAL_PROGRAM = True
problem = renders_every_scene
defines = no_defines
params = no_params
QUEUE_ENTRY_BYTES = 4  # one int (a pixel index) per live path


def passes(host: RenderHost, shape: str, spectral_bins: int) -> "PixelPasses | WavefrontPasses":
    return WavefrontPasses(host) if shape == "wavefront" else PixelPasses(host)


class WavefrontPasses:
    """The wavefront's passes: its path slots and the two queues of live paths."""

    def __init__(self, host: RenderHost):
        self.host = host
        pixels = host.pixel_count
        slot_size = np.zeros(1, np.uint32)
        size_buffer = host.buffer(4)
        host.launch(host.kernel("wavefront_slot_size"), 1, size_buffer)
        host.download(slot_size, size_buffer)
        slots = pixels * int(slot_size[0])
        host.check_memory({"path slots": slots, "path queues": 2 * pixels * QUEUE_ENTRY_BYTES})
        self._slots = host.buffer(slots)
        self._queues = [host.buffer(pixels * QUEUE_ENTRY_BYTES) for _ in range(2)]
        self._queue_lengths = [host.buffer(4) for _ in range(2)]
        self._start_kernel = host.kernel("wavefront_start")
        self._advance_kernel = host.kernel("wavefront_advance")

    def reset(self) -> None:
        pass

    def run_pass(self, sample_count: int) -> None:
        host = self.host
        film = host.film
        zero = np.zeros(1, np.int32)
        live = np.zeros(1, np.int32)
        with host.render_pass(sample_count):
            host.upload(self._queue_lengths[0], zero)
            host.launch(
                self._start_kernel,
                host.pixel_count,
                host.params_buffer,
                host.cmf_buffer,
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
                host.download(live, self._queue_lengths[current])  # blocking: sizes the next launch
                if live[0] == 0:
                    break
                following = 1 - current
                host.upload(self._queue_lengths[following], zero)
                host.launch(
                    self._advance_kernel,
                    int(live[0]),
                    *host.scene_arguments(),
                    *host.film_arguments(),
                    self._slots,
                    self._queues[current],
                    self._queue_lengths[current],
                    self._queues[following],
                    self._queue_lengths[following],
                )
                current = following
            host.finish()


def from_mitsuba(importer, element, properties, settings: dict) -> dict:
    """The [integrator] table of Mitsuba's path tracers (`settings`: the shared keys, read already)."""
    kind = importer.kind(element)
    if kind == "direct":
        settings["max_depth"] = 2
        importer.notes.append(
            f"{importer.at(element)}: integrator 'direct' imported as path tracing with max_depth 2 "
            "(emitters seen directly and direct light)"
        )
        # Mitsuba's direct integrator's sample counts per technique change the noise, not the mean.
        properties.understood("emitter_samples", "bsdf_samples", "shading_samples")
    elif kind.startswith("volpath"):
        importer.notes.append(f"{importer.at(element)}: integrator '{kind}' imported as 'path', which renders media")
        # volpath counts no null interaction toward max_depth, and Mitsuba's thindielectric transmits by a
        # null lobe: a pass straight through a thin sheet is no segment there (path counts it).
        settings["count_thin_passes"] = False
    return settings


def to_mitsuba(scene) -> dict:
    """Mitsuba's path tracer; its volpath is the one that counts no pass straight through a thin sheet."""
    return {"type": "volpath" if not scene.count_thin_passes else "path"}


def from_pbrt(context, integrator) -> dict:
    """pbrt-v4's path tracers (`integrator` None: its default, volpath), or an integrator of the same image, with
    a note. pbrt's maxdepth counts bounces (0: emitters only), spectrace's max_depth path segments (1)."""
    depth = PBRT_DEFAULT_MAXDEPTH
    if integrator is not None:
        depth = context.integer(integrator, "maxdepth", depth, low=0)
        if integrator.kind in _PBRT_SAME_IMAGE:
            context.notes.append(
                f"{integrator.location}: integrator '{context.shown(integrator.kind)}' imported as path tracing "
                "(same image)"
            )
    return {"type": "path", "max_depth": depth + 1}
