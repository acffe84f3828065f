"""`spectrace bench --quality`: error at equal wall time, spectrace against Mitsuba 3.

A converged reference is a long spectrace render (its own seed, so its noise is independent of the images
judged), cross-checked region by region against a long Mitsuba render of the exported scene. Then each
renderer gets the same wall-clock budget: spectrace renders 1-spp passes until the budget is spent; Mitsuba,
whose render call takes a fixed spp, gets the spp its warm throughput fits into the budget. The error is the
RMSE of film XYZ over all pixels and channels against the reference, and relative to the reference's mean Y.
The reference's own noise (estimated from neighbouring pixels) is reported: RMSE² includes it.
"""

import tempfile
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

from spectrace.benchmarks.image_agreement import compare_regions, region_mean_and_error, regions_for
from spectrace.benchmarks.peer_mitsuba import bench_scene
from spectrace.device import open_device
from spectrace.render.renderer import Renderer
from spectrace.scene import limits

REFERENCE_SEED_OFFSET = 1_000_003


def _rmse(image: np.ndarray, reference: np.ndarray) -> float:
    return float(np.sqrt(np.mean((image.astype(np.float64) - reference) ** 2)))


def _noise_rms(image: np.ndarray) -> float:
    """RMS per-pixel noise of an image, from neighbour differences (see image_agreement)."""
    _, standard_error = region_mean_and_error(image)
    pixels = image.shape[0] * image.shape[1]
    return float(np.sqrt(np.mean((standard_error * np.sqrt(pixels)) ** 2)))


def run_quality_bench(scene_path: Path | None, size: int, max_depth: int, seconds: float, reference_spp: int,
                      device_key: str | None, log: Callable[[str], None] = lambda text: None) -> dict:
    scene = bench_scene(scene_path, size, 1, max_depth)
    device = open_device(device_key)
    log(f"reference: spectrace, {reference_spp} spp")
    reference_renderer = Renderer(scene.with_overrides(seed=scene.seed + REFERENCE_SEED_OFFSET), device)
    reference = reference_renderer.render(spp=reference_spp).xyz.astype(np.float64)
    result = {"scene": str(scene.source), "width": size, "height": size, "max_depth": max_depth,
              "budget_seconds": seconds, "runtime": device.report.key,
              "reference": {"spp": reference_spp, "noise_rms": _noise_rms(reference),
                            "mean_y": float(reference[..., 1].mean())},
              "renderers": [], "cross_check": None, "notes": []}

    renderer = Renderer(scene, device)
    renderer.run_pass(1)
    renderer.reset()
    start = time.perf_counter()
    image = renderer.render(spp=limits.MAX_SPP, pass_spp=1, should_stop=lambda: time.perf_counter() - start >= seconds)
    elapsed = time.perf_counter() - start
    result["renderers"].append({"renderer": "spectrace", "runtime": device.report.key, "spp": image.spp,
                                "seconds": elapsed, "rmse": _rmse(image.xyz, reference)})
    log(f"spectrace: {image.spp} spp in {elapsed:.2f} s")

    try:
        from spectrace.benchmarks.mitsuba_runtime import render_with_mitsuba, usable_variants
        from spectrace.interop.mitsuba_export import scene_to_mitsuba_dict

        usable = usable_variants()
    except ImportError:
        result["notes"].append("mitsuba is not installed (pip install 'spectrace[bench]'): spectrace only")
        usable = None
    if usable is not None:
        result["notes"] += usable.notes
        pixels = size * size
        with tempfile.TemporaryDirectory(prefix="spectrace-mitsuba-") as folder:
            for index, variant in enumerate(usable.available):
                import mitsuba as mi

                mi.set_variant(variant)
                scene_dict = scene_to_mitsuba_dict(scene, Path(folder))
                probe = render_with_mitsuba(scene_dict, variant, spp=4)
                rate = pixels * 4 / probe.seconds
                spp = max(1, int(round(seconds * rate / pixels)))
                timed = render_with_mitsuba(scene_dict, variant, spp=spp, warm_up=False)
                result["renderers"].append({"renderer": "mitsuba", "runtime": variant, "spp": spp,
                                            "seconds": timed.seconds, "rmse": _rmse(timed.xyz, reference)})
                log(f"mitsuba {variant}: {spp} spp in {timed.seconds:.2f} s")
                if index == 0:  # cross-check the reference against the fastest peer, at a quarter of its spp
                    check = render_with_mitsuba(scene_dict, variant, spp=max(1, reference_spp // 4), seed=7,
                                                warm_up=False)
                    regions = compare_regions(reference, check.xyz, regions_for(scene.source))
                    result["cross_check"] = {"mitsuba": variant, "spp": max(1, reference_spp // 4),
                                             "agrees": all(r.agrees for r in regions),
                                             "regions": [r.as_dict() for r in regions]}
    for row in result["renderers"]:
        row["relative_rmse"] = row["rmse"] / max(result["reference"]["mean_y"], 1e-30)
    return result


def quality_tables(result: dict) -> list:
    from rich.table import Table

    ref = result["reference"]
    table = Table(title=f"equal time: {result['budget_seconds']:g} s each, {result['width']}x{result['height']}, "
                        f"max_depth {result['max_depth']}; reference {ref['spp']} spp (its noise RMS "
                        f"{ref['noise_rms']:.3g})")
    for column in ("renderer", "runtime", "spp", "time s", "RMSE (XYZ)", "RMSE / mean Y"):
        table.add_column(column, justify="left" if column in ("renderer", "runtime") else "right")
    for r in result["renderers"]:
        table.add_row(r["renderer"], r["runtime"], str(r["spp"]), f"{r['seconds']:.2f}", f"{r['rmse']:.4g}",
                      f"{100 * r['relative_rmse']:.2f} %")
    tables = [table]
    check = result["cross_check"]
    if check:
        cross = Table(title=f"reference cross-check against Mitsuba {check['mitsuba']} at {check['spp']} spp")
        for column in ("region", "spectrace reference Y", "mitsuba Y", "max |Δ|/σ", "agrees"):
            cross.add_column(column)
        for r in check["regions"]:
            cross.add_row(r["region"], f"{r['ours'][1]:.4g}", f"{r['theirs'][1]:.4g}", f"{r['sigmas']:.2f}",
                          "pass" if r["agrees"] else "FAIL")
        tables.append(cross)
    return tables
