"""Progressive rendering on an OpenCL device: upload the scene once, then run passes of samples into the film."""

import os
import time
from collections.abc import Callable

import numpy as np
import pyopencl as cl

from spectrace import registries
from spectrace.aovs import albedo_channel_scale, aov_defines
from spectrace.core import limits
from spectrace.core.contract import SCENE_KERNEL_BUFFERS, TEXEL_BANDS, TEXEL_RGB, TEXEL_SIGMOID
from spectrace.device import Device, open_device
from spectrace.engine.bdpt import pixels_per_light_path
from spectrace.engine.launch import launch_shape, render_work_group
from spectrace.engine.light_tracer import LightPasses
from spectrace.engine.memory import check_device_memory, device_memory_need
from spectrace.engine.opencl_errors import translate_opencl_errors
from spectrace.engine.scene_buffers import SceneBuffers, build_scene_buffers, render_params
from spectrace.engine.scene_features import camera_feature_defines, scene_feature_defines
from spectrace.engine.sppm import SppmPasses
from spectrace.errors import SpectraceError
from spectrace.film import Film, dropped_samples_problem, spectral_defines, spectral_range
from spectrace.geometry.bvh4 import traversal_defines
from spectrace.image import Image
from spectrace.scene.model import SAMPLER_TYPES, Scene
from spectrace.spectral.grid import GRID_MAX_NM, GRID_MIN_NM

ProgressCallback = Callable[[int, int], None]  # (samples done, samples total)

# Aim for passes of about this long: short enough for a live progress bar and prompt Ctrl-C, long enough that
# launch overhead does not matter.
TARGET_PASS_SECONDS = 0.5

INTEGRATOR_PROGRAMS = {
    "path": "integrator_path.cl",
    "direct": "integrator_direct.cl",
    "light": "integrator_light.cl",
    "bdpt": "integrator_bdpt.cl",
    "sppm": "integrator_sppm.cl",
}
# Integrators whose connections land in any pixel: their passes are spectrace.engine.light_tracer's (splat records
# reduced on the host in a fixed order), their kernels take its arguments.
SPLATTING_KERNELS = {"light": "light_pass", "bdpt": "bdpt_pass"}
# Every integrator's pass kernel other than render_pass: the splatting ones, and stochastic progressive photon
# mapping's gather (its passes are spectrace.engine.sppm's, which also runs the program's photon kernel).
PASS_KERNELS = {**SPLATTING_KERNELS, "sppm": "sppm_gather_pass"}


def sampler_defines(sampler: str) -> dict[str, int]:
    """Build defines selecting the sampler of kernels/rng.cl (the independent one needs none)."""
    if sampler not in SAMPLER_TYPES:
        raise SpectraceError(f"unknown sampler '{sampler}' (use {' or '.join(SAMPLER_TYPES)})")
    return {"SAMPLER_SOBOL": 1} if sampler == "sobol" else {}


GENERAL_KERNELS_VARIABLE = "SPECTRACE_GENERAL_KERNELS"


def specialise_by_default() -> bool:
    """Whether a renderer builds its scene's own kernels when not told: yes, unless $SPECTRACE_GENERAL_KERNELS is 1.
    The images are the same bits either way; the general kernels save a build per distinct scene (the test suite
    renders hundreds) at the cost of a longer one, shared by them all."""
    value = os.environ.get(GENERAL_KERNELS_VARIABLE, "").strip()
    if value not in ("", "0", "1"):
        raise SpectraceError(f"{GENERAL_KERNELS_VARIABLE}={value!r}: use 1 (general kernels) or 0 (the scene's own)")
    return value != "1"


def upload_scene(context: cl.Context, buffers: SceneBuffers) -> list[cl.Buffer]:
    """Read-only device copies of the scene's buffers in the order every scene kernel takes them after the
    RenderParams buffer (SCENE_KERNEL_BUFFERS; kernels/scene.cl's SCENE_KERNEL_PARAMS)."""
    flags = cl.mem_flags.READ_ONLY | cl.mem_flags.COPY_HOST_PTR
    return [
        cl.Buffer(context, flags, hostbuf=np.ascontiguousarray(getattr(buffers, name))) for name in SCENE_KERNEL_BUFFERS
    ]


def film_table(scene: Scene, buffers: SceneBuffers) -> np.ndarray:
    """The film table the render kernels read as `cmf` (kernels/film.cl): the scene buffers' CIE 1931 CMFs for the
    default film; other films bring their own, whose first rows are the film observer's XYZ curves on its grid."""
    response = scene.film_response
    return buffers.cmf if response.is_default else response.device_table()


def film_albedo_scale(scene: Scene, table: np.ndarray) -> np.ndarray:
    """The albedo AOV's channel scale (spectrace.aovs) for the film observer's XYZ rows of a film table."""
    return albedo_channel_scale(table[: scene.film_response.grid_nm.size])


class Renderer:
    _light_passes: LightPasses | None = None  # set by _allocate for a `light` or `bdpt` scene
    _sppm_passes: SppmPasses | None = None  # set by _allocate for an `sppm` scene

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
        if specialise is None:
            specialise = specialise_by_default()
        self.specialised = specialise
        self.scene = scene
        self._check_scene(scene)
        if spectral_range_nm is None:
            spectral_range_nm = spectral_range(scene)
        problem = (
            limits.render_settings_problem(scene.width, scene.height, scene.spp)
            or limits.scene_settings_problem(scene)
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
        self._check_film_range(scene)
        # Refuse before allocating anything: a failed allocation deep in the driver says far less.
        response_channels = len(scene.film_response.channel_names)
        check_device_memory(
            device_memory_need(
                self.buffers, scene.width * scene.height, spectral_bins, response_channels, aovs=bool(scene.aovs)
            ),
            self.device,
        )
        defines: dict[str, int | float] = {**sampler_defines(scene.sampler), **traversal_defines()}
        if specialise:
            hides = scene.hide_emitters and any(shape.emitter is not None for shape in scene.shapes)
            defines |= scene_feature_defines(self.buffers, hides)
            defines |= camera_feature_defines(render_params(scene, self.buffers, 0, 0))
        defines |= spectral_defines(spectral_bins, spectral_range_nm) | aov_defines(scene.aovs)
        response = scene.film_response
        defines |= response.defines()
        if scene.integrator == "bdpt":
            defines["BDPT_PIXELS_PER_LIGHT_PATH"] = pixels_per_light_path(scene)
        self.program = self.device.build_program(
            self._program_file(scene), defines=defines or None, generated=registries.generated_sources()
        )
        self.kernel = self._create_kernels()
        # Work-items per group of the pass launches (None: the runtime's choice); `spectrace bench` varies it.
        self.work_group = render_work_group(self.device)
        ctx = self.device.context
        ro = cl.mem_flags.READ_ONLY | cl.mem_flags.COPY_HOST_PTR
        b = self.buffers
        self._params = cl.Buffer(ctx, cl.mem_flags.READ_ONLY, render_params(scene, self.buffers, 0, 0).nbytes)
        self._scene = upload_scene(ctx, b)
        # The default CIE 1931 film's table is the scene buffers' CMFs; other films bring their own (film.cl), whose
        # first rows are the film observer's XYZ curves on the film's grid.
        self.film_table = film_table(scene, b)
        self._cmf = cl.Buffer(ctx, ro, hostbuf=np.ascontiguousarray(self.film_table))
        self.film = Film(
            self.device,
            scene.width,
            scene.height,
            spectral_bins,
            spectral_range_nm,
            aovs=scene.aovs,
            albedo_scale=film_albedo_scale(scene, self.film_table),
            response=response,
        )
        # The pixels [begin, end) the passes render: all of them, or one tile of a split render (spectrace.engine.
        # tiles). The launch's global offset moves the work-item ids, so each pixel runs the same code on the
        # same ids either way and adds the same bits.
        self.pixel_range = (0, self.film.pixel_count)
        self._allocate(spectral_bins)

    def _check_film_range(self, scene: Scene) -> None:
        """A film range of its own reaches every tabulated spectrum (the table refuses those that fall short). The
        textures' RGB texels are sigmoids of λ and the pictures' weight basis spectra from the table, so they hold on
        any range inside the visible; beyond it they follow the rule of RGB spectra (continued only with
        film.extend_rgb), and a spectral texture must have bands as far as the film goes."""
        response = scene.film_response
        if not response.has_own_grid:
            return
        lo, hi = response.wavelengths
        if lo >= GRID_MIN_NM and hi <= GRID_MAX_NM:
            return
        where = str(scene.source) if scene.source else None
        textures = self.buffers.textures[: self.buffers.texture_count]
        features = scene_feature_defines(self.buffers)
        rgb = bool(np.any(np.isin(textures["texel_format"], (TEXEL_SIGMOID, TEXEL_RGB))))
        if (rgb or features["SCENE_HAS_LIGHT_IMAGES"]) and not response.extend_rgb:
            raise SpectraceError(
                f"film.wavelengths {lo:g}-{hi:g} nm: textures and emitter pictures hold RGB colours, defined for the "
                f"visible ({GRID_MIN_NM:g}-{GRID_MAX_NM:g} nm) only; film.extend_rgb = true continues them (as it "
                "does RGB spectra)",
                where=where,
            )
        for texture in textures[textures["texel_format"] == TEXEL_BANDS]:
            first = float(texture["band_first_nm"])
            last = first + float(texture["band_step_nm"]) * (int(texture["channels"]) - 1)
            if (lo < GRID_MIN_NM and first > lo) or (hi > GRID_MAX_NM and last < hi):
                raise SpectraceError(
                    f"film.wavelengths {lo:g}-{hi:g} nm: a spectral texture's bands span {first:g}-{last:g} nm; beyond "
                    f"the visible the film's range needs measured bands",
                    where=where,
                )

    def _check_scene(self, scene: Scene) -> None:
        """Refuses a scene this kernel shape cannot render, before any other check."""

    def _allocate(self, spectral_bins: int) -> None:
        """The device buffers this kernel shape needs beyond the film and the scene: the light tracer's launches and
        splat records (spectrace.engine.light_tracer) for a `light` scene."""
        splats = self.scene.integrator in SPLATTING_KERNELS
        self._light_passes = LightPasses(self, spectral_bins) if splats else None
        self._sppm_passes = SppmPasses(self, spectral_bins) if self.scene.integrator == "sppm" else None

    def _program_file(self, scene: Scene) -> str:
        return INTEGRATOR_PROGRAMS[scene.integrator]

    def _create_kernels(self) -> cl.Kernel:
        return cl.Kernel(self.program, PASS_KERNELS.get(self.scene.integrator, "render_pass"))

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
        if self._sppm_passes is not None:
            self._sppm_passes.reset()

    @translate_opencl_errors("running a render pass")
    def run_pass(self, sample_count: int) -> None:
        """Add `sample_count` samples per pixel, continuing the sample sequence where the last pass stopped."""
        if self._light_passes is not None:
            self._light_passes.run_pass(sample_count)
            return
        if self._sppm_passes is not None:
            self._sppm_passes.run_pass(sample_count)
            return
        queue = self.device.queue
        params = render_params(self.scene, self.buffers, self.samples_done, sample_count)
        start = time.perf_counter()
        cl.enqueue_copy(queue, self._params, params)
        film = self.film
        self.kernel.set_args(
            self._params,
            *self._scene,
            self._cmf,
            film.xyz_buffer,
            film.ray_count_buffer,
            film.spectral_buffer,
            film.response_buffer,
            film.aov_buffer,
        )
        begin, end = self.pixel_range
        global_size, local_size = launch_shape(end - begin, self.work_group)
        offset = (begin,) if begin else None
        cl.enqueue_nd_range_kernel(queue, self.kernel, global_size, local_size, offset)
        queue.finish()
        film.add_pass(sample_count, time.perf_counter() - start)

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

    def _film_metadata(self) -> dict[str, str]:
        """What the film responded to, for the image's metadata (nothing for the default film)."""
        response = self.scene.film_response
        if response.is_default:
            return {}
        lo, hi = response.wavelengths
        metadata = {"observer": response.observer, "wavelengths_nm": f"{lo:g}-{hi:g}"}
        if response.sensor is not None:
            metadata["sensor"] = response.sensor.source
        if response.sensor_white is not None:
            metadata["sensor_white"] = response.sensor_white
        return metadata

    def image(self) -> Image:
        """The image of the samples so far; a SpectraceError when most of them were dropped as non-finite
        (spectrace.film.DROPPED_FAIL_FRACTION), naming the likeliest input."""
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
                **self._film_metadata(),
                "bvh_seconds": f"{self.buffers.bvh_seconds:.3f}",
                **(
                    {"bvh_peak_mib": f"{self.buffers.bvh_peak_bytes / 2**20:.1f}"}
                    if self.buffers.bvh_peak_bytes is not None
                    else {}
                ),
            },
        )
