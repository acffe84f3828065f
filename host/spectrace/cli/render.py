"""`spectrace render`: a scene file to an image, with checkpoints and a clean stop on Ctrl-C, SIGTERM or SIGHUP."""

from contextlib import contextmanager
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from spectrace.cli.common import DeviceOption, console
from spectrace.errors import SpectraceError

if TYPE_CHECKING:
    from spectrace.io.output_lock import OutputLocks


def render(
    scene: Annotated[
        Path,
        typer.Argument(
            help="Scene file: spectrace TOML, Mitsuba 3 XML, pbrt-v4, glTF 2.0 (.gltf, .glb) or Blender (.blend), "
            "imported on the way in (the format from the suffix, else from the first bytes); or a bundled scene's "
            "name (cornell_box)."
        ),
    ],
    output: Annotated[
        Path,
        typer.Option(
            "--output",
            "-o",
            help="Output image: .exr (linear float), .png, .tif, .jpg (display-encoded) or .pfm (linear float RGB).",
        ),
    ],
    spp: Annotated[int | None, typer.Option(help="Samples per pixel (default: the scene's).", min=1)] = None,
    width: Annotated[
        int | None,
        typer.Option(help="Film width in pixels; alone, the height follows the scene's aspect ratio.", min=1),
    ] = None,
    height: Annotated[
        int | None,
        typer.Option(help="Film height in pixels; alone, the width follows the scene's aspect ratio.", min=1),
    ] = None,
    seed: Annotated[int | None, typer.Option(help="Sampler seed.", min=0)] = None,
    max_depth: Annotated[int | None, typer.Option(help="Path segments from the camera; -1 = unbounded.")] = None,
    sampler: Annotated[
        str | None, typer.Option(help="Sampler: sobol or independent (default: the scene's; see docs/sampling.md).")
    ] = None,
    exposure: Annotated[float | None, typer.Option(help="Stops: RGB output x 2**exposure (film XYZ unscaled).")] = None,
    integrator: Annotated[
        str | None,
        typer.Option(help="Integrator, replacing the scene's integrator.type (see docs/integrators.md)."),
    ] = None,
    settings: Annotated[
        list[str] | None,
        typer.Option(
            "--set",
            metavar="KEY.PATH=VALUE",
            help="Replace a value of the scene at a dotted key path, as if the file said so (repeatable), e.g. "
            "--set film.exposure=1 --set 'materials.red.reflectance={ rgb = [0.6, 0.1, 0.1] }'. VALUE is read as a "
            "TOML value, or as text when it is none; an imported scene takes the keys of the TOML its import writes.",
        ),
    ] = None,
    device: DeviceOption = None,
    xyz: Annotated[
        bool, typer.Option("--xyz/--no-xyz", help="EXR only: also store the film's X, Y, Z channels.")
    ] = True,
    spectral_bins: Annotated[
        int,
        typer.Option(
            help="EXR only: also store N equal wavelength bands over the film's wavelengths (film.wavelengths, "
            "360-830 nm by default; at most one band per nm) (spectral EXR, Fichet et al. 2021 layout; band-averaged "
            "radiance in W/(m² sr nm)).",
            min=0,
            max=2301,
        ),
    ] = 0,
    delta_e_map: Annotated[
        bool,
        typer.Option(
            "--delta-e-map",
            help="EXR only: also store a deltaE00 channel, the per-pixel CIEDE2000 between the first two observers of "
            "the scene's film.observers (each in CIELAB against its own D65 white at the scene's white Y), and "
            "write it as a false-colour map <output stem>.deltaE00.png beside the EXR (see docs/colour.md).",
        ),
    ] = False,
    delta_e_white_y: Annotated[
        float | None,
        typer.Option(
            help="Film Y of the --delta-e-map's reference white (CIELAB's Y_n), e.g. the Y of a white patch in the "
            "scene (default: the Y of the brightest area of 3x3 pixels or more).",
        ),
    ] = None,
    colour_space: Annotated[
        str,
        typer.Option(
            "--colour-space",
            "--color-space",
            help=(
                "Colour space of the output: srgb, display-p3, rec2020 (linear in EXR, with that space's curve in "
                "PNG) or xyz (EXR only). See docs/colour.md."
            ),
        ),
    ] = "srgb",
    white_balance: Annotated[
        str | None,
        typer.Option(
            help=(
                "Adapt this white to the output's white (D65): a CIE illuminant (A, D50, FL2), a temperature (3200K), "
                "a chromaticity 'x,y' or a library spectrum."
            )
        ),
    ] = None,
    adaptation: Annotated[str, typer.Option(help="White-balance transform: bradford or von-kries.")] = "bradford",
    bit_depth: Annotated[int, typer.Option(help="Bits per sample of a .png or .tif output: 8 or 16.")] = 8,
    false_color: Annotated[
        Path | None,
        typer.Option(
            "--false-color",
            "--false-colour",
            help=(
                "Also write a false-colour map of the luminance (cd/m², 683 lm/W x integral of L ybar) with a scale "
                "bar (.png, .pdf, .svg)."
            ),
        ),
    ] = None,
    false_color_scale: Annotated[str, typer.Option(help="Scale of the false-colour map: log or linear.")] = "log",
    pixel_filter: Annotated[
        str | None,
        typer.Option(
            "--filter",
            help="Pixel filter, replacing the scene's film.filter: TYPE or TYPE:KEY=VALUE,... with TYPE box, tent, "
            "gaussian or mitchell and the keys of docs/scene-format.md's filter table, e.g. "
            "gaussian:stddev=0.5,radius=2.",
        ),
    ] = None,
    quiet: Annotated[
        bool, typer.Option("--quiet", "-q", help="No progress bar and no messages but warnings and errors.")
    ] = False,
    checkpoint: Annotated[
        Path | None,
        typer.Option(
            help="Save the render's state to this file every --checkpoint-interval seconds, when stopped, and at the "
            "end; --resume continues from it."
        ),
    ] = None,
    checkpoint_interval: Annotated[
        float, typer.Option(help="Seconds between checkpoints (0: after every pass).", min=0.0)
    ] = 60.0,
    resume: Annotated[
        Path | None,
        typer.Option(
            help="Continue the render saved in this checkpoint (same scene, size and seed; --spp may be higher). "
            "Checkpoints then go to this file unless --checkpoint names another."
        ),
    ] = None,
    overwrite: Annotated[
        bool,
        typer.Option(
            "--overwrite",
            help="Start afresh although --checkpoint names an existing checkpoint, which is then "
            "replaced (without it, such a render is refused: --resume continues it).",
        ),
    ] = False,
    aov: Annotated[
        str | None,
        typer.Option(
            "--aov",
            help="EXR only: also store these AOVs, comma-separated: albedo, normal, depth, position, variance "
            "(standard error of Y), emission (directly seen, as its expected value); replaces the scene's film.aovs. "
            "See docs/scene-format.md.",
        ),
    ] = None,
    denoise: Annotated[
        bool,
        typer.Option(
            "--denoise",
            help="Denoise with Open Image Denoise (the spectrace[denoise] extra), guided by the albedo and normal "
            "AOVs (recorded for it); the emitters seen directly are rendered apart by camera rays alone at "
            "max(32, 2 spp) and replace the image's own (docs/integrators.md). --output gets the denoised image, "
            "<stem>.noisy<suffix> beside it the noisy one (replacing only an earlier --denoise render's noisy image "
            "of the same output; any other file there is refused).",
        ),
    ] = False,
    kernel: Annotated[
        str,
        typer.Option(
            help="Kernel shape: megakernel (the default, fastest on CPU runtimes as measured) or wavefront (one launch "
            "per path segment; path integrator only). Both give the same image."
        ),
    ] = "megakernel",
    cluster: Annotated[
        str | None,
        typer.Option(
            help="Render on the Dask scheduler at this address (tcp://host:8786), split into tiles; the image is "
            "bit-identical to one rendered here on the same device type (docs/distributed.md).",
        ),
    ] = None,
    workers: Annotated[
        int | None,
        typer.Option(
            help="Render split into tiles on a Dask LocalCluster of N worker processes on this machine (at most its "
            "cores; more than the tiles are not started).",
            min=1,
        ),
    ] = None,
    tile_rows: Annotated[
        int | None,
        typer.Option(
            help="With --cluster or --workers (only): film rows per tile (default: at most 65536 pixels, at least 16 "
            "tiles; the light, bdpt and sppm integrators render the whole film as one tile).",
            min=1,
        ),
    ] = None,
    cluster_timeout: Annotated[
        float,
        typer.Option(help="Seconds to wait for the --cluster scheduler to answer (0.1 to 86400, a day).", min=0.1),
    ] = 30.0,
    display_server: Annotated[
        str | None,
        typer.Option(
            "--display-server",
            metavar="HOST:PORT",
            help="Show the image in the tev viewer listening there (tev's default: 127.0.0.1:14158) as it "
            "converges: the output's linear R, G, B as the EXR holds them, the last update the image written. A "
            "viewer absent or gone is one warning; the render goes on. A render here only (not --workers or "
            "--cluster).",
        ),
    ] = None,
) -> None:
    """Render SCENE to an image. Ctrl-C, SIGTERM or SIGHUP (a closed terminal) stops after the current pass and
    writes the samples done so far (and a checkpoint, with --checkpoint); a second Ctrl-C stops at once without
    writing."""
    console.quiet = quiet
    job = _job_from_options(
        scene,
        output,
        integrator=integrator,
        settings=settings,
        spp=spp,
        width=width,
        height=height,
        seed=seed,
        max_depth=max_depth,
        sampler=sampler,
        exposure=exposure,
        device=device,
        spectral_bins=spectral_bins,
        delta_e_map=delta_e_map,
        delta_e_white_y=delta_e_white_y,
        colour_space=colour_space,
        white_balance=white_balance,
        adaptation=adaptation,
        bit_depth=bit_depth,
        false_color=false_color,
        false_color_scale=false_color_scale,
        pixel_filter=pixel_filter,
        aov=aov,
        denoise=denoise,
        kernel=kernel,
        tile_rows=tile_rows,
        display_server=display_server,
    )
    state_file = checkpoint or resume
    noisy = None
    if denoise:
        from spectrace.denoising import noisy_path_for

        noisy = noisy_path_for(output)
    if delta_e_map:
        from spectrace.cli import checks as cli_checks
        from spectrace.cli.render_output import delta_e_map_path

        cli_checks.check_output_file(delta_e_map_path(output), "--delta-e-map")
    with _check_output_files(scene, output, false_color, checkpoint, resume, overwrite, noisy):
        from spectrace.engine.checkpoint import read_checkpoint

        saved = read_checkpoint(resume) if resume is not None else None  # a bad file fails before the device work
        resumes_tiles = saved is not None and saved.tiles is not None
        if tile_rows is not None and cluster is None and workers is None and not resumes_tiles:
            raise SpectraceError(
                "splits a render over --workers or --cluster (or resumes a tiled checkpoint); a render here is one "
                "piece",
                where="--tile-rows",
            )
        if job.display_server is not None and (cluster is not None or workers is not None or resumes_tiles):
            raise SpectraceError(
                "streams a render made here in one piece; it does not go with --workers, --cluster or a tiled "
                "checkpoint",
                where="--display-server",
            )
        if cluster is not None or workers is not None or resumes_tiles:
            from spectrace.cli.render_tiles import render_tiled

            render_tiled(
                job,
                output,
                xyz=xyz,
                quiet=quiet,
                state_file=state_file,
                checkpoint_interval=checkpoint_interval,
                saved=saved,
                resume=resume,
                cluster=cluster,
                workers=workers,
                cluster_timeout=cluster_timeout,
                noisy=noisy,
            )
            return
        _render_here(job, output, xyz, quiet, state_file, checkpoint_interval, saved, resume, noisy)


def _say(text: str) -> None:
    console.say(text)


def _job_from_options(
    scene: Path,
    output: Path,
    *,
    delta_e_map: bool,
    delta_e_white_y: float | None,
    colour_space: str,
    white_balance: str | None,
    false_color: Path | None,
    false_color_scale: str,
    pixel_filter: str | None,
    aov: str | None,
    settings: list[str] | None,
    **options,
):
    """The render's RenderJob from the command's options (every check made there, under the options' names), with
    the ΔE map the command adds to the scene's film."""
    from spectrace.cli.scene_settings import named_by_option, parse_settings
    from spectrace.engine.job import COMMAND_LINE, RenderJob
    from spectrace.interop.scene_files import load_any_scene

    chosen_filter = None
    if pixel_filter is not None:
        from spectrace.pixel_filters import parse_filter_option

        chosen_filter = parse_filter_option(pixel_filter)

    overrides = parse_settings(settings or [], "--set")

    def loaded():
        try:
            return load_any_scene(scene, overrides or None, report=_say)
        except SpectraceError as error:
            if not overrides:
                raise
            where = error.where.split(": ", 1)[0] if error.where else ""
            raise named_by_option(error, Path(where), overrides, "--set") from None

    job = RenderJob.make(
        loaded,
        COMMAND_LINE,
        output=output,
        pixel_filter=chosen_filter,
        aovs=aov,
        colour_space=colour_space,
        white_balance=white_balance or None,
        false_colour=false_color,
        false_colour_scale=false_color_scale,
        **options,
    )
    for note in job.notes:
        _say(note)
    if delta_e_map:
        response = _with_delta_e_map(job.scene.film_response, output, delta_e_white_y)
        job = job.with_scene(job.scene.with_overrides(film_response=response))
    return job


def _render_here(job, output: Path, xyz: bool, quiet: bool, state_file, interval: float, saved, resume, noisy):
    """The render in one piece on one device of this machine, then its files."""
    from spectrace.cli.render_output import write_render
    from spectrace.engine.stop_signals import StopOnSignals
    from spectrace.session import Session

    # The same session `spectrace.render` and the viewer render through; a command-line render is its first passes.
    with Session.for_job(job) as session:
        renderer = session.renderer
        report = renderer.device.report
        _say(f"device: {report.key} ({report.device_name})")
        _say(_scene_line(renderer.buffers))
        identity = _resume(renderer, saved, resume) if saved is not None and resume is not None else None
        with StopOnSignals() as stop, _display(job, output) as display:
            _render_passes(renderer, stop, state_file, interval, quiet, identity, display)
            interrupted = stop.requested
            image = renderer.image()
            if image.spp == 0:
                raise SpectraceError("interrupted before the first pass finished; nothing written")
            image = write_render(
                job,
                image,
                output,
                include_xyz=xyz,
                state_file=state_file,
                noisy=noisy,
                device=renderer.device,
                log=_say,
            )
        if display is not None:
            display.finish(image)
        pixels = image.width * image.height * image.spp
        note = " (interrupted: partial image)" if interrupted else ""
        note += f" (denoised; the noisy image is {noisy})" if noisy is not None else ""
        _say(
            f"wrote {output}: {image.width}x{image.height}, {image.spp} spp, {image.render_seconds:.2f} s, "
            f"{pixels / max(image.render_seconds, 1e-9) / 1e6:.2f} M samples/s{note}"
        )
    if image.dropped_samples:
        console.print(f"warning: {image.dropped_samples} non-finite samples were dropped", highlight=False)
    if interrupted:
        raise typer.Exit(130)


def _warn(message: str) -> None:
    console.print(f"warning: {message}", highlight=False, markup=False)


@contextmanager
def _display(job, output: Path):
    """The job's image in tev as it renders (spectrace.engine.display_stream), named as the output file; None
    without --display-server. A render that fails or is stopped at once leaves tev what it has."""
    if job.display_server is None:
        yield None
        return
    from spectrace.engine.display_stream import RenderDisplay

    display = RenderDisplay(job, output.name, _warn)
    try:
        yield display
    except BaseException:
        display.close()
        raise


def _scene_line(buffers) -> str:
    peak = f", peak {buffers.bvh_peak_bytes / 2**20:.0f} MiB" if buffers.bvh_peak_bytes is not None else ""
    object_shapes = f" and {buffers.instanced_shape_count} analytic shapes" if buffers.instanced_shape_count else ""
    instanced = (
        f" + {buffers.instance_count} instances of {buffers.instanced_triangle_count} object triangles"
        f"{object_shapes} stored once"
        if buffers.instance_count
        else ""
    )
    return f"scene: {buffers.triangle_count} triangles{instanced}, BVH built in {buffers.bvh_seconds:.2f} s{peak}"


def _with_delta_e_map(response, output: Path, white_y: float | None):
    from dataclasses import replace

    import numpy as np

    if white_y is not None and not (np.isfinite(white_y) and white_y > 0):
        raise SpectraceError(f"must be a positive number, got {white_y}", where="--delta-e-white-y")

    if output.suffix.lower() != ".exr":
        raise SpectraceError("--delta-e-map needs an .exr output", where=str(output))
    if len(response.observers) < 2:
        raise SpectraceError("compares the first two of film.observers; the scene lists fewer", where="--delta-e-map")
    from spectrace.plot_extra import require_matplotlib

    require_matplotlib("--delta-e-map")  # its picture
    return replace(response, delta_e_pair=(response.observers[0], response.observers[1]), delta_e_white_y=white_y)


def _check_output_files(
    scene: Path,
    output: Path,
    false_color: Path | None,
    checkpoint: Path | None,
    resume: Path | None,
    overwrite: bool,
    noisy: Path | None = None,
) -> "OutputLocks":
    """Before any device work: every file the render will write can be written, no two name the same file, none
    is the scene, no other command is writing one (their locks, held until the returned OutputLocks exits), and a
    fresh render does not replace a checkpoint that holds another render's samples."""
    from spectrace.cli import checks as cli_checks
    from spectrace.io.output_lock import OutputLocks

    state_option, state_file = ("--checkpoint", checkpoint) if checkpoint is not None else ("--resume", resume)
    if overwrite and resume is not None:
        raise SpectraceError("starts the render afresh, so it cannot go with --resume", where="--overwrite")
    cli_checks.check_distinct_files(
        {"--output": output, "--false-color": false_color, state_option: state_file, "--denoise": noisy},
        {"the scene file": scene},
    )
    cli_checks.check_output_file(output, "--output")
    if noisy is not None:
        from spectrace.denoising import check_noisy_path

        cli_checks.check_output_file(noisy, "--denoise")
        check_noisy_path(noisy, output)
    if false_color is not None:
        cli_checks.check_output_file(false_color, "--false-color")
    if state_file is not None:
        cli_checks.check_output_file(state_file, state_option)
    locks = OutputLocks(
        {"--output": output, "--denoise": noisy, "--false-color": false_color, state_option: state_file},
        command="spectrace render",
    )
    continued = resume is not None and checkpoint is not None and cli_checks.same_file(checkpoint, resume)
    if checkpoint is not None and checkpoint.exists() and not continued and not overwrite:
        locks.release()
        raise SpectraceError(
            f"--checkpoint names a file that already exists; use --resume {checkpoint} to continue "
            f"the render it holds, or --overwrite to start again and replace it",
            where=str(checkpoint),
        )
    return locks


def _resume(renderer, restored, path: Path):
    """Load the checkpoint; returns the render's identity (see restore_checkpoint)."""
    from spectrace.engine.checkpoint import restore_checkpoint

    identity = restore_checkpoint(renderer, restored, str(path))
    done, target = restored.state.samples_done, renderer.scene.spp
    note = f" (already at or beyond the {target} spp asked for)" if done >= target else ""
    _say(f"resumed {path}: {done} spp done{note}")
    if restored.device != renderer.device.report.key:
        console.print(
            f"warning: the checkpoint was rendered on {restored.device}; continuing on "
            f"{renderer.device.report.key} gives an equally valid image, but not bit for bit the one an "
            f"uninterrupted render would",
            highlight=False,
            markup=False,
        )
    return identity


def _render_passes(
    renderer, stop, state_file: Path | None, interval: float, quiet: bool, identity=None, display=None
) -> None:
    """The API's render loop with the bar on this console (none with -q), checkpoints to `state_file`
    (`identity`: the render's, when --resume has computed it) and each pass shown on `display` (a RenderDisplay)."""
    from spectrace.api import render_passes
    from spectrace.engine.checkpoint import PeriodicCheckpoints

    saver = PeriodicCheckpoints(state_file, renderer, interval, warn=_warn, identity=identity) if state_file else None
    each_pass = (lambda: display.after_pass(renderer)) if display is not None else None
    try:
        render_passes(
            renderer, progress=not quiet, stop=stop, checkpoints=saver, console=console.rich(), each_pass=each_pass
        )
    except SpectraceError as error:
        # An OpenCL failure mid-pass may leave part of a pass in the film: the film is not saved now, but the
        # last checkpoint, written between passes, is sound.
        if saver is None or saver.saved_samples is None:
            raise
        raise SpectraceError(
            f"{error.message}; {state_file} holds the last {saver.saved_samples} spp (continue with --resume)",
            where=error.where,
        ) from None
