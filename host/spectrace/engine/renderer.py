"""Progressive rendering on an OpenCL device: upload the scene once, then run passes of samples into the film."""

import os
import time
from collections.abc import Callable, Iterable, Iterator
from contextlib import contextmanager
from typing import Any

import numpy as np
import pyopencl as cl

from spectrace import plugins
from spectrace.core import limits
from spectrace.core.contract import SCENE_KERNEL_BUFFERS
from spectrace.device import Device, open_device
from spectrace.device.host_memory import read_only_buffer
from spectrace.engine.launch import launch_shape, render_work_group
from spectrace.engine.memory import check_device_memory, device_memory_need
from spectrace.engine.opencl_errors import translate_opencl_errors
from spectrace.engine.scene_buffers import SceneBuffers, build_scene_buffers, render_params
from spectrace.engine.scene_features import camera_feature_defines, polarization_defines, scene_feature_defines
from spectrace.errors import SpectraceError
from spectrace.film.image import Image
from spectrace.film.setup import FilmSetup
from spectrace.film.state import dropped_samples_problem
from spectrace.geometry.bvh4 import traversal_defines
from spectrace.integrators import INTEGRATORS, scene_settings_problem
from spectrace.integrators.base import PixelPasses
from spectrace.scene.model import SAMPLER_TYPES, Scene

ProgressCallback = Callable[[int, int], None]  # (samples done, samples total)

# Aim for passes of about this long: short enough for a live progress bar and prompt Ctrl-C, long enough that
# launch overhead does not matter.
TARGET_PASS_SECONDS = 0.5


def sampler_defines(sampler: str) -> dict[str, int]:
    """Build defines selecting the sampler of kernels/rng.cl (the independent one needs none)."""
    if sampler not in SAMPLER_TYPES:
        raise SpectraceError(f"unknown sampler '{sampler}' (use {' or '.join(SAMPLER_TYPES)})")
    return {"SAMPLER_SOBOL": 1} if sampler == "sobol" else {}


GENERAL_KERNELS_VARIABLE = "SPECTRACE_GENERAL_KERNELS"
GENERAL_KERNELS_SETTINGS = ("", "0", "1", "common")


def specialise_by_default(rare_variant: bool = False) -> bool:
    """Whether a renderer builds its scene's own kernels when not told: yes, unless $SPECTRACE_GENERAL_KERNELS is 1,
    or is `common` and the build is of no rare variant. The images are the same bits either way; the general kernels
    save a build per distinct scene (the test suite renders hundreds) at the cost of a longer one, shared by them all.
    rare_variant: the build carries a film or polarisation define (a spectral film, AOVs, Stokes, a film range of its
    own), each a general program of its own that few scenes share: a scene's own build costs a tenth of one; or its
    integrator's general program costs more than its scenes' own builds together (not SHARES_GENERAL_PROGRAM)."""
    value = os.environ.get(GENERAL_KERNELS_VARIABLE, "").strip()
    if value not in GENERAL_KERNELS_SETTINGS:
        raise SpectraceError(
            f"{GENERAL_KERNELS_VARIABLE}={value!r}: use 1 (general kernels), 0 (the scene's own) or common (general "
            "kernels for the common builds, the scene's own for a rare film or polarised one)"
        )
    if value == "common":
        return rare_variant
    return value != "1"


def upload_scene(context: cl.Context, buffers: SceneBuffers) -> list[cl.Buffer]:
    """Read-only device copies of the scene's buffers in the order every scene kernel takes them after the
    RenderParams buffer (SCENE_KERNEL_BUFFERS; kernels/scene.cl's SCENE_KERNEL_PARAMS); on a CPU the large ones (the
    nodes, the triangles) in huge pages (spectrace.device.host_memory)."""
    return [read_only_buffer(context, getattr(buffers, name)) for name in SCENE_KERNEL_BUFFERS]


class Renderer:
    """A render of one scene on one device: the film, the scene's device buffers and the launches, which it hands its
    integrator's passes as their spectrace.integrators.base.RenderHost (the integrator owns its program, its passes
    and their device state)."""

    KERNEL_SHAPE = "megakernel"  # which of the integrator's programs it runs (spectrace.engine.wavefront)

    @translate_opencl_errors("setting up the render")
    def __init__(
        self,
        scene: Scene,
        device: Device | str | None = None,
        spectral_bins: int = 0,
        spectral_range_nm: tuple[float, float] | None = None,
        specialise: bool | None = None,
        buffers: SceneBuffers | None = None,
    ):
        """spectral_bins > 0 also accumulates that many equal wavelength bands over spectral_range_nm (None: the
        film's wavelengths, which the samples span; the band-averaged radiance per pixel, W/(m² sr nm)), for
        spectral EXR output. specialise=False builds the kernels that handle every scene instead of ones carrying
        only this scene's features (the same bits; one program for all scenes rather than one per feature set);
        None: as $SPECTRACE_GENERAL_KERNELS says (`specialise_by_default`). `buffers`: the scene's buffers when
        already built (build_scene_buffers(scene)), as a cluster's workers receive them."""
        # The setting is checked now, before the device opens; under `common` it is decided again below, once the
        # film's defines are known.
        self.specialised = specialise_by_default() if specialise is None else specialise
        self.scene = scene
        self.integrator = INTEGRATORS.named(scene.integrator)
        if self.KERNEL_SHAPE not in self.integrator.PROGRAMS:
            having = " and ".join(name for name, plugin in INTEGRATORS.items() if self.KERNEL_SHAPE in plugin.PROGRAMS)
            raise SpectraceError(
                f"the {self.KERNEL_SHAPE} kernel runs the {having} integrator only, not {scene.integrator!r}",
                where=str(scene.source) if scene.source else None,
            )
        if problem := limits.film_size_problem(scene.width, scene.height):
            # A scene file's size was checked as it was read: this one was set in Python (with_overrides, Scene),
            # so the message names the field, not the file.
            raise SpectraceError(problem)
        problem = (  # the spp: checked by render(), which is given it
            limits.scene_settings_problem(scene)
            or scene_settings_problem(scene)
            or limits.scene_geometry_problem(scene)
        )
        if problem:
            raise SpectraceError(problem, where=str(scene.source) if scene.source else None)
        self.device = device if isinstance(device, Device) else open_device(device)
        try:
            self.buffers: SceneBuffers = buffers if buffers is not None else build_scene_buffers(scene)
        except SpectraceError as exc:  # a spectrum short of the film's range: name the scene when nothing else is
            if exc.where or scene.source is None:
                raise
            raise SpectraceError(exc.message, where=str(scene.source)) from None
        film = FilmSetup.of(scene, self.buffers.cmf, spectral_bins, spectral_range_nm)
        if film.beyond_the_visible:
            light_images = bool(scene_feature_defines(self.buffers)["SCENE_HAS_LIGHT_IMAGES"])
            film.check_scene_spectra(self.buffers.textures[: self.buffers.texture_count], light_images, scene.source)
        if problem := self.integrator.problem(scene, self.buffers.medium_count, spectral_bins):
            raise SpectraceError(problem, where=str(scene.source) if scene.source else None)
        # Refuse before allocating anything: a failed allocation deep in the driver says far less.
        check_device_memory(
            device_memory_need(
                self.buffers, scene.width * scene.height, spectral_bins, film.response_channels, aovs=bool(film.aovs)
            ),
            self.device,
        )
        defines: dict[str, int | float] = {**sampler_defines(scene.sampler), **traversal_defines()}
        if specialise is None:
            rare = (
                bool(film.defines())
                or bool(polarization_defines(scene, self.buffers))
                or not self.integrator.SHARES_GENERAL_PROGRAM
            )
            self.specialised = specialise_by_default(rare)
        self.feature_defines = self._feature_defines(scene, self.buffers)
        defines |= self.feature_defines
        defines |= film.defines()
        defines |= self.integrator.defines(scene)
        self.program = self.device.build_program(
            self.integrator.PROGRAMS[self.KERNEL_SHAPE],
            defines=defines or None,
            generated=plugins.generated_sources(),
        )
        # Work-items per group of the pass launches (None: the runtime's choice); `spectrace bench` varies it.
        self.work_group = self._work_group()
        ctx = self.device.context
        self._params = cl.Buffer(ctx, cl.mem_flags.READ_ONLY, render_params(scene, self.buffers, 0, 0).nbytes)
        self._scene = upload_scene(ctx, self.buffers)
        self.film = film.create(self.device)
        # The pixels [begin, end) the passes render: all of them, or one tile of a split render (spectrace.engine.
        # tiles). The launch's global offset moves the work-item ids, so each pixel runs the same code on the
        # same ids either way and adds the same bits.
        self.pixel_range = (0, self.film.pixel_count)
        self.passes = self.integrator.passes(self, self.KERNEL_SHAPE, spectral_bins)

    def _feature_defines(self, scene: Scene, buffers: SceneBuffers) -> dict[str, int]:
        """The defines of the scene's features its program is specialised to (none for the general kernels)."""
        polarized = polarization_defines(scene, buffers)
        if not self.specialised:
            return polarized
        hides = scene.hide_emitters and any(shape.emitter is not None for shape in scene.shapes)
        return (
            scene_feature_defines(buffers, hides)
            | camera_feature_defines(render_params(scene, buffers, 0, 0))
            | polarized
        )

    def program_fits(self, scene: Scene, buffers: SceneBuffers) -> bool:
        """Whether this renderer's program renders `scene` (an edit of its own) with `buffers`: the same features."""
        return self._feature_defines(scene, buffers) == self.feature_defines

    @translate_opencl_errors("updating the scene")
    def replace_scene(self, scene: Scene, buffers: SceneBuffers, changed: Iterable[str]) -> None:
        """Render `scene` from now on, whose buffers differ from those uploaded in `changed` (names among
        SCENE_KERNEL_BUFFERS) alone: each rewritten where its size is the same, replaced where not. The film and
        the passes start again."""
        names = list(SCENE_KERNEL_BUFFERS)
        replaced = False
        for name in changed:
            i = names.index(name)
            array = np.ascontiguousarray(getattr(buffers, name))
            if array.nbytes == self._scene[i].size:
                cl.enqueue_copy(self.device.queue, self._scene[i], array)
            else:
                self._scene[i] = read_only_buffer(self.device.context, array)
                replaced = True
        self.scene, self.buffers = scene, buffers
        # A per-pixel integrator's passes read the scene's buffers at each launch; others may have set their
        # kernels' arguments to the buffers replaced or kept state derived from the scene.
        if replaced or not isinstance(self.passes, PixelPasses):
            self.passes = self.integrator.passes(self, self.KERNEL_SHAPE, self.spectral_bins)
        self.reset()

    def _work_group(self) -> int | None:
        return render_work_group(self.device)

    # What the integrator's passes are handed (spectrace.integrators.base.RenderHost).
    def kernel(self, name: str) -> cl.Kernel:
        return cl.Kernel(self.program, name)

    def buffer(self, nbytes: int = 0, data: np.ndarray | None = None) -> cl.Buffer:
        if data is not None:
            return cl.Buffer(self.device.context, cl.mem_flags.READ_ONLY | cl.mem_flags.COPY_HOST_PTR, hostbuf=data)
        return cl.Buffer(self.device.context, cl.mem_flags.READ_WRITE, nbytes)

    def check_memory(self, extra: dict[str, int]) -> None:
        scene = self.scene
        need = device_memory_need(
            self.buffers, self.pixel_count, self.spectral_bins, self.film.response_channels, aovs=bool(scene.aovs)
        )
        need.buffers.update(extra)
        check_device_memory(need, self.device)

    @property
    def params_buffer(self) -> cl.Buffer:
        return self._params

    @property
    def cmf_buffer(self) -> cl.Buffer:
        return self.film.table_buffer

    def scene_arguments(self) -> tuple:
        return (self._params, *self._scene)

    def film_arguments(self) -> tuple:
        return self.film.kernel_arguments()

    @contextmanager
    def render_pass(self, sample_count: int) -> Iterator[int]:
        if (splats := self.integrator.SPLATS) is not None and tuple(self.pixel_range) != (0, self.pixel_count):
            raise SpectraceError(
                f"integrator '{self.scene.integrator}' renders whole films, not tiles: its {splats} land in any pixel"
            )
        done = self.samples_done
        params = render_params(self.scene, self.buffers, done, sample_count)
        self.film.setup.write_params(params)
        start = time.perf_counter()
        cl.enqueue_copy(self.device.queue, self._params, params)
        yield done
        self.film.add_pass(sample_count, time.perf_counter() - start)

    def launch(self, kernel: cl.Kernel, count: int, *arguments: Any, offset: int = 0) -> None:
        if arguments:
            kernel.set_args(*arguments)
        global_size, local_size = launch_shape(count, self.work_group)
        cl.enqueue_nd_range_kernel(self.device.queue, kernel, global_size, local_size, (offset,) if offset else None)

    def upload(self, buffer: cl.Buffer, array: np.ndarray) -> None:
        cl.enqueue_copy(self.device.queue, buffer, array)

    def download(self, array: np.ndarray, buffer: cl.Buffer) -> None:
        cl.enqueue_copy(self.device.queue, array, buffer)

    def clear(self, buffer: cl.Buffer) -> None:
        cl.enqueue_fill_buffer(self.device.queue, buffer, np.zeros(1, np.float32), 0, buffer.size)

    def finish(self) -> None:
        self.device.queue.finish()

    # The film's size and bands, which the film holds (one copy, no drift).
    @property
    def pixel_count(self) -> int:
        return self.film.pixel_count

    @property
    def spectral_bins(self) -> int:
        return self.film.spectral_bins

    @property
    def spectral_range_nm(self) -> tuple[float, float]:
        return self.film.spectral_range_nm

    @property
    def samples_done(self) -> int:
        return self.film.samples_done

    @property
    def render_seconds(self) -> float:
        return self.film.render_seconds

    def reset(self) -> None:
        """Clear the film to start the render again."""
        self.film.reset()
        self.passes.reset()

    @translate_opencl_errors("running a render pass")
    def run_pass(self, sample_count: int) -> None:
        """Add `sample_count` samples per pixel, continuing the sample sequence where the last pass stopped."""
        self.passes.run_pass(sample_count)

    def render(
        self,
        spp: int | None = None,
        pass_spp: int | None = None,
        progress: ProgressCallback | None = None,
        should_stop: Callable[[], bool] | None = None,
    ) -> Image:
        """Render until `spp` samples per pixel (default: the scene's). Passes adapt their size to about
        TARGET_PASS_SECONDS unless pass_spp fixes it; the image does not depend on the pass sizes.
        `should_stop` is asked between passes; when it says True the image of the samples done so far is returned."""
        total = spp if spp is not None else self.scene.spp
        if problem := limits.spp_problem(total) or limits.pass_spp_problem(pass_spp):
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

    def read_film(self) -> tuple[np.ndarray, np.ndarray]:
        """The film's sums (see Film.read)."""
        return self.film.read()

    def read_spectral_film(self) -> np.ndarray:
        """(height, width, bins) band sums; divide by samples_done for the band-averaged radiance."""
        return self.film.read_spectral()

    def image(self) -> Image:
        """The image of the samples so far; a SpectraceError when most of them were dropped as non-finite
        (spectrace.film.state.DROPPED_FAIL_FRACTION), naming the likeliest input."""
        scene = self.scene
        image = self._film_image()
        begin, end = self.pixel_range
        if problem := dropped_samples_problem(image.dropped_samples, image.spp * (end - begin), scene):
            raise SpectraceError(problem)
        return image

    def _film_image(self) -> Image:
        scene = self.scene
        return self.film.image(
            seed=scene.seed,
            device=self.device.report.key,
            exposure=scene.exposure,
            extra={
                "max_depth": scene.max_depth,
                "width": scene.width,
                "height": scene.height,
                "sampler": scene.sampler,
                "triangles": self.buffers.triangle_count,
                **self.film.setup.metadata(),
                "bvh_seconds": f"{self.buffers.bvh_seconds:.3f}",
                **(
                    {"bvh_peak_mib": f"{self.buffers.bvh_peak_bytes / 2**20:.1f}"}
                    if self.buffers.bvh_peak_bytes is not None
                    else {}
                ),
            },
        )
