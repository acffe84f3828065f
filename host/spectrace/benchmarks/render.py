"""`spectrace bench` (no mode): throughput of an integrator (the scene's, or --integrator) on a scene (the Cornell
box by default).

Figures are samples/s (pixel samples, each a full path: a camera path, or for the light tracer one light path per
pixel) and rays/s (closest-hit and shadow rays traced), timed
around the kernel passes only, after one warm-up pass. The program build time says whether it came from the
binary cache; "to 1st pass" is scene setup + build + the first 1-spp pass, which on PoCL includes its lazy
kernel compilation (run with empty SPECTRACE_CACHE_DIR and POCL_CACHE_DIR folders for a cold start).
"""

import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from rich.table import Table

from spectrace.device import discover_devices, open_device
from spectrace.engine.renderer import Renderer
from spectrace.resources import scenes_dir
from spectrace.scene import load_scene


def run_render_bench(
    scene_path: Path | None,
    sizes: list[int],
    spp: int,
    max_depth: int,
    device: str | None,
    all_devices: bool,
    log: Callable[[str], None] = lambda text: None,
    integrator: str | None = None,
) -> list[dict]:
    scene = load_scene(scene_path or scenes_dir() / "cornell_box.toml").with_overrides(integrator=integrator)
    keys = [r.key for r in discover_devices() if r.ok] if all_devices else [device]
    results = []
    for key in keys:
        dev = open_device(key)
        for size in sizes:
            sized = scene.with_overrides(width=size, height=size, max_depth=max_depth)
            start = time.perf_counter()
            renderer = Renderer(sized, dev)
            setup_seconds = time.perf_counter() - start
            start = time.perf_counter()
            renderer.run_pass(1)  # warm-up: the first launch pays for lazy work (PoCL compiles kernels here)
            first_pass_seconds = time.perf_counter() - start
            renderer.reset()
            image = renderer.render(spp=spp)
            samples = size * size * image.spp
            row: dict[str, Any] = {
                "device": dev.report.key,
                "device_name": dev.report.device_name,
                "width": size,
                "height": size,
                "integrator": sized.integrator,
                "spp": image.spp,
                "max_depth": max_depth,
                "seconds": image.render_seconds,
                "samples_per_second": samples / image.render_seconds,
                "rays_per_second": image.rays_traced / image.render_seconds,
                "kernel_build_seconds": dev.last_build_seconds,
                "kernel_build_cached": dev.last_build_cached,
                "setup_seconds": setup_seconds,
                "first_pass_seconds": first_pass_seconds,
                "start_to_first_pass_seconds": setup_seconds + first_pass_seconds,
            }
            log(
                f"{row['device']} {size}x{size} {sized.integrator}: {row['samples_per_second'] / 1e6:.3f} M samples/s, "
                f"{row['rays_per_second'] / 1e6:.3f} M rays/s"
            )
            results.append(row)
    return results


def render_bench_table(results: list[dict]) -> Table:
    table = Table(title="spectrace bench: throughput")
    columns = ("device", "size", "integrator", "spp", "depth", "M samples/s", "M rays/s", "time s", "build s")
    for column in (*columns, "to 1st pass s"):
        table.add_column(column, justify="right" if column != "device" else "left")
    for r in results:
        build = f"{r['kernel_build_seconds']:.2f}" + (" (cached)" if r["kernel_build_cached"] else "")
        table.add_row(
            r["device"],
            f"{r['width']}x{r['height']}",
            r["integrator"],
            str(r["spp"]),
            str(r["max_depth"]),
            f"{r['samples_per_second'] / 1e6:.3f}",
            f"{r['rays_per_second'] / 1e6:.3f}",
            f"{r['seconds']:.2f}",
            build,
            f"{r['start_to_first_pass_seconds']:.2f}",
        )
    return table
