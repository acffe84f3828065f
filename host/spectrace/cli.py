"""Command line: `spectrace render | devices | bench`. Errors print as one line and exit non-zero."""

import importlib
import json
import sys
from pathlib import Path
from typing import Annotated, Optional

import typer
from rich.console import Console
from typer.core import TyperGroup

from spectrace.errors import SpectraceError

# Sub-commands whose modules import colour-science, SciPy or the Mitsuba importer: listed in `--help` from these
# lines and imported only when run. name -> (module, attribute: a Typer app or a command function, help line).
LAZY_COMMANDS = {
    "display": ("spectrace.displays.cli", "display_app",
                "Displays as spectral emitters: the same RGB on LCD, OLED and CRT displays."),
    "spectra": ("spectrace.spectra_cli", "spectra_app",
                "Spectra: list the library's and a scene's spectra, and plot any of them."),
    "import-mitsuba": ("spectrace.interop.cli", "import_mitsuba_command",
                       "Convert a Mitsuba 3 XML scene to a spectrace TOML scene (docs/mitsuba.md)."),
}


def _load_command(name: str):
    module, attribute, _ = LAZY_COMMANDS[name]
    target = getattr(importlib.import_module(module), attribute)
    if not isinstance(target, typer.Typer):
        target, function = typer.Typer(add_completion=False, pretty_exceptions_enable=False), target
        target.command(name)(function)
    return typer.main.get_command(target)


class _LazyGroup(TyperGroup):
    """The top-level group: the lazy sub-commands stand as placeholders (name and help line) until one is run."""

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        for name, (_, _, help_line) in LAZY_COMMANDS.items():
            self.add_command(typer.core.TyperCommand(name, help=help_line), name)

    def resolve_command(self, ctx, args):
        name, command, rest = super().resolve_command(ctx, args)
        if name in LAZY_COMMANDS:
            command = self.commands[name] = _load_command(name)
        return name, command, rest


app = typer.Typer(
    cls=_LazyGroup,
    help="spectrace: a physically based spectral path tracer (OpenCL on CPU or GPU).",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)
console = Console(stderr=True, soft_wrap=True, markup=False)  # messages with long paths stay on one line

DeviceOption = Annotated[
    Optional[str],
    typer.Option("--device", "-d", help="Device key or substring (see `spectrace devices`); env SPECTRACE_DEVICE."),
]


@app.command()
def render(
    scene: Annotated[Path, typer.Argument(help="Scene file (TOML).")],
    output: Annotated[Path, typer.Option("--output", "-o", help="Output image: .png (sRGB) or .exr (linear).")],
    spp: Annotated[Optional[int], typer.Option(help="Samples per pixel (default: the scene's).", min=1)] = None,
    width: Annotated[Optional[int], typer.Option(help="Film width in pixels.", min=1)] = None,
    height: Annotated[Optional[int], typer.Option(help="Film height in pixels.", min=1)] = None,
    seed: Annotated[Optional[int], typer.Option(help="Sampler seed.", min=0)] = None,
    max_depth: Annotated[Optional[int], typer.Option(help="Path segments from the camera; -1 = unbounded.")] = None,
    sampler: Annotated[Optional[str], typer.Option(
        help="Sampler: sobol or independent (default: the scene's; see docs/sampling.md).")] = None,
    exposure: Annotated[Optional[float], typer.Option(help="Stops: RGB output x 2**exposure (film XYZ unscaled).")] = None,
    device: DeviceOption = None,
    xyz: Annotated[bool, typer.Option("--xyz/--no-xyz", help="EXR only: also store the film's X, Y, Z channels.")] = True,
    spectral_bins: Annotated[int, typer.Option(
        help="EXR only: also store N equal wavelength bands over 360-830 nm (spectral EXR, Fichet et al. 2021 "
             "layout; band-averaged radiance in W/(m² sr nm)).", min=0, max=471)] = 0,
    colour_space: Annotated[str, typer.Option("--colour-space", "--color-space", help=(
        "Colour space of the output: srgb, display-p3, rec2020 (linear in EXR, with that space's curve in PNG) or "
        "xyz (EXR only). See docs/colour.md."))] = "srgb",
    white_balance: Annotated[Optional[str], typer.Option(help=(
        "Adapt this white to the output's white (D65): a CIE illuminant (A, D50, FL2), a temperature (3200K), "
        "a chromaticity 'x,y' or a library spectrum."))] = None,
    adaptation: Annotated[str, typer.Option(help="White-balance transform: bradford or von-kries.")] = "bradford",
    false_color: Annotated[Optional[Path], typer.Option("--false-color", "--false-colour", help=(
        "Also write a false-colour map of the luminance (cd/m², 683 lm/W x integral of L ybar) with a scale bar "
        "(.png, .pdf, .svg)."))] = None,
    false_color_scale: Annotated[str, typer.Option(help="Scale of the false-colour map: log or linear.")] = "log",
    quiet: Annotated[bool, typer.Option("--quiet", "-q", help="No progress bar.")] = False,
    checkpoint: Annotated[Optional[Path], typer.Option(
        help="Save the render's state to this file every --checkpoint-interval seconds, when stopped, and at the "
             "end; --resume continues from it.")] = None,
    checkpoint_interval: Annotated[float, typer.Option(
        help="Seconds between checkpoints (0: after every pass).", min=0.0)] = 60.0,
    resume: Annotated[Optional[Path], typer.Option(
        help="Continue the render saved in this checkpoint (same scene, size and seed; --spp may be higher). "
             "Checkpoints then go to this file unless --checkpoint names another.")] = None,
    overwrite: Annotated[bool, typer.Option(
        "--overwrite", help="Start afresh although --checkpoint names an existing checkpoint, which is then "
                            "replaced (without it, such a render is refused: --resume continues it).")] = False,
    kernel: Annotated[str, typer.Option(
        help="Kernel shape: megakernel (the default, fastest on CPU runtimes as measured) or wavefront (one launch "
             "per path segment; path integrator only). Both give the same image.")] = "megakernel",
) -> None:
    """Render SCENE to an image. Ctrl-C or SIGTERM stops after the current pass and writes the samples done so far
    (and a checkpoint, with --checkpoint); a second Ctrl-C stops at once without writing."""
    from spectrace import cli_checks
    from spectrace.output_options import RenderOutputOptions
    from spectrace.engine.checkpoint import read_checkpoint
    from spectrace.engine.stop_signals import StopOnSignals
    from spectrace.engine.wavefront import make_renderer
    from spectrace.scene import load_scene
    from spectrace.scene.model import SAMPLER_TYPES

    if sampler is not None and sampler not in SAMPLER_TYPES:
        raise SpectraceError(f"unknown sampler '{sampler}' (use {' or '.join(SAMPLER_TYPES)})", where="--sampler")
    cli_checks.check_seed(seed)
    cli_checks.check_max_depth(max_depth)
    cli_checks.check_exposure(exposure)
    loaded = load_scene(scene).with_overrides(spp=spp, width=width, height=height, seed=seed, max_depth=max_depth,
                                              exposure=exposure, sampler=sampler)
    if spectral_bins and output.suffix.lower() != ".exr":
        raise SpectraceError("--spectral-bins needs an .exr output", where=str(output))
    _check_render_options(loaded, output, width, height, spp)
    outputs = RenderOutputOptions.parse(output, colour_space, white_balance, adaptation, false_color,
                                        false_color_scale)
    state_file = checkpoint or resume
    _check_output_files(scene, output, false_color, checkpoint, resume, overwrite)
    saved = read_checkpoint(resume) if resume is not None else None  # a bad file fails before the device work
    renderer = make_renderer(loaded, device, kernel, spectral_bins=spectral_bins)
    console.print(f"device: {renderer.device.report.key} ({renderer.device.report.device_name})", highlight=False,
                  markup=False)
    if saved is not None:
        _resume(renderer, saved, resume)
    with StopOnSignals() as stop:
        _render_passes(renderer, loaded.spp, stop, state_file, checkpoint_interval, quiet)
        interrupted = stop.requested
        image = renderer.image()
        if image.spp == 0:
            raise SpectraceError("interrupted before the first pass finished; nothing written")
        _write_image(outputs.apply(image), output, xyz, state_file)
        outputs.write_false_colour(image, log=lambda text: console.print(text, highlight=False, markup=False))
    pixels = image.width * image.height * image.spp
    note = " (interrupted: partial image)" if interrupted else ""
    console.print(
        f"wrote {output}: {image.width}x{image.height}, {image.spp} spp, {image.render_seconds:.2f} s, "
        f"{pixels / max(image.render_seconds, 1e-9) / 1e6:.2f} M samples/s{note}",
        highlight=False, markup=False,
    )
    if image.dropped_samples:
        console.print(f"warning: {image.dropped_samples} non-finite samples were dropped", highlight=False)
    if interrupted:
        raise typer.Exit(130)


def _check_render_options(scene, output: Path, width, height, spp) -> None:
    """Refuse what would fail only after the render (unknown format) or could never run."""
    from spectrace.scene import limits

    if output.suffix.lower() not in (".exr", ".png"):
        raise SpectraceError(f"unknown image format '{output.suffix}' (use .exr or .png)", where=str(output))
    if (width or height) and (problem := limits.film_size_problem(scene.width, scene.height)):
        raise SpectraceError(problem, where="--width/--height")
    if spp and (problem := limits.spp_problem(spp)):
        raise SpectraceError(problem, where="--spp")


def _check_output_files(scene: Path, output: Path, false_color: Optional[Path], checkpoint: Optional[Path],
                        resume: Optional[Path], overwrite: bool) -> None:
    """Before any device work: every file the render will write can be written, no two name the same file, none
    is the scene, and a fresh render does not replace a checkpoint that holds another render's samples."""
    from spectrace import cli_checks

    state_option, state_file = ("--checkpoint", checkpoint) if checkpoint is not None else ("--resume", resume)
    if overwrite and resume is not None:
        raise SpectraceError("starts the render afresh, so it cannot go with --resume", where="--overwrite")
    cli_checks.check_distinct_files({"--output": output, "--false-color": false_color, state_option: state_file},
                                    {"the scene file": scene})
    cli_checks.check_output_file(output, "--output")
    if false_color is not None:
        cli_checks.check_output_file(false_color, "--false-color")
    if state_file is not None:
        cli_checks.check_output_file(state_file, state_option)
    continued = resume is not None and checkpoint is not None and cli_checks.same_file(checkpoint, resume)
    if checkpoint is not None and checkpoint.exists() and not continued and not overwrite:
        raise SpectraceError(f"--checkpoint names a file that already exists; use --resume {checkpoint} to continue "
                             f"the render it holds, or --overwrite to start again and replace it",
                             where=str(checkpoint))


def _resume(renderer, restored, path: Path) -> None:
    from spectrace.engine.checkpoint import restore_checkpoint

    restore_checkpoint(renderer, restored, str(path))
    done, target = restored.state.samples_done, renderer.scene.spp
    note = f" (already at or beyond the {target} spp asked for)" if done >= target else ""
    console.print(f"resumed {path}: {done} spp done{note}", highlight=False, markup=False)
    if restored.device != renderer.device.report.key:
        console.print(f"warning: the checkpoint was rendered on {restored.device}; continuing on "
                      f"{renderer.device.report.key} gives an equally valid image, but not bit for bit the one an "
                      f"uninterrupted render would", highlight=False, markup=False)


def _render_passes(renderer, spp: int, stop, state_file: Optional[Path], interval: float, quiet: bool) -> None:
    """Render to `spp` with a progress bar until done or asked to stop; checkpoint on the way and at the end."""
    from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn, TimeRemainingColumn

    from spectrace.engine.checkpoint import PeriodicCheckpoints

    def warn(message: str) -> None:
        console.print(f"warning: {message}", highlight=False, markup=False)

    saver = PeriodicCheckpoints(state_file, renderer, interval, warn=warn) if state_file else None
    with Progress(
        TextColumn("rendering"), BarColumn(), TextColumn("{task.completed}/{task.total} spp"),
        TimeElapsedColumn(), TimeRemainingColumn(), console=console, disable=quiet,
    ) as bar:
        task = bar.add_task("render", total=spp, completed=renderer.samples_done)

        def on_pass(done: int, total: int) -> None:
            bar.update(task, completed=done)
            if saver is not None:
                saver.maybe_save()

        try:
            renderer.render(progress=on_pass, should_stop=stop)
        except SpectraceError as error:
            # An OpenCL failure mid-pass may leave part of a pass in the film: the film is not saved now, but the
            # last checkpoint, written between passes, is sound.
            if saver is None or saver.saved_samples is None:
                raise
            raise SpectraceError(f"{error.message}; {state_file} holds the last {saver.saved_samples} spp "
                                 f"(continue with --resume)", where=error.where) from None
    if saver is not None and renderer.samples_done > 0:
        saver.save()


def _write_image(image, output: Path, include_xyz: bool, state_file: Optional[Path]) -> None:
    try:
        image.write(output, include_xyz=include_xyz)
    except OSError as error:
        kept = f"; the render's state is in {state_file} (continue with --resume)" if state_file else ""
        raise SpectraceError(f"cannot write the image ({error.strerror or error}){kept}", where=str(output)) from None


@app.command()
def devices(as_json: Annotated[bool, typer.Option("--json", help="One JSON object on stdout.")] = False) -> None:
    """List every OpenCL platform and device found, with the build probe's result or why it failed."""
    from dataclasses import asdict

    from spectrace.device import device_table, discover_devices

    reports = discover_devices()
    if as_json:
        print(json.dumps({"devices": [asdict(r) for r in reports]}, indent=2))
        return
    Console(markup=False).print(device_table(reports))
    if not any(r.ok for r in reports):
        from spectrace.device import NoWorkingDeviceError

        raise NoWorkingDeviceError(reports)


@app.command()
def bench(
    size: Annotated[Optional[list[int]], typer.Option(help="Square image size(s) in pixels.")] = None,
    spp: Annotated[int, typer.Option(help="Samples per pixel per measurement.", min=1)] = 16,
    max_depth: Annotated[int, typer.Option(help="Path segments from the camera.")] = 8,
    scene: Annotated[Optional[Path], typer.Option(help="Scene file (default: the Cornell box).")] = None,
    device: DeviceOption = None,
    all_devices: Annotated[bool, typer.Option("--all", help="Every working device in turn.")] = False,
    as_json: Annotated[bool, typer.Option("--json", help="One JSON object on stdout.")] = False,
    samplers: Annotated[bool, typer.Option("--samplers", help=(
        "Instead compare the samplers: RMSE of independent and sobol at 4, 16, 64 spp against a long reference "
        "render (default size 32; see docs/sampling.md)."))] = False,
    peer: Annotated[Optional[str], typer.Option(help="Also render with this peer and compare: mitsuba.")] = None,
    quality: Annotated[bool, typer.Option("--quality", help="Error at equal time against a reference.")] = False,
    rays: Annotated[bool, typer.Option("--rays", help="Closest-hit rays/s on a large mesh, vs Embree.")] = False,
    scaling: Annotated[bool, typer.Option("--scaling", help="Throughput vs size, depth, triangles.")] = False,
    cold: Annotated[bool, typer.Option("--cold", help="Kernel build with empty caches, then warm.")] = False,
    triangles: Annotated[int, typer.Option(help="Largest mesh for --rays/--scaling.", min=20)] = 1_000_000,
    ray_count: Annotated[int, typer.Option(help="Rays for --rays.", min=1)] = 1_000_000,
    seconds: Annotated[float, typer.Option(help="Time budget per renderer for --quality.", min=0.0)] = 2.0,
    peer_sampler: Annotated[str, typer.Option(help=(
        "Mitsuba's sampler for --peer and --quality: independent (its default), stratified, multijitter, "
        "orthogonal, ldsampler."))] = "independent",
    kernel_shapes: Annotated[bool, typer.Option(
        "--kernel-shapes", help="Compare the megakernel and the wavefront at work-group sizes 1-32 and the "
                                "runtime's choice (medians of alternating repeats; one device, --device).")] = False,
) -> None:
    """Measure samples/s and rays/s (a benchmark, never a test); modes compare with Mitsuba 3 and Embree
    (docs/performance.md)."""
    _check_bench_options(size, max_depth, seconds)
    if samplers:
        from spectrace.benchmarks.samplers import sampler_bench_command
        return sampler_bench_command(scene, size, device, as_json, console)
    from spectrace.bench import run_render_bench, render_bench_table
    from spectrace.benchmarks.modes import BenchRequest, run_bench_modes

    if kernel_shapes:
        from spectrace.benchmarks.kernel_shapes import (kernel_shape_table, kernel_shape_variants,
                                                        run_kernel_shape_bench)

        results = run_kernel_shape_bench(scene, size or [256, 512], spp, max_depth, device, kernel_shape_variants(),
                                         log=lambda text: console.print(text, highlight=False))
        if as_json:
            print(json.dumps({"kernel_shapes": results}, indent=2))
        else:
            Console(width=150, markup=False).print(kernel_shape_table(results))
        return
    request = BenchRequest(scene, size, spp, max_depth, device, all_devices, peer, quality, rays, scaling, cold,
                           triangles, ray_count, seconds, peer_sampler)
    if request.any_mode():
        output, tables = run_bench_modes(request, log=lambda text: console.print(text, highlight=False))
        if as_json:
            print(json.dumps(output, indent=2))
        else:
            for table in tables:
                Console(width=160, markup=False).print(table)
        return
    results = run_render_bench(scene, sizes=size or [256, 512], spp=spp, max_depth=max_depth, device=device,
                               all_devices=all_devices, log=lambda text: console.print(text, highlight=False))
    if as_json:
        print(json.dumps({"render": results}, indent=2))
    else:
        Console(width=150, markup=False).print(render_bench_table(results))


def _check_bench_options(sizes: Optional[list[int]], max_depth: int, seconds: float) -> None:
    """The limits the render command applies, for the options bench shares with it."""
    from spectrace import cli_checks
    from spectrace.scene import limits

    cli_checks.check_max_depth(max_depth)
    cli_checks.check_finite(seconds, "--seconds")
    for size in sizes or []:
        if problem := limits.film_size_problem(size, size):
            raise SpectraceError(problem, where="--size")


@app.command()
def validate(
    case: Annotated[Optional[list[str]], typer.Option(help="Run only these cases (default: all).")] = None,
    device: DeviceOption = None,
    as_json: Annotated[bool, typer.Option("--json", help="One JSON object on stdout.")] = False,
) -> None:
    """Check the laws of radiometry numerically: each law, its analytic value, the renderer's measurement ±
    its standard error, and pass/fail (|difference| <= 4 standard errors). Exits 1 if any check fails."""
    from rich.table import Table

    from spectrace.validation import CASES, run_validation

    unknown = [c for c in case or [] if c not in CASES]
    if unknown:
        raise SpectraceError(f"unknown validation case(s) {', '.join(unknown)}; cases: {', '.join(CASES)}")
    checks = run_validation(case, device)
    if as_json:
        print(json.dumps({"checks": [c.as_dict() for c in checks]}, indent=2))
    else:
        table = Table(title="spectrace validate: the laws of radiometry, measured")
        for column in ("case", "law", "analytic", "measured ± s.e.", "unit", "result"):
            table.add_column(column)
        for c in checks:
            result = {True: "pass", False: "FAIL", None: "(figure)"}[c.passed]
            analytic = "" if c.reported_only else f"{c.analytic:.6g}"
            table.add_row(c.case, c.law, analytic, f"{c.measured:.6g} ± {c.standard_error:.2g}", c.unit, result)
        Console(width=160, markup=False).print(table)
    if any(c.passed is False for c in checks):
        raise typer.Exit(1)


def _usage_error_type() -> type[Exception]:
    """Click's UsageError (bad option values, unknown options, missing arguments); recent typer versions carry
    their own copy of click."""
    try:
        from typer._click.exceptions import UsageError
    except ImportError:
        from click.exceptions import UsageError
    return UsageError


def _usage_error_line(exc: Exception) -> str:
    """One line, like every other error: the option, what is wrong with its value, and where the help is."""
    param, reason = getattr(exc, "param", None), getattr(exc, "message", "")
    if param is not None and param.opts and reason:
        message = f"{param.opts[0]}: {reason}"
    else:  # unknown options, missing arguments: click's own sentence names them
        message = exc.format_message()
    message = " ".join(message.split())
    context = getattr(exc, "ctx", None)
    if context is not None:
        message += f" (see `{context.command_path} --help`)"
    return f"error: {message}"


# Help printed to a pipe or a file: rich would assume 80 columns and cut long option names ("--colour-space,-…").
PIPED_HELP_COLUMNS = 120


def _set_help_width() -> None:
    """Read by typer when it first formats help: COLUMNS when set (what rich itself honours), else wide enough for
    every option name when stdout is no terminal; a terminal's own width otherwise."""
    import os

    if "TERMINAL_WIDTH" in os.environ:
        return
    if columns := os.environ.get("COLUMNS"):
        os.environ["TERMINAL_WIDTH"] = columns
    elif not sys.stdout.isatty():
        os.environ["TERMINAL_WIDTH"] = str(PIPED_HELP_COLUMNS)


def main() -> None:
    try:
        _set_help_width()
        usage_error = _usage_error_type()
        # Not standalone, so that a bad option value reaches the handler below instead of click's framed box.
        status = app(standalone_mode=False)
        sys.exit(status if isinstance(status, int) else 0)
    except KeyboardInterrupt:  # first: `usage_error` is unbound if Ctrl-C came before it was
        console.print("interrupted", highlight=False)
        sys.exit(130)
    except usage_error as exc:
        if type(exc).__name__ != "NoArgsIsHelpError":  # that one has already printed the help
            console.print(_usage_error_line(exc), highlight=False, markup=False, soft_wrap=True)
        sys.exit(exc.exit_code)
    except typer.Abort:
        console.print("aborted", highlight=False)
        sys.exit(1)
    except SpectraceError as exc:
        console.print(f"error: {exc}", highlight=False, markup=False, soft_wrap=True)
        sys.exit(2)
    except MemoryError:
        console.print("error: out of host memory (a smaller film, --width/--height, needs less)", highlight=False)
        sys.exit(2)
    except Exception as exc:
        opencl = sys.modules.get("pyopencl")
        if opencl is None or not isinstance(exc, opencl.Error):
            raise
        from spectrace.engine.opencl_errors import describe_opencl_error

        console.print(f"error: {describe_opencl_error(exc, 'running', 'the OpenCL device')}", highlight=False,
                      markup=False, soft_wrap=True)
        sys.exit(2)


if __name__ == "__main__":
    main()
