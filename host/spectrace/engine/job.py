"""One render's settings, checked once: `RenderJob`, which `spectrace render`, `spectrace.render` and a render
split into tiles (spectrace.engine.tiles) all build and run from.

It lives in the engine, not the film, because most of what it settles is the engine's (the scene with its
overrides, the spp, the device, the kernel shape, the tiles); the film's part is a few of its fields (spectral
bands, AOVs, colour output), which spectrace.film.setup turns into the film. Each check is made here and nowhere
else on the way in, so a wrong setting gets the same one line from the command line and from Python; only the
name it is reported under follows the front end (`--spp` on the command line, the message alone in Python, whose
messages name the argument themselves).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING

from spectrace.core import limits
from spectrace.errors import SpectraceError
from spectrace.film.colour_output import Adaptation, ColourSpace, WhiteBalance
from spectrace.film.image import output_format_problem
from spectrace.film.output_options import RenderOutputOptions

if TYPE_CHECKING:
    from spectrace.device import Device
    from spectrace.engine.checkpoint import RenderIdentity
    from spectrace.engine.renderer import Renderer
    from spectrace.engine.tiles import TileJob
    from spectrace.film.image import Image
    from spectrace.io.tev import DisplayServer
    from spectrace.pixel_filters import PixelFilter
    from spectrace.scene.model import Scene


@dataclass(frozen=True)
class SettingNames:
    """How a front end names the settings its errors point at (None: the message names the setting itself)."""

    spp: str | None
    pass_spp: str | None
    spectral_bins: str | None
    tile_rows: str | None
    aovs: str | None
    colour_space: str | None
    white_balance: str | None
    adaptation: str | None
    size: str | None = None
    seed: str | None = None
    max_depth: str | None = None
    exposure: str | None = None
    sampler: str | None = None
    denoise: str | None = None
    display_server: str | None = None
    integrator: str | None = None


COMMAND_LINE = SettingNames(
    spp="--spp",
    pass_spp="--pass-spp",
    spectral_bins="--spectral-bins",
    tile_rows="--tile-rows",
    aovs="--aov",
    colour_space="--colour-space",
    white_balance="--white-balance",
    adaptation="--adaptation",
    size="--width/--height",
    seed="--seed",
    max_depth="--max-depth",
    exposure="--exposure",
    sampler="--sampler",
    denoise="--denoise",
    display_server="--display-server",
    integrator="--integrator",
)
PYTHON = SettingNames(
    spp=None,
    pass_spp=None,
    spectral_bins=None,
    tile_rows=None,
    aovs="aovs",
    colour_space="colour_space",
    white_balance="white_balance",
    adaptation="adaptation",
    display_server="display_server",
)


def _refuse(problem: str | None | bool, where: str | None) -> None:
    if problem:
        raise SpectraceError(str(problem), where=where)


def _count_problem(name: str, value: object, least: int) -> str | None:
    """Why `value` is no whole number of at least `least` (named `name`), or None."""
    if problem := limits.whole_number_problem(name, value):
        return problem
    assert isinstance(value, int)
    return f"{name} must be at least {least}, got {value}" if value < least else None


def _keeping_aspect(scene: Scene, width: int | None, height: int | None) -> tuple[int | None, int | None]:
    """(width, height) with the one not given following the scene's aspect ratio (at least 1 pixel); both given or
    neither: as they are. A scene whose own size is no positive whole number keeps its size, for its check."""
    own_width, own_height = scene.width, scene.height
    usable = all(isinstance(n, int) and not isinstance(n, bool) and n > 0 for n in (own_width, own_height))
    if not usable or (width is None) == (height is None):
        return width, height
    if height is None and isinstance(width, int) and width > 0:
        return width, max(1, round(width * own_height / own_width))
    if width is None and isinstance(height, int) and height > 0:
        return max(1, round(height * own_width / own_height)), height
    return width, height


def check_camera(scene: Scene) -> None:
    """Refuses, naming the key, a camera a Scene built in Python may hold that a scene file's loader would refuse
    (its own checks name the file too): target at the origin, up along the view, clips, type, numbers out of
    range, and a pixel filter that is none."""
    import numpy as np

    from spectrace.cameras import CAMERAS
    from spectrace.cameras.shared import clip_problem
    from spectrace.pixel_filters import PixelFilter

    camera = scene.camera
    forward = np.subtract(camera.target, camera.origin)
    if not np.linalg.norm(forward) > 0:
        raise SpectraceError("camera target equals origin", where="camera.target")
    if np.linalg.norm(np.cross(forward, camera.up)) < 1e-9 * np.linalg.norm(forward) * np.linalg.norm(camera.up):
        raise SpectraceError("camera up is parallel to the viewing direction (or zero)", where="camera.up")
    if problem := clip_problem(camera):
        raise SpectraceError(problem, where="camera.far_clip")
    if camera.type not in CAMERAS:
        raise SpectraceError(f"unknown camera type {camera.type!r}; one of {', '.join(CAMERAS)}", where="camera.type")
    # The camera's numbers that are fields of the model (a thin lens's f_number is resolved into its aperture).
    fields = {field.name for field in dataclasses.fields(camera)}
    for parameter in CAMERAS[camera.type].PARAMETERS:
        name = parameter.api_name or parameter.name
        if parameter.type == "float" and name in fields and (value := getattr(camera, name)) is not None:
            parameter.check(value, where=f"camera.{parameter.name}")
    if not isinstance(scene.pixel_filter, PixelFilter):
        raise SpectraceError("expected a spectrace.PixelFilter", where="pixel_filter")


@dataclass(frozen=True)
class RenderJob:
    """The validated settings of one render: the scene with every override applied (its `spp` is the render's: one
    source of truth), the device, the kernel shape, the film's extra outputs (spectral bands, AOVs in the scene,
    the colour space, white balance and false-colour map of the files), denoising, and the tiles when split.
    Build it with `make`."""

    scene: Scene
    device: Device | str | None = None
    kernel: str = "megakernel"
    pass_spp: int | None = None
    spectral_bins: int = 0
    outputs: RenderOutputOptions = RenderOutputOptions()
    denoise: bool = False
    tile_rows: int | None = None
    names: SettingNames = PYTHON
    notes: tuple[str, ...] = ()  # what the front end should tell the user (a setting left unused)
    display_server: DisplayServer | None = None  # the tev viewer shown the render as it converges

    @classmethod
    def make(
        cls,
        scene: Scene | Callable[[], Scene],
        names: SettingNames = PYTHON,
        *,
        spp: int | None = None,
        width: int | None = None,
        height: int | None = None,
        seed: int | None = None,
        max_depth: int | None = None,
        exposure: float | None = None,
        sampler: str | None = None,
        integrator: str | None = None,
        pixel_filter: PixelFilter | None = None,
        aovs: str | Sequence[str] | None = None,
        spectral_bins: int = 0,
        pass_spp: int | None = None,
        device: Device | str | None = None,
        kernel: str = "megakernel",
        colour_space: ColourSpace | str = ColourSpace.SRGB,
        white_balance: WhiteBalance | str | None = None,
        adaptation: Adaptation | str = Adaptation.BRADFORD,
        false_colour: Path | None = None,
        false_colour_scale: str = "log",
        bit_depth: int = 8,
        denoise: bool = False,
        tile_rows: int | None = None,
        output: Path | None = None,
        display_server: str | None = None,
    ) -> RenderJob:
        """Check every setting and build the job. `scene`: the scene, or what loads it (called once the settings
        that need no scene have passed, so that a wrong one is named before any file is read). `output`: the image
        file, when there is one: spectral bands and asked-for AOVs need an .exr, and the scene's own AOVs are left
        out of another (a note says so). `display_server`: HOST:PORT of a tev viewer to stream the render to. A
        width without a height, or a height without a width, keeps the scene's aspect ratio. A Scene given as it is
        has its camera checked (`check_camera`); one a loader gives was checked by it."""
        from spectrace.film.aovs import parse_aovs
        from spectrace.scene.model import SAMPLER_TYPES, Scene

        if isinstance(scene, Scene):  # built in Python: what a scene file's loader checks of its camera, checked here
            check_camera(scene)
        _refuse(spp is not None and limits.spp_problem(spp), names.spp)
        _refuse(limits.pass_spp_problem(pass_spp), names.pass_spp)
        _refuse(_count_problem("spectral_bins", spectral_bins, 0), names.spectral_bins)
        _refuse(tile_rows is not None and _count_problem("tile_rows", tile_rows, 1), names.tile_rows)
        asked_aovs = parse_aovs(aovs, where=names.aovs) if aovs is not None else None
        if denoise:
            from spectrace.denoising import INSTALL_HINT, denoise_available

            _refuse(not denoise_available() and INSTALL_HINT, names.denoise)
        if sampler is not None and sampler not in SAMPLER_TYPES:
            raise SpectraceError(f"unknown sampler '{sampler}' (use {' or '.join(SAMPLER_TYPES)})", where=names.sampler)
        if integrator is not None:
            from spectrace.integrators import INTEGRATORS

            _refuse(limits.choice_problem("integrator", integrator, tuple(INTEGRATORS)), names.integrator)
        _refuse(seed is not None and limits.seed_problem(seed), names.seed)
        _refuse(max_depth is not None and limits.max_depth_problem(max_depth), names.max_depth)
        _refuse(exposure is not None and limits.exposure_problem(exposure), names.exposure)
        viewer = None
        if display_server is not None:
            from spectrace.io.tev import DisplayServer

            viewer = DisplayServer.parse(display_server, names.display_server)

        loaded = scene() if callable(scene) else scene
        width, height = _keeping_aspect(loaded, width, height)
        loaded = loaded.with_overrides(
            spp=spp,
            width=width,
            height=height,
            seed=seed,
            max_depth=max_depth,
            exposure=exposure,
            sampler=sampler,
            integrator=integrator,
            pixel_filter=pixel_filter,
        )
        if spp is None:  # the scene's own: a file's was checked as it was read, a Scene built in Python was not
            _refuse(limits.spp_problem(loaded.spp), str(loaded.source) if loaded.source else None)
        exr = output is None or output.suffix.lower() == ".exr"
        if spectral_bins and not exr:
            raise SpectraceError(f"{names.spectral_bins or 'spectral_bins'} needs an .exr output", where=str(output))
        if spectral_bins:
            from spectrace.film.state import spectral_bins_problem, spectral_range

            _refuse(spectral_bins_problem(spectral_bins, spectral_range(loaded)), names.spectral_bins)
        if asked_aovs and not exr:
            raise SpectraceError(f"{names.aovs} needs an .exr output", where=str(output))
        kept = loaded.aovs if asked_aovs is None else asked_aovs
        notes: tuple[str, ...] = ()
        if kept and not exr:
            assert output is not None
            notes = (
                f"note: the scene's film.aovs ({', '.join(kept)}) go to .exr files only; {output.name} gets the image",
            )
            kept = ()
        if denoise:
            from spectrace.denoising import RENDER_AOVS

            kept = tuple(dict.fromkeys((*kept, *RENDER_AOVS)))
        loaded = loaded.with_overrides(aovs=kept)
        if output is not None and (problem := output_format_problem(output)):
            raise SpectraceError(problem, where=str(output))
        if (width or height) and (problem := limits.film_size_problem(loaded.width, loaded.height)):
            raise SpectraceError(problem, where=names.size)
        outputs = RenderOutputOptions.parse(
            output,
            colour_space,
            white_balance,
            adaptation,
            false_colour,
            false_colour_scale,
            (names.colour_space, names.white_balance, names.adaptation),
            bit_depth=bit_depth,
        )
        return cls(
            loaded,
            device,
            kernel,
            pass_spp,
            spectral_bins,
            outputs,
            denoise,
            tile_rows,
            names,
            notes,
            display_server=viewer,
        )

    @property
    def spp(self) -> int:
        return self.scene.spp

    def with_scene(self, scene: Scene) -> RenderJob:
        """The same job for a changed scene (a setting the front end adds after the checks, as the ΔE map)."""
        return replace(self, scene=scene)

    def renderer(self, device: Device | str | None = None) -> Renderer:
        """A renderer of the whole film in this process, of the job's kernel shape."""
        from spectrace.engine.wavefront import make_renderer

        chosen = device if device is not None else self.device
        if self.spectral_bins:
            return make_renderer(self.scene, chosen, self.kernel, spectral_bins=self.spectral_bins)
        return make_renderer(self.scene, chosen, self.kernel)

    def tiles(self, rows: int | None = None) -> tuple[TileJob, RenderIdentity]:
        """The job split into tiles of `rows` rows (default: the job's) and the render's identity (for checkpoints),
        built here on the client: the scene buffers (BVH included) are built once, not once per worker."""
        from spectrace.device import Device
        from spectrace.engine.checkpoint import scene_identity
        from spectrace.engine.scene_buffers import build_scene_buffers
        from spectrace.engine.tiles import TileJob, plan_tiles, whole_film_rows
        from spectrace.film.state import spectral_range
        from spectrace.integrators import scene_settings_problem

        scene = self.scene
        if problem := limits.film_size_problem(scene.width, scene.height):
            # A scene file's size was checked as it was read: this one was set in Python (with_overrides, Scene),
            # so the message names the field, not the file.
            raise SpectraceError(problem)
        problem = (
            limits.scene_settings_problem(scene)
            or scene_settings_problem(scene)
            or limits.scene_geometry_problem(scene)
        )
        if problem:
            raise SpectraceError(problem, where=str(scene.source) if scene.source else None)
        tile_rows = whole_film_rows(scene, self.tile_rows if rows is None else rows)
        buffers = build_scene_buffers(scene)
        spectral_range_nm = spectral_range(scene)
        identity = scene_identity(scene, buffers, self.spectral_bins, spectral_range_nm)
        plan = plan_tiles(scene.width, scene.height, tile_rows)
        # Workers open the device by name: a device opened here goes by its key.
        device = self.device.report.key if isinstance(self.device, Device) else self.device
        tiles = TileJob.make(
            scene,
            buffers,
            plan,
            scene.spp,
            device,
            self.spectral_bins,
            spectral_range_nm,
            identity.scene_digest,
            identity.kernels_digest,
        )
        return tiles, identity

    def finish(self, image: Image) -> Image:
        """The image labelled with the job's colour output (its film XYZ untouched)."""
        return self.outputs.apply(image)
