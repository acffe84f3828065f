"""`spectrace bench quality`: error at equal wall time, spectrace against Mitsuba 3.

A converged reference is a long spectrace render (its own seed, so its noise is independent of the images
judged), cross-checked region by region against a long Mitsuba render of the exported scene. Then each
renderer gets the same wall-clock budget, in the same way: a warm 4-spp probe render measures its throughput,
then it renders the spp that fit the budget (the time actually taken is reported), warm too (a JIT variant of
Mitsuba compiles anew for each sample count, once, as spectrace builds its kernels once). With the Sobol sampler
spectrace renders powers of two, as its users would: Owen-scrambled Sobol points are balanced at powers of two, and a
few samples past one can raise the error (docs/sampling.md). It renders the two that bracket the budget, the largest
that fits and the next, and "RMSE at budget" interpolates their errors (net of the reference's noise) on log error
against log spp to the spp the budget buys at the two renders' throughput: Sobol's error falls faster than 1/√spp
where the image has edges, so scaling one render's error by its time (below) would favour whichever integrator
happens to reach the higher power of two. The error is the RMSE of
film XYZ over all pixels and channels against the reference, and relative to the reference's mean Y. The
reference's own noise RMS (from its two independent halves) is reported: RMSE² includes its square. "RMSE at
budget" takes that out and scales to exactly the budget (variance ∝ 1/time), since a renderer may overrun it.
Where lights are in view, each error is also given over the pixels that see none ("off lights"): a light seen
directly puts most of the RMSE into the few pixels its edge crosses. Each renderer also renders `equal_spp` samples
per pixel, for the error at equal spp (the estimators' variance,
whatever their speed), with the reference's noise taken out the same way ("RMSE net"). The image keeps the scene's
aspect ratio, `size` pixels wide. The timed renders are not alternated (each renderer's budget is one render), so the
load around them is judged as `bench peer` judges it (bench_rounds.py: a pause before each timed render and after
the last) and printed, a busy machine named in the notes.
"""

import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from spectrace.benchmarks import bench_rounds
from spectrace.benchmarks.image_agreement import compare_regions, regions_for
from spectrace.benchmarks.peer_mitsuba import bench_scene
from spectrace.core import limits
from spectrace.device import open_device
from spectrace.engine.renderer import Renderer

REFERENCE_SEED_OFFSET = 1_000_003
PROBE_SPP = 4
EQUAL_SPP = 64


def _rmse(image: np.ndarray, reference: np.ndarray, pixels: np.ndarray | None = None) -> float:
    difference = image.astype(np.float64) - reference
    return float(np.sqrt(np.mean((difference if pixels is None else difference[pixels]) ** 2)))


def _pixels_off_lights(scene, device) -> np.ndarray | None:
    """The pixels where no camera ray meets a light (a render of emitters only, max_depth 1, is black there), or
    None when the scene has no light in view. A light seen directly puts most of a small image's RMSE into the
    few pixels it covers in part, which measures antialiasing of its edge, not the light transport around it."""
    seen = Renderer(scene.with_overrides(max_depth=1), device).render(spp=64).xyz[..., 1] > 0.0
    return ~seen if seen.any() else None


def _spp_for_budget(seconds_for_probe: float, probe_spp: int, budget_seconds: float) -> int:
    return max(1, int(round(budget_seconds * probe_spp / max(seconds_for_probe, 1e-9))))


def _time_spectrace(scene, device, seconds: float, equal_spp: int, result: dict, errors, log, pause) -> None:
    """One integrator's rows: the spp that fit the budget (from a warm probe), and equal_spp. With the Sobol sampler,
    the powers of two either side of the budget: the row is the lower one's, with the upper one's as "above".
    `pause` is called before each timed render."""
    renderer = Renderer(scene, device)
    renderer.run_pass(1)
    renderer.reset()
    probe = renderer.render(spp=PROBE_SPP)
    spp = min(_spp_for_budget(probe.render_seconds, PROBE_SPP, seconds), limits.MAX_SPP)
    counts = [spp]
    if scene.sampler == "sobol":
        spp = 1 << (spp.bit_length() - 1)
        counts = [spp] + ([2 * spp] if 2 * spp <= limits.MAX_SPP else [])
    row = {"renderer": "spectrace", "integrator": scene.integrator, "runtime": device.report.key}
    timed = []
    for count in counts:
        renderer.reset()
        pause()
        start = time.perf_counter()
        image = renderer.render(spp=count)
        elapsed = time.perf_counter() - start
        timed.append({"spp": image.spp, "seconds": elapsed, **errors(image.xyz)})
        log(f"spectrace {scene.integrator}: {image.spp} spp in {elapsed:.2f} s")
    result["renderers"].append({**row, **timed[0], **({"above": timed[1]} if len(timed) > 1 else {})})
    renderer.reset()
    pause()
    start = time.perf_counter()
    image = renderer.render(spp=equal_spp)
    elapsed = time.perf_counter() - start
    result["equal_spp"]["renderers"].append({**row, "spp": image.spp, "seconds": elapsed, **errors(image.xyz)})


def run_quality_bench(
    scene_path: Path | None,
    size: int,
    max_depth: int,
    seconds: float,
    reference_spp: int,
    device_key: str | None,
    log: Callable[[str], None] = lambda text: None,
    peer_sampler: str = "independent",
    equal_spp: int = EQUAL_SPP,
    integrators: list[str] | None = None,
    reference_integrator: str | None = None,
    peer: bool = True,
) -> dict:
    """integrators: spectrace's integrators to compare (default: the scene's own), each a row; reference_integrator:
    the one rendering the reference (default: the scene's; any unbiased one converges to the same image)."""
    watch = bench_rounds.LoadWatch()  # before the kernel builds and the reference add the bench's own threads
    scene = bench_scene(scene_path, size, 1, max_depth, keep_aspect=True)
    device = open_device(device_key)
    reference_integrator = reference_integrator or scene.integrator
    log(f"reference: spectrace {reference_integrator}, {reference_spp} spp")
    reference_renderer = Renderer(
        scene.with_overrides(
            seed=limits.offset_seed(scene.seed, REFERENCE_SEED_OFFSET), integrator=reference_integrator
        ),
        device,
    )
    half = reference_renderer.render(spp=max(1, reference_spp // 2)).xyz.astype(np.float64)
    reference = reference_renderer.render(spp=reference_spp).xyz.astype(np.float64)
    # The reference is the mean of two independent halves a and b: its own noise is RMS(a - b) / 2.
    other_half = (reference * reference_spp - half * (reference_spp // 2)) / (reference_spp - reference_spp // 2)
    off_lights = _pixels_off_lights(scene, device)

    def errors(image: np.ndarray) -> dict:
        found = {"rmse": _rmse(image, reference)}
        if off_lights is not None:
            found["rmse_off_lights"] = _rmse(image, reference, off_lights)
        return found

    result: dict[str, Any] = {
        "scene": str(scene.source),
        "width": size,
        "height": scene.height,
        "max_depth": max_depth,
        "samplers": {"spectrace": scene.sampler, "mitsuba": peer_sampler},
        "integrators": list(integrators or [scene.integrator]),
        "budget_seconds": seconds,
        "runtime": device.report.key,
        "reference": {
            "spp": reference_spp,
            "integrator": reference_integrator,
            "noise_rms": _rmse(half, other_half) / 2.0,
            "noise_rms_off_lights": None if off_lights is None else _rmse(half, other_half, off_lights) / 2.0,
            "mean_y": float(reference[..., 1].mean()),
        },
        "renderers": [],
        "equal_spp": {"spp": equal_spp, "renderers": []},
        "cross_check": None,
        "notes": [],
    }

    watch.start()
    for integrator in result["integrators"]:
        _time_spectrace(
            scene.with_overrides(integrator=integrator), device, seconds, equal_spp, result, errors, log, watch.pause
        )

    usable = None
    if not peer:
        result["notes"].append("Mitsuba left out (--no-mitsuba)")
    else:
        try:
            from spectrace.benchmarks.mitsuba_runtime import render_with_mitsuba, usable_variants
            from spectrace.interop.mitsuba.export import scene_to_mitsuba_dict

            usable = usable_variants()
        except ImportError:
            result["notes"].append("mitsuba is not installed (pip install 'spectrace[bench]'): spectrace only")
    if usable is not None:
        result["notes"] += usable.notes + [f"Mitsuba's sampler: {peer_sampler}; spectrace's: {scene.sampler}"]
        with tempfile.TemporaryDirectory(prefix="spectrace-mitsuba-") as folder:
            for index, variant in enumerate(usable.available):
                import mitsuba as mi

                mi.set_variant(variant)
                scene_dict = scene_to_mitsuba_dict(scene, Path(folder), sampler=peer_sampler)
                peer_probe = render_with_mitsuba(scene_dict, variant, spp=PROBE_SPP)
                spp = _spp_for_budget(peer_probe.seconds, PROBE_SPP, seconds)
                # Warm, as spectrace's timed renders are: a JIT variant compiles its kernels again for a new sample
                # count, which the first render at that count would otherwise pay inside the budget.
                watch.pause()
                timed = render_with_mitsuba(scene_dict, variant, spp=spp)
                result["renderers"].append(
                    {
                        "renderer": "mitsuba",
                        "runtime": variant,
                        "spp": timed.spp,
                        "seconds": timed.seconds,
                        **errors(timed.xyz),
                    }
                )
                log(f"mitsuba {variant}: {timed.spp} spp in {timed.seconds:.2f} s")
                watch.pause()
                same = render_with_mitsuba(scene_dict, variant, spp=equal_spp)
                result["equal_spp"]["renderers"].append(
                    {
                        "renderer": "mitsuba",
                        "runtime": variant,
                        "spp": same.spp,
                        "seconds": same.seconds,
                        **errors(same.xyz),
                    }
                )
                if index == 0:  # cross-check the reference against the fastest peer, at a quarter of its spp
                    check = render_with_mitsuba(
                        scene_dict, variant, spp=max(1, reference_spp // 4), seed=7, warm_up=False
                    )
                    regions = compare_regions(reference, check.xyz, regions_for(scene.source))
                    result["cross_check"] = {
                        "mitsuba": variant,
                        "spp": max(1, reference_spp // 4),
                        "agrees": all(r.agrees for r in regions),
                        "regions": [r.as_dict() for r in regions],
                    }
    watch.pause()
    load = watch.check()
    result["load"] = load.as_dict()
    if load.busy:
        result["notes"].append(bench_rounds.load_text(result["load"]))
    noise = result["reference"]["noise_rms"]
    for row in result["renderers"]:
        row["relative_rmse"] = row["rmse"] / max(result["reference"]["mean_y"], 1e-30)
        row["rmse_at_budget"] = _at_budget(row, "rmse", noise, seconds)
    for row in result["equal_spp"]["renderers"]:
        row["relative_rmse"] = row["rmse"] / max(result["reference"]["mean_y"], 1e-30)
        row["rmse_net"] = float(np.sqrt(max(row["rmse"] ** 2 - noise**2, 0.0)))
    if off_lights is not None:
        result["reference"]["pixels_off_lights"] = float(off_lights.mean())
        noise_off = result["reference"]["noise_rms_off_lights"]
        for row in result["equal_spp"]["renderers"]:
            row["rmse_off_lights_net"] = float(np.sqrt(max(row["rmse_off_lights"] ** 2 - noise_off**2, 0.0)))
        for row in result["renderers"]:
            row["rmse_off_lights_at_budget"] = _at_budget(row, "rmse_off_lights", noise_off, seconds)
    return result


def _at_budget(row: dict, key: str, noise: float, seconds: float) -> float:
    """The error row[key] would have had in exactly `seconds`, with the reference's own noise taken out (RMSE² =
    error² + reference noise², the two being independent). One render: Monte Carlo variance falls as 1/time. Two
    (the row and row["above"], Sobol's powers of two either side of the budget): interpolated between them on log
    error against log spp, at the spp the budget buys at their throughput."""
    error2 = max(row[key] ** 2 - noise**2, 1e-30)
    above = row.get("above")
    if above is None:
        return float(np.sqrt(error2 * row["seconds"] / seconds))
    above2 = max(above[key] ** 2 - noise**2, 1e-30)
    # The spp the budget buys at the throughput of both renders together (one render's time is noisier), and the
    # error there on the line through the two in log error against log spp.
    spp_at_budget = seconds * (row["spp"] + above["spp"]) / (row["seconds"] + above["seconds"])
    slope = np.log(above2 / error2) / np.log(above["spp"] / row["spp"])
    return float(np.sqrt(error2 * (spp_at_budget / row["spp"]) ** slope))


def _off_lights_note(reference: dict) -> str:
    if "pixels_off_lights" not in reference:
        return ""
    share = 100 * reference["pixels_off_lights"]
    return f", {reference['noise_rms_off_lights']:.3g} on the {share:.1f} % of pixels off lights"


def _renderer_name(row: dict) -> str:
    return f"{row['renderer']} {row['integrator']}" if "integrator" in row else row["renderer"]


def _error_table(table, renderers: list[dict], label: str, key: str, off_lights: bool):
    """`table` with a row per renderer: its error as measured, and as `key` corrects it (`label`: "at budget" for equal
    time, "net" of the reference's noise for equal spp), with the error off the lights where the scene shows them."""
    columns = ["renderer", "runtime", "spp", "time s", "RMSE (XYZ)", "RMSE / mean Y", f"RMSE {label}"]
    for column in columns + ([f"off lights, {label}"] if off_lights else []):
        table.add_column(column, justify="left" if column in ("renderer", "runtime") else "right")
    off_key = key.replace("rmse_", "rmse_off_lights_")
    for r in renderers:
        table.add_row(
            _renderer_name(r),
            r["runtime"],
            str(r["spp"]) + (f", {r['above']['spp']}" if "above" in r else ""),
            f"{r['seconds']:.2f}" + (f", {r['above']['seconds']:.2f}" if "above" in r else ""),
            f"{r['rmse']:.4g}",
            f"{100 * r['relative_rmse']:.2f} %",
            f"{r[key]:.4g}",
            *([f"{r[off_key]:.4g}"] if off_lights else []),
        )
    return table


def quality_tables(result: dict) -> list:
    from rich.table import Table

    ref = result["reference"]
    table = Table(
        title=f"equal time: {result['budget_seconds']:g} s each, {result['width']}x{result['height']}, "
        f"max_depth {result['max_depth']}; reference {ref['spp']} spp of {ref['integrator']} (its noise RMS "
        f"{ref['noise_rms']:.3g}{_off_lights_note(ref)}); samplers: spectrace {result['samplers']['spectrace']}, "
        f"Mitsuba {result['samplers']['mitsuba']}",
        caption=bench_rounds.load_text(result["load"]),
    )
    off = "pixels_off_lights" in ref
    tables = [_error_table(table, result["renderers"], "at budget", "rmse_at_budget", off)]
    same = result["equal_spp"]
    if same["renderers"]:
        equal = Table(title=f"equal spp: {same['spp']} each (Mitsuba's stratified samplers may round it up)")
        tables.append(_error_table(equal, same["renderers"], "net", "rmse_net", off))
    check = result["cross_check"]
    if check:
        cross = Table(title=f"reference cross-check against Mitsuba {check['mitsuba']} at {check['spp']} spp")
        for column in ("region", "spectrace reference Y", "mitsuba Y", "max |Δ|/σ", "agrees"):
            cross.add_column(column)
        for r in check["regions"]:
            cross.add_row(
                r["region"],
                f"{r['ours'][1]:.4g}",
                f"{r['theirs'][1]:.4g}",
                f"{r['sigmas']:.2f}",
                "pass" if r["agrees"] else "FAIL",
            )
        tables.append(cross)
    return tables
