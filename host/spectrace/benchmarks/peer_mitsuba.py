"""`spectrace bench --peer mitsuba`: the same scene rendered by spectrace and by Mitsuba 3, timed side by side.

Both render the scene exported by spectrace.interop.mitsuba_export (same triangles, camera, measured spectra,
resolution, spp, max_depth and Russian roulette start). Figures are wall-clock times of warm renders, film
read-back included, the best of `repeats` identical renders (default 2; the CPU may be shared): spectrace's
after its kernel build and one 1-spp warm-up pass, Mitsuba's JIT variant after one identical warm-up render
(its first render compiles kernels, or loads them from Dr.Jit's disk cache). samples/s = pixels × spp / time. The
images must agree (mean XYZ of a few regions within 4 standard errors), so that the ratio compares equal work.
On a shared machine the process CPU time of the same renders (all threads) gives a second, load-robust ratio.
"""

import tempfile
import time
from collections.abc import Callable
from pathlib import Path

from spectrace.benchmarks.image_agreement import SIGMA_LIMIT, compare_regions, regions_for
from spectrace.device import discover_devices, open_device
from spectrace.render.renderer import Renderer
from spectrace.resources import scenes_dir
from spectrace.scene import load_scene
from spectrace.scene.model import Scene


def bench_scene(scene_path: Path | None, size: int, spp: int, max_depth: int) -> Scene:
    scene = load_scene(scene_path or scenes_dir() / "cornell_box.toml")
    return scene.with_overrides(width=size, height=size, spp=spp, max_depth=max_depth)


def device_keys(device: str | None, all_devices: bool) -> list[str | None]:
    return [r.key for r in discover_devices() if r.ok] if all_devices else [device]


def render_with_spectrace(scene: Scene, device_key: str | None, repeats: int = 1) -> tuple[dict, object]:
    """The best of `repeats` warm renders (each the same image): the row of figures and the image."""
    device = open_device(device_key)
    start = time.perf_counter()
    renderer = Renderer(scene, device)
    setup_seconds = time.perf_counter() - start
    renderer.run_pass(1)  # warm-up: PoCL compiles kernels lazily at the first launch
    seconds, cpu_seconds = float("inf"), float("inf")
    for _ in range(max(1, repeats)):
        renderer.reset()
        start, cpu = time.perf_counter(), time.process_time()
        image = renderer.render(spp=scene.spp)
        if time.perf_counter() - start < seconds:
            seconds, cpu_seconds = time.perf_counter() - start, time.process_time() - cpu
    row = {
        "renderer": "spectrace", "runtime": device.report.key, "device_name": device.report.device_name,
        "width": scene.width, "height": scene.height, "spp": image.spp, "max_depth": scene.max_depth,
        "seconds": seconds, "samples_per_second": scene.width * scene.height * image.spp / seconds,
        "cpu_seconds": cpu_seconds, "samples_per_cpu_second": scene.width * scene.height * image.spp / cpu_seconds,
        "setup_seconds": setup_seconds, "kernel_build_seconds": device.last_build_seconds,
        "kernel_build_cached": device.last_build_cached,
    }
    return row, image


def run_peer_bench(scene_path: Path | None, size: int, spp: int, max_depth: int, device: str | None,
                   all_devices: bool, variants: list[str] | None = None, repeats: int = 2,
                   log: Callable[[str], None] = lambda text: None) -> dict:
    from spectrace.benchmarks.mitsuba_runtime import render_with_mitsuba, usable_variants
    from spectrace.interop.mitsuba_export import scene_to_mitsuba_dict

    scene = bench_scene(scene_path, size, spp, max_depth)
    usable = usable_variants(variants)  # before any render: it may set DRJIT_LIBLLVM_PATH
    notes = list(usable.notes)
    ours, images = [], {}
    for key in device_keys(device, all_devices):
        row, image = render_with_spectrace(scene, key, repeats)
        log(f"spectrace {row['runtime']}: {row['samples_per_second'] / 1e6:.3f} M samples/s ({row['seconds']:.2f} s)")
        ours.append(row)
        images[row["runtime"]] = image.xyz
    theirs, their_images = [], {}
    with tempfile.TemporaryDirectory(prefix="spectrace-mitsuba-") as folder:
        for variant in usable.available:
            import mitsuba as mi

            mi.set_variant(variant)
            result = render_with_mitsuba(scene_to_mitsuba_dict(scene, Path(folder), spp=spp), variant, spp,
                                         seed=scene.seed, repeats=repeats)
            row = {
                "renderer": "mitsuba", "runtime": variant, "width": scene.width, "height": scene.height, "spp": spp,
                "max_depth": scene.max_depth, "seconds": result.seconds,
                "samples_per_second": scene.width * scene.height * spp / result.seconds,
                "cpu_seconds": result.cpu_seconds,
                "samples_per_cpu_second": scene.width * scene.height * spp / result.cpu_seconds,
                "scene_load_seconds": result.load_seconds, "first_render_seconds": result.first_render_seconds,
                "threads": result.threads, "mitsuba_version": mi.__version__,
            }
            log(f"mitsuba {variant}: {row['samples_per_second'] / 1e6:.3f} M samples/s ({row['seconds']:.2f} s)")
            theirs.append(row)
            their_images[variant] = result.xyz
    if not theirs:
        notes.append("no Mitsuba variant ran: only spectrace's figures are shown")
    ratios = [{"spectrace": a["runtime"], "mitsuba": b["runtime"],
               "ratio": a["samples_per_second"] / b["samples_per_second"],
               "cpu_time_ratio": a["samples_per_cpu_second"] / b["samples_per_cpu_second"]}
              for a in ours for b in theirs]
    regions = regions_for(scene.source)
    agreement = [{"spectrace": a, "mitsuba": b, "regions": [r.as_dict() for r in compare_regions(
        images[a], their_images[b], regions)]} for a in images for b in their_images]
    for pair in agreement:
        pair["agrees"] = all(r["agrees"] for r in pair["regions"])
    return {"scene": str(scene.source), "width": size, "height": size, "spp": spp, "max_depth": max_depth,
            "rr_depth": scene.rr_depth, "repeats": repeats, "spectrace": ours, "mitsuba": theirs, "ratios": ratios,
            "agreement": agreement, "sigma_limit": SIGMA_LIMIT, "notes": notes}


def peer_tables(result: dict) -> list:
    from rich.table import Table

    timing = Table(title=f"spectrace vs Mitsuba 3: {result['width']}x{result['height']}, {result['spp']} spp, "
                         f"max_depth {result['max_depth']}, rr_depth {result['rr_depth']} (warm renders, best of "
                         f"{result['repeats']})")
    for column in ("renderer", "runtime", "M samples/s", "wall s", "CPU s", "notes"):
        timing.add_column(column, justify="left" if column in ("renderer", "runtime", "notes") else "right")
    for row in result["spectrace"]:
        build = f"build {row['kernel_build_seconds']:.2f} s" + (" (cached)" if row["kernel_build_cached"] else "")
        timing.add_row("spectrace", row["runtime"], f"{row['samples_per_second'] / 1e6:.3f}",
                       f"{row['seconds']:.2f}", f"{row['cpu_seconds']:.2f}", build)
    for row in result["mitsuba"]:
        first = row["first_render_seconds"]
        note = (f"first (JIT) render {first:.2f} s" if first is not None else "no JIT") + f", {row['threads']} threads"
        timing.add_row(f"mitsuba {row['mitsuba_version']}", row["runtime"], f"{row['samples_per_second'] / 1e6:.3f}",
                       f"{row['seconds']:.2f}", f"{row['cpu_seconds']:.2f}", note)
    tables = [timing]
    if result["ratios"]:
        ratios = Table(title="ratio = spectrace samples/s ÷ Mitsuba samples/s (and per CPU second)")
        for column in ("spectrace", "mitsuba", "ratio", "per CPU s"):
            ratios.add_column(column)
        for r in result["ratios"]:
            ratios.add_row(r["spectrace"], r["mitsuba"], f"{r['ratio']:.2f}x", f"{r['cpu_time_ratio']:.2f}x")
        tables.append(ratios)
    for pair in result["agreement"]:
        table = Table(title=f"do the images agree? {pair['spectrace']} vs {pair['mitsuba']}: mean XYZ per region, "
                            f"pass when |difference| <= {result['sigma_limit']:g} standard errors")
        for column in ("region", "spectrace X Y Z", "mitsuba X Y Z", "max |Δ|/σ", "max |Δ|/value", "agrees"):
            table.add_column(column)
        for r in pair["regions"]:
            table.add_row(r["region"], " ".join(f"{v:.4g}" for v in r["ours"]),
                          " ".join(f"{v:.4g}" for v in r["theirs"]), f"{r['sigmas']:.2f}",
                          f"{100 * r['relative_difference']:.2f} %", "pass" if r["agrees"] else "FAIL")
        tables.append(table)
    return tables
