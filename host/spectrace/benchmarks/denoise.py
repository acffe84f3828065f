"""`spectrace bench denoise`: how much Open Image Denoise lowers the error of a short render.

The Cornell box (or --scene) is rendered at 4 spp with the albedo and normal AOVs, denoised (spectrace.denoising),
and both images are compared with a long reference render of other seeds. RMSE is reported three ways, since one
figure hides where the error is:
- film XYZ over every pixel (linear, HDR): the visible light's pixels, whose XYZ carries the colour noise of
  sampling four wavelengths at Y ≈ 10, dominate it;
- film XYZ away from the emitters (pixels of the reference below EMITTER_Y, less a ring of RING_PIXELS around them);
- display sRGB (clipped to [0, 1] and encoded, what a viewer sees; 0..1 per channel).
Each noisy render is denoised three ways: as `spectrace render --denoise` does (its directly seen emission taken
out, the rest denoised, the directly seen emission pass of spectrace.denoising added back), with the image's own
emission exchanged for its expected value over the wavelengths (the emission AOV) instead, and whole (the image as
it is). Beside them, the noisy render given the time of render + emission pass + denoising (its spp scaled by that
time over the render's), so that the comparison is at equal cost.
The reference is rendered as two halves of different seeds, whose difference estimates its own RMSE (reported).
"""

import json
import time
from pathlib import Path

import numpy as np
from rich.console import Console
from rich.table import Table

from spectrace.device import open_device
from spectrace.engine.renderer import Renderer
from spectrace.film.colour_output import ColourSpace, xyz_to_output
from spectrace.resources import scenes_dir
from spectrace.scene import load_scene
from spectrace.spectral.colorimetry import srgb_encode

REFERENCE_SEED = 2_000_003  # the reference halves use this seed and the next; the measured renders use 0, 1, ...
EMITTER_Y = 2.0  # reference pixels brighter than this are the emitter (the Cornell box's light has Y ≈ 11)
RING_PIXELS = 2


def _display(xyz: np.ndarray) -> np.ndarray:
    return srgb_encode(np.clip(xyz_to_output(xyz, ColourSpace.SRGB), 0.0, 1.0))


def _away_from_emitters(reference: np.ndarray) -> np.ndarray:
    """Pixels neither on an emitter nor within RING_PIXELS of one (a square ring, by shifts)."""
    emitter = reference[..., 1] > EMITTER_Y
    near = emitter.copy()
    for dy in range(-RING_PIXELS, RING_PIXELS + 1):
        for dx in range(-RING_PIXELS, RING_PIXELS + 1):
            near |= np.roll(np.roll(emitter, dy, axis=0), dx, axis=1)
    return ~near


LABELS = ("noisy", "equal_time", "whole", "exchanged", "denoised")


def run_denoise_bench(
    scene_path: Path | None,
    size: int,
    spp: int,
    reference_spp: int,
    seeds: int,
    device: str | None,
    log=print,
) -> dict:
    from spectrace.denoising import RENDER_AOVS, denoise, directly_seen_emission

    dev = open_device(device)
    scene = load_scene(scene_path or scenes_dir() / "cornell_box.toml").with_overrides(width=size, height=size)
    start = time.perf_counter()
    halves = [
        Renderer(scene.with_overrides(seed=REFERENCE_SEED + i, aovs=()), dev).render(spp=max(reference_spp // 2, 1))
        for i in range(2)
    ]
    reference = 0.5 * (halves[0].xyz.astype(np.float64) + halves[1].xyz)
    reference_rmse = float(np.sqrt(np.mean((halves[0].xyz.astype(np.float64) - halves[1].xyz) ** 2) / 4.0))
    log(f"reference: {size}x{size}, {2 * max(reference_spp // 2, 1)} spp ({time.perf_counter() - start:.1f} s)")
    away = _away_from_emitters(reference)
    reference_display = _display(reference)
    errors: dict[str, list[float]] = {}
    seconds = {"render": 0.0, "emission_pass": 0.0, "denoise": 0.0}
    emission_spp = 0
    results: list[tuple[str, np.ndarray]] = []
    for seed in range(seeds):
        seeded = scene.with_overrides(seed=seed)
        noisy = Renderer(seeded.with_overrides(aovs=RENDER_AOVS), dev).render(spp=spp)
        seconds["render"] += noisy.render_seconds
        emission = directly_seen_emission(seeded, spp, dev)
        seconds["emission_pass"] += emission.render_seconds
        emission_spp = emission.spp
        started = time.perf_counter()
        denoised = denoise(noisy, emission=emission)
        seconds["denoise"] += time.perf_counter() - started
        results += [
            ("noisy", noisy.xyz),
            ("whole", denoise(noisy, exchange_emission=False).xyz),
            ("exchanged", denoise(noisy).xyz),
            ("denoised", denoised.xyz),
        ]
    # The noisy image given the time of render + emission pass + denoising: spp scaled by that time over the
    # render's (render time grows in proportion to spp at a fixed size).
    total = sum(seconds.values())
    equal_time_spp = max(spp, round(spp * total / max(seconds["render"], 1e-9)))
    for seed in range(seeds):
        longer = Renderer(scene.with_overrides(seed=seed, aovs=()), dev).render(spp=equal_time_spp)
        results.append(("equal_time", longer.xyz))
    for label, xyz in results:
        difference = xyz.astype(np.float64) - reference
        for metric, value in (
            ("xyz", np.mean(difference**2)),
            ("xyz_away", np.mean(difference[away] ** 2)),
            ("display", np.mean((_display(xyz) - reference_display) ** 2)),
        ):
            errors.setdefault(f"{label}_{metric}", []).append(float(value))
    rmse = {key: float(np.sqrt(np.mean(values))) for key, values in errors.items()}
    rows = [
        {
            "metric": metric,
            **{label: rmse[f"{label}_{metric}"] for label in LABELS},
            **{f"ratio_{label}": rmse[f"noisy_{metric}"] / rmse[f"{label}_{metric}"] for label in LABELS[1:]},
        }
        for metric in ("xyz", "xyz_away", "display")
    ]
    for row in rows:
        log(
            f"{row['metric']}: RMSE noisy {row['noisy']:.4g}; "
            + ", ".join(f"{label} {row[label]:.4g} ({row[f'ratio_{label}']:.2f}x)" for label in LABELS[1:])
        )
    return {
        "device": dev.report.key,
        "scene": str(scene.source) if scene.source else None,
        "width": size,
        "height": size,
        "spp": spp,
        "seeds": seeds,
        "reference_spp": 2 * max(reference_spp // 2, 1),
        "reference_rmse": reference_rmse,
        "pixels_away_from_emitters": int(away.sum()),
        "emission_pass_spp": emission_spp,
        "render_seconds_per_image": seconds["render"] / seeds,
        "emission_pass_seconds_per_image": seconds["emission_pass"] / seeds,
        "denoise_seconds_per_image": seconds["denoise"] / seeds,
        "equal_time_spp": equal_time_spp,
        "rows": rows,
    }


METRIC_LABELS = {
    "xyz": "film XYZ, every pixel",
    "xyz_away": f"film XYZ, away from emitters (>{RING_PIXELS} px)",
    "display": "display sRGB (clipped, encoded)",
}


def denoise_bench_table(result: dict) -> Table:
    table = Table(
        title=f"spectrace bench denoise: RMSE against a {result['reference_spp']}-spp reference "
        f"({result['width']}x{result['height']}, {result['spp']} spp, {result['seeds']} seeds, reference's own "
        f"XYZ RMSE ~{result['reference_rmse']:.2g}); per image: render {result['render_seconds_per_image']:.2f} s, "
        f"emission pass ({result['emission_pass_spp']} spp) {result['emission_pass_seconds_per_image']:.2f} s, "
        f"denoising {result['denoise_seconds_per_image']:.2f} s",
        caption="each cell: RMSE (noisy's RMSE over it). --denoise is OIDN of the image less its directly seen "
        "emission, plus the emission pass; 'AOV exchange' adds back the image's own emission's expected value "
        "instead; 'whole' denoises the image as it is",
    )
    columns = (
        "RMSE of",
        "noisy",
        f"noisy, equal time ({result['equal_time_spp']} spp)",
        "denoised whole",
        "denoised, AOV exchange",
        "--denoise (emission pass)",
    )
    for column in columns:
        table.add_column(column, justify="right")
    for r in result["rows"]:
        table.add_row(
            METRIC_LABELS[r["metric"]],
            f"{r['noisy']:.4g}",
            *(f"{r[label]:.4g} ({r[f'ratio_{label}']:.2f}x)" for label in LABELS[1:]),
        )
    return table


def denoise_bench_command(
    scene_path: Path | None,
    size: int,
    spp: int,
    reference_spp: int,
    seeds: int,
    device: str | None,
    as_json: bool,
    console,
) -> None:
    """`spectrace bench denoise`: the table on the terminal, or one JSON object on stdout."""
    result = run_denoise_bench(
        scene_path, size, spp, reference_spp, seeds, device, log=lambda text: console.print(text, highlight=False)
    )
    if as_json:
        print(json.dumps({"denoise": result}, indent=2))
    else:
        Console(width=160, markup=False).print(denoise_bench_table(result))
