"""`spectrace bench [MODE]`: throughput measurements and comparisons with peers (docs/performance.md).

`spectrace bench` alone is the plain render bench, with its options; each mode is a subcommand with only the
options it reads. The plain bench is the group's callback (typer's `invoke_without_command`), so its options stand
before any mode name: given there with a mode, they would be read by nothing, and are refused."""

import json
from collections.abc import Callable
from pathlib import Path
from typing import Annotated

import typer

from spectrace.benchmarks.bench_rounds import DEFAULT_ROUNDS
from spectrace.cli.common import GROUP_SETTINGS, DeviceOption, JsonOption, console
from spectrace.errors import SpectraceError

PEER_DEFAULT_SIZE = 512
PEER_DEFAULT_ROUNDS = DEFAULT_ROUNDS
QUALITY_DEFAULT_SIZE = 128
QUALITY_REFERENCE_SPP = 1024
COLD_DEFAULT_SIZE = 256
SAMPLERS_DEFAULT_SIZE = 32
DENOISE_DEFAULT_SIZE = 128
RENDER_DEFAULT_SIZES = [256, 512]

# spectrace.integrators.INTEGRATORS' names, written out: the help must not import the integrators (and their
# kernels' host code); tests/cli/test_help_names.py keeps the two the same.
INTEGRATOR_NAMES = "path, direct, light, bdpt or sppm"

SizesOption = Annotated[list[int] | None, typer.Option("--size", help="Square image size(s) in pixels, repeatable.")]
SppOption = Annotated[int, typer.Option(help="Samples per pixel per measurement.", min=1)]
MaxDepthOption = Annotated[int, typer.Option(help="Path segments from the camera.")]
IntegratorOption = Annotated[
    str | None,
    typer.Option(help=f"Integrator to time: {INTEGRATOR_NAMES} (default: the scene's)."),
]
SceneOption = Annotated[Path | None, typer.Option(help="Scene file (default: the Cornell box).")]
AllOption = Annotated[bool, typer.Option("--all", help="Every working device in turn.")]
TrianglesOption = Annotated[int, typer.Option(help="Triangles of the largest mesh.", min=20)]
PeerSamplerOption = Annotated[
    str,
    typer.Option(
        help=("Mitsuba's sampler: independent (its default), stratified, multijitter, orthogonal, ldsampler.")
    ),
]


def _size_help(default: int) -> str:
    return f"Square image size in pixels (default {default})."


# One alias per mode: a type checker takes only names, not calls, as annotations.
PeerSizeOption = Annotated[int | None, typer.Option("--size", help=_size_help(PEER_DEFAULT_SIZE))]
QualitySizeOption = Annotated[int | None, typer.Option("--size", help=_size_help(QUALITY_DEFAULT_SIZE))]
ColdSizeOption = Annotated[int | None, typer.Option("--size", help=_size_help(COLD_DEFAULT_SIZE))]
SamplersSizeOption = Annotated[int | None, typer.Option("--size", help=_size_help(SAMPLERS_DEFAULT_SIZE))]
DenoiseSizeOption = Annotated[int | None, typer.Option("--size", help=_size_help(DENOISE_DEFAULT_SIZE))]


def _check_integrators(names: list[str], option: str) -> None:
    """Names from the integrator registry (spectrace.integrators.INTEGRATORS), so a new integrator is benched as
    soon as it is registered there."""
    from spectrace.integrators import INTEGRATORS

    for name in names:
        if name not in INTEGRATORS:
            raise SpectraceError(f"unknown integrator {name!r}; choose {', '.join(INTEGRATORS)}", where=option)


def _one(size: int | None) -> list[int] | None:
    return None if size is None else [size]


def _or(size: int | None, default: int) -> int:
    return default if size is None else size


def _log(text: str) -> None:
    console.print(text, highlight=False)


def _check(sizes: list[int] | None = None, max_depth: int | None = None, seconds: float | None = None) -> None:
    """The limits the render command applies, for the options a bench shares with it."""
    from spectrace.cli import checks
    from spectrace.core import limits

    checks.check_max_depth(max_depth)
    checks.check_finite(seconds, "--seconds")
    for size in sizes or []:
        if problem := limits.film_size_problem(size, size):
            raise SpectraceError(problem, where="--size")


def _emit(mode: str, result, tables: Callable[[], list], as_json: bool, width: int = 160) -> None:
    """One JSON object {mode: result} on stdout, or the mode's tables; notes a mode left go to stderr first."""
    for note in result.get("notes", []) if isinstance(result, dict) else []:
        _log(f"note ({mode}): {note}")
    if as_json:
        print(json.dumps({mode: result}, indent=2))
        return
    from rich.console import Console

    for table in tables():
        Console(width=width, markup=False).print(table)


bench_app = typer.Typer(
    help="Measure samples/s and rays/s (a benchmark, never a test). Alone, it times the Cornell box (or --scene) "
    "at each --size; a mode compares with Mitsuba 3 or Embree or measures one thing more (docs/performance.md).",
    **GROUP_SETTINGS,
)


@bench_app.callback(invoke_without_command=True)
def render_bench(
    ctx: typer.Context,
    size: SizesOption = None,
    spp: SppOption = 16,
    max_depth: MaxDepthOption = 8,
    scene: SceneOption = None,
    integrator: IntegratorOption = None,
    device: DeviceOption = None,
    all_devices: AllOption = False,
    as_json: JsonOption = False,
) -> None:
    if ctx.invoked_subcommand is not None:
        given = [
            param
            for param in ctx.command.params
            if getattr(ctx.get_parameter_source(param.name), "name", "DEFAULT") != "DEFAULT"
        ]
        if given:
            option = given[0].opts[0]
            raise SpectraceError(
                f"belongs to the plain render bench; give `spectrace bench "
                f"{ctx.invoked_subcommand}` its own options after the mode's name",
                where=option,
            )
        return
    _check(size, max_depth)
    from spectrace.benchmarks.render import render_bench_table, run_render_bench

    _check_integrators([integrator] if integrator is not None else [], "--integrator")

    results = run_render_bench(
        scene,
        sizes=size or RENDER_DEFAULT_SIZES,
        spp=spp,
        max_depth=max_depth,
        device=device,
        all_devices=all_devices,
        log=_log,
        integrator=integrator,
    )
    _emit("render", results, lambda: [render_bench_table(results)], as_json, width=150)


@bench_app.command("peer")
def peer_bench(
    size: PeerSizeOption = None,
    spp: SppOption = 16,
    max_depth: MaxDepthOption = 8,
    scene: SceneOption = None,
    device: DeviceOption = None,
    all_devices: AllOption = False,
    peer_sampler: PeerSamplerOption = "independent",
    rounds: Annotated[
        int, typer.Option(help="Alternated rounds (spectrace, Mitsuba, spectrace, ...); median and spread.", min=1)
    ] = PEER_DEFAULT_ROUNDS,
    per_core: Annotated[
        bool,
        typer.Option(
            "--per-core",
            help="One core each: every thread pinned to one core, one compute unit of each OpenCL runtime (device "
            "fission) against Dr.Jit with one thread.",
        ),
    ] = False,
    as_json: JsonOption = False,
) -> None:
    """The same scene rendered by spectrace and by Mitsuba 3 (needs the bench extra), timed side by side in
    alternated rounds with the load between them, with a check that the images agree."""
    _check(_one(size), max_depth)
    from spectrace.benchmarks.peer_mitsuba import peer_tables, run_peer_bench

    try:
        result = run_peer_bench(
            scene,
            _or(size, PEER_DEFAULT_SIZE),
            spp,
            max_depth,
            device,
            all_devices,
            rounds=rounds,
            log=_log,
            peer_sampler=peer_sampler,
            per_core=per_core,
        )
    except ImportError:
        raise SpectraceError(
            "the Mitsuba comparison needs mitsuba: pip install 'spectrace[bench]'", where="bench peer"
        ) from None
    _emit("peer", result, lambda: peer_tables(result), as_json)


@bench_app.command("quality")
def quality_bench(
    size: QualitySizeOption = None,
    seconds: Annotated[float, typer.Option(help="Time budget per renderer.", min=0.0)] = 2.0,
    max_depth: MaxDepthOption = 8,
    scene: SceneOption = None,
    device: DeviceOption = None,
    peer_sampler: PeerSamplerOption = "independent",
    spp: Annotated[int, typer.Option(help="Samples per pixel of the equal-spp comparison.", min=1)] = 64,
    integrator: Annotated[
        list[str] | None,
        typer.Option(
            "--integrator",
            help="spectrace integrator to compare, repeatable: each gets the budget (default: the scene's).",
        ),
    ] = None,
    reference_integrator: Annotated[
        str | None, typer.Option(help="Integrator of the reference render (default: the scene's).")
    ] = None,
    mitsuba: Annotated[bool, typer.Option(help="Compare with Mitsuba 3 where installed.")] = True,
    as_json: JsonOption = False,
) -> None:
    """Error at equal wall time and at equal spp against a long reference render: spectrace (one row per
    --integrator), and Mitsuba 3 where installed. --scene veach_mis is Veach's MIS scene (bundled)."""
    _check(_one(size), max_depth, seconds)
    _check_integrators(integrator or [], "--integrator")
    _check_integrators([reference_integrator] if reference_integrator else [], "--reference-integrator")
    from spectrace.benchmarks.quality import quality_tables, run_quality_bench

    result = run_quality_bench(
        scene,
        _or(size, QUALITY_DEFAULT_SIZE),
        max_depth,
        seconds,
        QUALITY_REFERENCE_SPP,
        device,
        log=_log,
        peer_sampler=peer_sampler,
        equal_spp=spp,
        integrators=integrator,
        reference_integrator=reference_integrator,
        peer=mitsuba,
    )
    _emit("quality", result, lambda: quality_tables(result), as_json)


@bench_app.command("rays")
def rays_bench(
    triangles: TrianglesOption = 1_000_000,
    ray_count: Annotated[int, typer.Option(help="Random rays to trace.", min=1)] = 1_000_000,
    rounds: Annotated[
        int, typer.Option(help="Timed traces of each tracer, the tracers in turn within each round.", min=1)
    ] = 5,
    device: DeviceOption = None,
    all_devices: AllOption = False,
    as_json: JsonOption = False,
) -> None:
    """Closest-hit rays/s on a large mesh, against Embree on the same rays where installed."""
    from spectrace.benchmarks.peer_mitsuba import device_keys
    from spectrace.benchmarks.rays import rays_tables, run_rays_bench

    result = run_rays_bench(triangles, ray_count, device_keys(device, all_devices), log=_log, rounds=rounds)
    _emit("rays", result, lambda: rays_tables(result), as_json)


@bench_app.command("build")
def build_bench(
    triangles: TrianglesOption = 2_000_000,
    mesh: Annotated[
        list[Path] | None,
        typer.Option(help="Mesh file(s) to build over instead (a folder: its .ply files), repeatable."),
    ] = None,
    rounds: Annotated[int, typer.Option(help="Alternating rounds of each; the best counts.", min=1)] = 2,
    mitsuba_scene: Annotated[
        Path | None, typer.Option(help="Time Mitsuba loading this whole scene file (which uses the --mesh files).")
    ] = None,
    as_json: JsonOption = False,
) -> None:
    """BVH build time and memory on a large mesh, against Mitsuba 3 loading the same mesh where installed."""
    from spectrace.benchmarks.build import build_tables, run_build_bench

    for path in [*(mesh or []), *([mitsuba_scene] if mitsuba_scene else [])]:
        if not path.exists():
            raise SpectraceError("no such file or folder", where=str(path))
    if mitsuba_scene is not None and not mesh:
        raise SpectraceError(
            "needs the scene's meshes as --mesh, to build over the same triangles", where="--mitsuba-scene"
        )
    result = run_build_bench(triangles, list(mesh or []), rounds, log=_log, mitsuba_scene=mitsuba_scene)
    _emit("build", result, lambda: build_tables(result), as_json)


@bench_app.command("scaling")
def scaling_bench(
    size: SizesOption = None,
    spp: SppOption = 16,
    max_depth: MaxDepthOption = 8,
    triangles: TrianglesOption = 1_000_000,
    scene: SceneOption = None,
    device: DeviceOption = None,
    as_json: JsonOption = False,
) -> None:
    """Throughput against resolution, max_depth and triangle count."""
    _check(size, max_depth)
    from spectrace.benchmarks.scaling import run_scaling_bench, scaling_tables

    result = run_scaling_bench(scene, size, spp, max_depth, device, triangles, log=_log)
    _emit("scaling", result, lambda: scaling_tables(result), as_json)


@bench_app.command("instances")
def instances_bench(
    count: Annotated[int, typer.Option(help="Instances of the object.", min=1)] = 100,
    triangles: Annotated[int, typer.Option(help="Triangles of the instanced object.", min=2)] = 100_000,
    size: Annotated[int, typer.Option(help="Square image size in pixels.")] = 128,
    spp: SppOption = 16,
    max_depth: MaxDepthOption = 8,
    expanded: Annotated[bool, typer.Option(help="Also render the instances expanded into copies.")] = True,
    device: DeviceOption = None,
    as_json: JsonOption = False,
) -> None:
    """Instancing against expanded copies: scene device memory, set-up and samples/s."""
    _check([size], max_depth)
    from spectrace.benchmarks.instances import instances_tables, run_instances_bench

    result = run_instances_bench(count, triangles, size, spp, max_depth, device, expanded, log=_log)
    _emit("instances", result, lambda: instances_tables(result), as_json)


@bench_app.command("cold")
def cold_bench(
    size: ColdSizeOption = None,
    spp: SppOption = 16,
    max_depth: MaxDepthOption = 8,
    scene: SceneOption = None,
    device: DeviceOption = None,
    as_json: JsonOption = False,
) -> None:
    """The plain bench in a fresh process with empty kernel caches, then in another that finds them filled."""
    _check(_one(size), max_depth)
    from spectrace.benchmarks.cold_start import cold_tables, run_cold_bench

    _log("cold start (empty kernel caches), then warm start, each in a fresh process")
    cold, warm = run_cold_bench(_or(size, COLD_DEFAULT_SIZE), spp, max_depth, device, str(scene) if scene else None)
    if cold and warm:
        _log(
            f"whole processes (interpreter, imports, devices, scene, build, passes): cold "
            f"{cold[0]['process_seconds']:.2f} s, warm {warm[0]['process_seconds']:.2f} s"
        )
    _emit("cold", {"cold": cold, "warm": warm}, lambda: cold_tables(cold, warm), as_json)


@bench_app.command("samplers")
def samplers_bench(
    size: SamplersSizeOption = None,
    scene: SceneOption = None,
    device: DeviceOption = None,
    as_json: JsonOption = False,
) -> None:
    """The samplers compared: RMSE of independent and sobol at 4, 16, 64 spp against a long reference render
    (docs/sampling.md)."""
    _check(_one(size))
    from spectrace.benchmarks.samplers import sampler_bench_command

    sampler_bench_command(scene, [_or(size, SAMPLERS_DEFAULT_SIZE)], device, as_json, console.rich())


@bench_app.command("denoise")
def denoise_bench(
    size: DenoiseSizeOption = None,
    spp: Annotated[int, typer.Option(help="Samples per pixel of the denoised renders.", min=1)] = 4,
    reference_spp: Annotated[int, typer.Option(help="Samples per pixel of the reference.", min=2)] = 1024,
    seeds: Annotated[int, typer.Option(help="Renders (seeds) averaged.", min=1)] = 4,
    scene: SceneOption = None,
    device: DeviceOption = None,
    as_json: JsonOption = False,
) -> None:
    """Open Image Denoise measured: RMSE of the noisy and the denoised image at --spp against a long reference
    render (the denoise extra; docs/performance.md)."""
    _check(_one(size))
    from spectrace.benchmarks.denoise import denoise_bench_command
    from spectrace.core import limits
    from spectrace.denoising import INSTALL_HINT, denoise_available

    for option, value in (("--spp", spp), ("--reference-spp", reference_spp)):
        if problem := limits.spp_problem(value):
            raise SpectraceError(problem, where=option)
    if not denoise_available():
        raise SpectraceError(INSTALL_HINT)
    denoise_bench_command(
        scene, _or(size, DENOISE_DEFAULT_SIZE), spp, reference_spp, seeds, device, as_json, console.rich()
    )


@bench_app.command("kernel-shapes")
def kernel_shapes_bench(
    size: SizesOption = None,
    spp: SppOption = 16,
    max_depth: MaxDepthOption = 8,
    scene: SceneOption = None,
    device: DeviceOption = None,
    as_json: JsonOption = False,
) -> None:
    """The megakernel and the wavefront at work-group sizes 1-32 and the runtime's choice (medians of alternating
    repeats; one device, --device; docs/devices.md)."""
    _check(size, max_depth)
    from spectrace.benchmarks.kernel_shapes import kernel_shape_table, kernel_shape_variants, run_kernel_shape_bench

    results = run_kernel_shape_bench(
        scene, size or RENDER_DEFAULT_SIZES, spp, max_depth, device, kernel_shape_variants(), log=_log
    )
    _emit("kernel_shapes", results, lambda: [kernel_shape_table(results)], as_json, width=150)


@bench_app.command("session")
def session_bench(
    scene: Annotated[
        list[Path] | None,
        typer.Option(help="Scene file(s), repeatable (default: the living room, the Cornell box, the teapot)."),
    ] = None,
    width: Annotated[
        int | None, typer.Option(help="Film width in pixels, the aspect kept (default: the scene's).")
    ] = None,
    pass_spp: Annotated[int, typer.Option(help="Samples per pixel of each pass.", min=1)] = 1,
    repeats: Annotated[int, typer.Option(help="Edits of each kind timed (the median counts).", min=1)] = 5,
    mitsuba: Annotated[bool, typer.Option(help="Time Mitsuba 3's traverse/update on its Cornell box.")] = True,
    device: DeviceOption = None,
    as_json: JsonOption = False,
) -> None:
    """What an edit of a live session costs beyond the first pass after it, by kind of edit, against building the
    edited scene again and against Mitsuba 3's traverse/update (docs/python-api.md, "Live sessions")."""
    if width is not None:
        _check([width])
    for path in scene or []:
        if not path.is_file():
            raise SpectraceError("no such scene file", where=str(path))
    from spectrace.benchmarks.session import run_session_bench, session_tables

    result = run_session_bench(scene, width, pass_spp, repeats, device, mitsuba, log=_log)
    _emit("session", result, lambda: session_tables(result), as_json, width=200)
