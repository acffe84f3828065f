"""`spectrace bench kernel-shapes`: samples/s of each kernel shape and work-group size, on the same scene, and of
the default megakernel built for every scene instead of for this one (scene_features).

The variants run alternately, each repeat timing every variant once in turn, and each figure is the median over
the repeats, so a machine whose load changes during the run (other work on a shared CPU) shifts every variant
alike and the ratios stay comparable. Each variant's first pass is a warm-up and is not timed.
"""

import statistics
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from rich.table import Table

from spectrace.device import open_device
from spectrace.engine.launch import render_work_group
from spectrace.engine.wavefront import make_renderer
from spectrace.resources import scenes_dir
from spectrace.scene import load_scene

WORK_GROUPS = (None, 1, 4, 8, 16, 32)  # None: the runtime chooses


@dataclass(frozen=True)
class Variant:
    kernel: str
    work_group: int | None
    specialised: bool = True  # built for the scene's features only (spectrace.engine.scene_features)

    @property
    def label(self) -> str:
        return f"{self.kernel} wg {self.work_group or 'runtime'}" + ("" if self.specialised else " generic")


def kernel_shape_variants(
    kernels: tuple[str, ...] = ("megakernel", "wavefront"), work_groups: tuple[int | None, ...] = WORK_GROUPS
) -> list[Variant]:
    return [Variant(kernel, group) for kernel in kernels for group in work_groups]


def run_kernel_shape_bench(
    scene_path: Path | None,
    sizes: list[int],
    spp: int,
    max_depth: int,
    device: str | None,
    variants: list[Variant],
    repeats: int = 3,
    log: Callable[[str], None] = lambda text: None,
) -> list[dict]:
    scene = load_scene(scene_path or scenes_dir() / "cornell_box.toml")
    dev = open_device(device)
    default_group = render_work_group(dev)
    generic = Variant("megakernel", default_group, specialised=False)
    if any(v.kernel == "megakernel" for v in variants) and generic not in variants:
        variants = [*variants, generic]
    results = []
    for size in sizes:
        sized = scene.with_overrides(width=size, height=size, max_depth=max_depth)
        renderers = {}
        for variant in variants:
            renderer = make_renderer(sized, dev, variant.kernel, specialise=variant.specialised)
            renderer.work_group = variant.work_group
            renderer.run_pass(1)  # warm-up: PoCL compiles for the launch's group size here
            renderers[variant] = renderer
        seconds: dict[Variant, list[float]] = {variant: [] for variant in variants}
        for _ in range(repeats):
            for variant, renderer in renderers.items():
                renderer.reset()
                renderer.run_pass(spp)
                seconds[variant].append(renderer.render_seconds)
        baseline = (
            statistics.median(seconds[Variant("megakernel", default_group)])
            if Variant("megakernel", default_group) in seconds
            else None
        )
        for variant in variants:
            median = statistics.median(seconds[variant])
            row: dict[str, Any] = {
                "device": dev.report.key,
                "scene": (scene_path or Path("cornell_box.toml")).name,
                "width": size,
                "height": size,
                "max_depth": max_depth,
                "spp": spp,
                "kernel": variant.kernel,
                "work_group": variant.work_group,
                "specialised": variant.specialised,
                "is_default": variant == Variant("megakernel", default_group),
                "repeats": repeats,
                "median_seconds": median,
                "samples_per_second": size * size * spp / median,
                "relative_to_default": baseline / median if baseline else None,
            }
            log(
                f"{row['device']} {row['scene']} {size}x{size} depth {max_depth}: {variant.label}: "
                f"{row['samples_per_second'] / 1e6:.3f} M samples/s"
            )
            results.append(row)
        del renderers
    return results


def kernel_shape_table(results: list[dict]) -> Table:
    table = Table(title="spectrace bench kernel-shapes: median samples/s by kernel shape and work-group size")
    for column in ("device", "scene", "size", "depth", "kernel", "work group", "M samples/s", "vs default"):
        table.add_column(column, justify="left" if column in ("device", "scene", "kernel") else "right")
    for r in results:
        group = str(r["work_group"] or "runtime") + (" (default)" if r["is_default"] else "")
        relative = f"{r['relative_to_default']:.2f}x" if r["relative_to_default"] else ""
        kernel = r["kernel"] + ("" if r["specialised"] else " (generic)")
        table.add_row(
            r["device"],
            r["scene"],
            f"{r['width']}x{r['height']}",
            str(r["max_depth"]),
            kernel,
            group,
            f"{r['samples_per_second'] / 1e6:.3f}",
            relative,
        )
    return table
