"""What every integrator is handed and holds: the renderer's side of a pass (`RenderHost`), an integrator's passes
(`Passes`), the passes of a per-pixel integrator (`PixelPasses`), and the `[integrator]` keys every integrator takes.

An integrator module never imports the engine or the scene layer (the scene model reads the registry's names): the
renderer hands it a RenderHost, which owns the device, the film, the scene's device buffers and the launches, and
through which every buffer is allocated and every kernel launched, so that the shared kernel arguments, the pass
preamble (the render parameters of the samples to add), the launch shape and the translation of OpenCL errors are
written once.
"""

from __future__ import annotations

from contextlib import AbstractContextManager
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np

from spectrace.core import limits
from spectrace.core.parameters import Parameter, Range

if TYPE_CHECKING:
    import pyopencl as cl

# A spectrace.scene.model.Scene. The scene layer imports the registry (its integrator names), so the integrators
# read its fields without importing it.
Scene = Any


class RenderHost(Protocol):
    """The renderer as its integrator's passes see it (spectrace.engine.renderer.Renderer)."""

    @property
    def scene(self) -> Scene: ...
    @property
    def buffers(self) -> Any: ...  # the scene's SceneBuffers
    @property
    def film(self) -> Any: ...  # the film its passes add to (spectrace.film.Film)
    @property
    def pixel_count(self) -> int: ...
    @property
    def pixel_range(self) -> tuple[int, int]: ...  # the pixels [begin, end) the passes render

    def kernel(self, name: str) -> cl.Kernel:
        """The kernel `name` of the integrator's program."""
        ...

    def buffer(self, nbytes: int = 0, data: np.ndarray | None = None) -> cl.Buffer:
        """A device buffer: read-write of `nbytes`, or a read-only copy of `data`."""
        ...

    def check_memory(self, extra: dict[str, int]) -> None:
        """Refuses, with the amounts, a render whose film, scene and `extra` buffers (bytes by name) do not fit."""
        ...

    def scene_arguments(self) -> tuple:
        """The arguments every scene kernel opens with: the render parameters, then the scene's buffers."""
        ...

    def film_arguments(self) -> tuple:
        """The film table (`cmf`) and the film's sums, as kernels/film.cl's film kernels take them after the scene."""
        ...

    @property
    def cmf_buffer(self) -> cl.Buffer: ...  # the film table alone (`cmf`), for kernels that add to no film sum
    @property
    def params_buffer(self) -> cl.Buffer: ...  # the render parameters alone
    @property
    def work_group(self) -> int | None: ...  # work-items per group of its launches

    def render_pass(self, sample_count: int) -> AbstractContextManager[int]:
        """The pass preamble: uploads the render parameters of the `sample_count` samples after those done (whose
        number it gives), and adds the pass to the film when the body returns."""
        ...

    def launch(self, kernel: cl.Kernel, count: int, *arguments: Any, offset: int = 0) -> None:
        """Runs `kernel` (with `arguments` when given) over `count` work-items from `offset`."""
        ...

    def upload(self, buffer: cl.Buffer, array: np.ndarray) -> None: ...
    def download(self, array: np.ndarray, buffer: cl.Buffer) -> None: ...
    def clear(self, buffer: cl.Buffer) -> None: ...
    def finish(self) -> None: ...


class Passes(Protocol):
    """An integrator's passes over one renderer: its device state, how it adds a pass of samples to the film."""

    def run_pass(self, sample_count: int) -> None:
        """Adds `sample_count` samples per pixel, continuing where the last pass stopped."""
        ...

    def reset(self) -> None:
        """Clears the device state beyond the film (the film is the renderer's)."""
        ...


class PixelPasses:
    """The passes of a per-pixel integrator: its program's `render_pass` runs one work-item per pixel of the
    renderer's range, which adds its samples to its own pixel of the film (kernels/render_pass.cl)."""

    def __init__(self, host: RenderHost):
        self.host = host
        self._kernel = host.kernel("render_pass")

    def run_pass(self, sample_count: int) -> None:
        host = self.host
        with host.render_pass(sample_count):
            begin, end = host.pixel_range
            self._kernel.set_args(*host.scene_arguments(), *host.film_arguments())
            host.launch(self._kernel, end - begin, offset=begin)
            host.finish()

    def reset(self) -> None:
        pass


def renders_every_scene(scene: Scene, medium_count: int, spectral_bins: int) -> str | None:
    """The `problem` of an integrator that refuses nothing."""
    return None


def glowing_media_problem(scene: Scene, name: str) -> str | None:
    """Why integrator `name`, whose paths cannot gather a medium's emission (the path tracer's and BDPT's camera
    paths do: kernels/medium_emission.cl; the light tracer's start in glowing media: kernels/light_glowing_media.cl),
    refuses this scene, or None."""
    if any(shape.glows_inside for shape in scene.every_shape):
        return f"integrator '{name}' does not render glowing media (a medium's emission); use 'path' or 'bdpt'"
    return None


def no_defines(scene: Scene) -> dict[str, int]:
    """The `defines` of an integrator whose program needs none."""
    return {}


def no_params(scene: Scene) -> dict[str, int]:
    """The `params` of an integrator whose kernels read no RenderParams field of their own."""
    return {}


# What an integrator may refuse whatever else the scene holds: each module's REFUSES lists those it does (and its
# `problem` says so in one line), which tests/render/test_furnace_integrators.py holds it to.
FEATURES = ("spectral bands", "AOVs", "pixel filters", "film responses", "media", "hidden area lights", "glowing media")

# The keys every integrator takes (the schema's IntegratorSpec, docs/scene-format.md's [integrator] table).
MAX_DEPTH = Parameter(
    "max_depth",
    "int",
    default=8,
    range=Range(-1, limits.MAX_DEPTH),
    doc="path segments from the camera; -1 = unbounded",
)
RR_DEPTH = Parameter(
    "rr_depth",
    "int",
    default=5,
    range=Range(1, limits.MAX_DEPTH),
    doc="bounces after which Russian roulette may end a path",
)
HIDE_ENVIRONMENT = Parameter(
    "hide_environment",
    "bool",
    default=False,
    doc="camera rays that leave the scene see black; reflections still show it",
)
HIDE_EMITTERS = Parameter(
    "hide_emitters",
    "bool",
    default=False,
    doc="Mitsuba 3's hide_emitters: hide_environment, and camera rays pass through area lights",
)
SHARED_PARAMETERS = (MAX_DEPTH, RR_DEPTH, HIDE_ENVIRONMENT, HIDE_EMITTERS)
