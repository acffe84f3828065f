"""`spectrace bench`: throughput measurements and comparisons with peers (docs/performance.md)."""

import json
from pathlib import Path
from typing import Annotated, Optional

import typer
from rich.console import Console

from spectrace.cli.common import DeviceOption, console
from spectrace.errors import SpectraceError


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
    from spectrace.cli import checks as cli_checks
    from spectrace.scene import limits

    cli_checks.check_max_depth(max_depth)
    cli_checks.check_finite(seconds, "--seconds")
    for size in sizes or []:
        if problem := limits.film_size_problem(size, size):
            raise SpectraceError(problem, where="--size")
