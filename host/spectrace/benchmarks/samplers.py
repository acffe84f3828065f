"""`spectrace bench samplers`: the error of each sampler at equal samples per pixel.

A small Cornell box is rendered at a few sample counts with the independent and the Sobol sampler, and each image
is compared with a long reference render: RMSE over every pixel and X, Y, Z channel, averaged (as mean squared
error) over several seeds so the figure itself is steady. The reference uses the Sobol sampler with seeds none of
the measured renders use, so its error is independent of theirs; it is rendered as two halves of different seeds,
whose difference estimates the reference's own RMSE (reported: it inflates both measured errors a little).
"""

import json
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
from rich.console import Console
from rich.table import Table

from spectrace.device import open_device
from spectrace.engine.renderer import Renderer
from spectrace.resources import scenes_dir
from spectrace.scene import load_scene
from spectrace.scene.model import SAMPLER_TYPES

REFERENCE_SEED = 1_000_003  # the reference halves use this seed and the next; the measured renders use 0, 1, ...


def _render_xyz(scene, device, sampler: str, seed: int, spp: int) -> np.ndarray:
    return Renderer(scene.with_overrides(sampler=sampler, seed=seed), device).render(spp=spp).xyz.astype(np.float64)


def run_sampler_bench(
    scene_path: Path | None,
    size: int,
    spp_list: list[int],
    reference_spp: int,
    seeds: int,
    device: str | None,
    log: Callable[[str], None] = lambda text: None,
) -> dict:
    dev = open_device(device)
    scene = load_scene(scene_path or scenes_dir() / "cornell_box.toml").with_overrides(width=size, height=size)
    start = time.perf_counter()
    halves = [_render_xyz(scene, dev, "sobol", REFERENCE_SEED + i, max(reference_spp // 2, 1)) for i in range(2)]
    reference = 0.5 * (halves[0] + halves[1])
    # Var(reference) = Var(half) / 2 and Var(half_a - half_b) = 2 Var(half).
    reference_rmse = float(np.sqrt(np.mean((halves[0] - halves[1]) ** 2) / 4.0))
    log(
        f"reference: {size}x{size}, {2 * max(reference_spp // 2, 1)} spp, own RMSE ~{reference_rmse:.3g} "
        f"({time.perf_counter() - start:.1f} s)"
    )
    rows = []
    for spp in spp_list:
        row: dict[str, float] = {"spp": spp}
        for sampler in SAMPLER_TYPES:
            squared_errors = [
                np.mean((_render_xyz(scene, dev, sampler, seed, spp) - reference) ** 2) for seed in range(seeds)
            ]
            row[f"rmse_{sampler}"] = float(np.sqrt(np.mean(squared_errors)))
        row["ratio"] = row["rmse_sobol"] / row["rmse_independent"]
        log(
            f"{spp} spp: RMSE independent {row['rmse_independent']:.4g}, sobol {row['rmse_sobol']:.4g}, "
            f"ratio {row['ratio']:.3f}"
        )
        rows.append(row)
    return {
        "device": dev.report.key,
        "scene": str(scene.source) if scene.source else None,
        "width": size,
        "height": size,
        "max_depth": scene.max_depth,
        "seeds": seeds,
        "reference_spp": 2 * max(reference_spp // 2, 1),
        "reference_rmse": reference_rmse,
        "mean_y": float(reference[..., 1].mean()),
        "rows": rows,
    }


def sampler_bench_table(result: dict) -> Table:
    table = Table(
        title=f"spectrace bench samplers: RMSE of film XYZ against a {result['reference_spp']}-spp "
        f"reference ({result['width']}x{result['height']}, mean Y {result['mean_y']:.3g}, "
        f"{result['seeds']} seeds, reference's own RMSE ~{result['reference_rmse']:.2g})"
    )
    for column in ("spp", "RMSE independent", "RMSE sobol", "ratio sobol/independent"):
        table.add_column(column, justify="right")
    for r in result["rows"]:
        table.add_row(str(r["spp"]), f"{r['rmse_independent']:.4g}", f"{r['rmse_sobol']:.4g}", f"{r['ratio']:.3f}")
    return table


def sampler_bench_command(
    scene_path: Path | None, sizes: list[int] | None, device: str | None, as_json: bool, console
) -> None:
    """`spectrace bench samplers`: the table on the terminal, or one JSON object on stdout."""

    result = run_sampler_bench(
        scene_path,
        size=(sizes or [32])[0],
        spp_list=[4, 16, 64],
        reference_spp=4096,
        seeds=16,
        device=device,
        log=lambda text: console.print(text, highlight=False),
    )
    if as_json:
        print(json.dumps({"samplers": result}, indent=2))
    else:
        Console(width=150, markup=False).print(sampler_bench_table(result))
