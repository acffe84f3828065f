"""`spectrace bench scaling`: how path-tracing throughput changes with resolution, max_depth and triangle count.

Triangle count grows by putting an icosphere of increasing subdivision (20·4^s triangles) into the Cornell box;
with a BVH the cost of a sample should grow about with log(triangles), not in proportion to them. Each row is
one warm render (after a 1-spp warm-up pass) of `spp` samples per pixel, timed around the kernel passes, with
the process CPU time of the same render (all the runtime's threads) as a figure that a shared machine's load
disturbs less; the cost column compares CPU time per sample with the first row's.
"""

import math
import time
from collections.abc import Callable
from dataclasses import replace
from typing import Any

import numpy as np

from spectrace.device import open_device
from spectrace.engine.renderer import Renderer
from spectrace.geometry.primitives import icosphere
from spectrace.geometry.transforms import apply_transform
from spectrace.resources import scenes_dir
from spectrace.scene import load_scene
from spectrace.scene.model import Scene, Shape

RESOLUTIONS = [128, 256, 512, 1024]
DEPTHS = [1, 2, 4, 8, 16]
TABLE_SIZE = 256  # image size of the depth and triangle tables


def scene_with_sphere(scene: Scene, subdivisions: int) -> Scene:
    """The Cornell box with a white icosphere (radius 0.1 m) on the floor, left of the short block."""
    matrix = np.diag([0.1, 0.1, 0.1, 1.0])
    matrix[:3, 3] = (0.42, 0.1, 0.12)
    white = next(shape.material for shape in scene.shapes if shape.emitter is None)
    ball = Shape(mesh=apply_transform(icosphere(subdivisions), matrix), material=white, name="sphere")
    return replace(scene, shapes=[*scene.shapes, ball])


def _measure(scene: Scene, device, spp: int) -> dict:
    renderer = Renderer(scene, device)
    renderer.run_pass(1)
    renderer.reset()
    cpu = time.process_time()
    image = renderer.render(spp=spp)
    cpu = time.process_time() - cpu
    samples = scene.width * scene.height * image.spp
    return {
        "width": scene.width,
        "height": scene.height,
        "spp": image.spp,
        "max_depth": scene.max_depth,
        "triangles": int(renderer.buffers.triangle_vertices.shape[0] // 3),
        "bvh_build_seconds": renderer.buffers.bvh.build_seconds,
        "seconds": image.render_seconds,
        "samples_per_second": samples / image.render_seconds,
        "rays_per_second": image.rays_traced / image.render_seconds,
        "cpu_seconds": cpu,
        "samples_per_cpu_second": samples / cpu,
    }


def run_scaling_bench(
    scene_path,
    sizes: list[int] | None,
    spp: int,
    max_depth: int,
    device_key: str | None,
    max_triangles: int,
    log: Callable[[str], None] = lambda text: None,
) -> dict:
    device = open_device(device_key)
    base = load_scene(scene_path or scenes_dir() / "cornell_box.toml").with_overrides(max_depth=max_depth)
    sizes = sizes or RESOLUTIONS
    table_size = TABLE_SIZE if TABLE_SIZE in sizes else min(sizes)
    result: dict[str, Any] = {
        "runtime": device.report.key,
        "spp": spp,
        "max_depth": max_depth,
        "table_size": table_size,
        "resolution": [],
        "depth": [],
        "triangles": [],
    }
    for size in sizes:
        result["resolution"].append(_measure(base.with_overrides(width=size, height=size), device, spp))
        log(f"resolution {size}: {result['resolution'][-1]['samples_per_second'] / 1e6:.3f} M samples/s")
    sized = base.with_overrides(width=table_size, height=table_size)
    for depth in DEPTHS:
        result["depth"].append(_measure(sized.with_overrides(max_depth=depth), device, spp))
        log(f"max_depth {depth}: {result['depth'][-1]['samples_per_second'] / 1e6:.3f} M samples/s")
    top = max(0, math.ceil(math.log(max(max_triangles, 20) / 20.0, 4) - 1e-9))
    for subdivisions in [None, *range(min(3, top), top + 1)]:
        scene = sized if subdivisions is None else scene_with_sphere(sized, subdivisions)
        result["triangles"].append(_measure(scene, device, spp))
        log(
            f"{result['triangles'][-1]['triangles']} triangles: "
            f"{result['triangles'][-1]['samples_per_second'] / 1e6:.3f} M samples/s"
        )
    return result


def scaling_tables(result: dict) -> list:
    from rich.table import Table

    def table(title: str, key: str, rows: list[dict], extra: str | None = None) -> Table:
        t = Table(title=title)
        for column in (
            key,
            "M samples/s",
            "M rays/s",
            "M samples/CPU s",
            "cost per sample vs first (CPU)",
            *([extra] if extra else []),
        ):
            t.add_column(column, justify="right")
        first = rows[0]["samples_per_cpu_second"]
        for r in rows:
            cells = [
                str(r[key]) if key != "size" else f"{r['width']}x{r['height']}",
                f"{r['samples_per_second'] / 1e6:.3f}",
                f"{r['rays_per_second'] / 1e6:.3f}",
                f"{r['samples_per_cpu_second'] / 1e6:.3f}",
                f"{first / r['samples_per_cpu_second']:.2f}",
            ]
            if extra:
                cells.append(f"{r['bvh_build_seconds']:.2f}")
            t.add_row(*cells)
        return t

    where = f"{result['runtime']}, {result['spp']} spp"
    return [
        table(f"resolution ({where}, max_depth {result['max_depth']})", "size", result["resolution"]),
        table(f"max_depth ({where}, {result['table_size']}²)", "max_depth", result["depth"]),
        table(
            f"triangles: Cornell box + icosphere ({where}, {result['table_size']}², max_depth {result['max_depth']})",
            "triangles",
            result["triangles"],
            "BVH build s",
        ),
    ]
