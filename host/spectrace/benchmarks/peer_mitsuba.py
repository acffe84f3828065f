"""`spectrace bench peer`: the same scene rendered by spectrace and by Mitsuba 3, timed side by side.

Both render the scene exported by spectrace.interop.mitsuba.export (same triangles, camera, measured spectra,
resolution, spp, max_depth and Russian roulette start). Figures are wall-clock times of warm renders, film
read-back included, the best of `repeats` identical renders (default 2) in rounds that alternate spectrace and
Mitsuba, as the CPU may be shared. spectrace's renders follow its kernel build and one 1-spp warm-up pass;
Mitsuba's JIT variant follows one identical warm-up render (its first render compiles kernels, or loads them
from Dr.Jit's disk cache). samples/s = pixels × spp / time. The images must agree (mean XYZ of a few regions
within 4 standard errors), so that the ratio compares equal work. The process CPU time of the same renders (all
threads) gives a second ratio, which a shared machine's load disturbs less.
"""

from __future__ import annotations

import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from spectrace.benchmarks.image_agreement import SIGMA_LIMIT, compare_regions, regions_for
from spectrace.device import discover_devices, open_device
from spectrace.engine.renderer import Renderer
from spectrace.resources import resolve_scene_path, scenes_dir
from spectrace.scene import load_scene
from spectrace.scene.model import Scene

if TYPE_CHECKING:
    from spectrace.benchmarks.mitsuba_runtime import MitsubaContestant
    from spectrace.film.image import Image


def bench_scene(scene_path: Path | None, size: int, spp: int, max_depth: int, keep_aspect: bool = False) -> Scene:
    """The scene (a file, or a bundled scene's name such as `veach_mis`) at `size` pixels wide: square, or with its
    own aspect ratio."""
    scene = load_scene(resolve_scene_path(scene_path) if scene_path is not None else scenes_dir() / "cornell_box.toml")
    height = max(1, round(size * scene.height / scene.width)) if keep_aspect else size
    return scene.with_overrides(width=size, height=height, spp=spp, max_depth=max_depth)


def device_keys(device: str | None, all_devices: bool) -> list[str | None]:
    return [r.key for r in discover_devices() if r.ok] if all_devices else [device]


class SpectraceContestant:
    """A renderer with its kernels built and warmed up, rendering the scene on demand; keeps the fastest run."""

    def __init__(self, scene: Scene, device_key: str | None):
        self.scene = scene
        self.device = open_device(device_key)
        start = time.perf_counter()
        self.renderer = Renderer(scene, self.device)
        self.setup_seconds = time.perf_counter() - start
        self.build_seconds, self.build_cached = self.device.last_build_seconds, self.device.last_build_cached
        self.renderer.run_pass(1)  # warm-up: PoCL compiles kernels lazily at the first launch
        self.seconds, self.cpu_seconds = float("inf"), float("inf")
        self.image: Image | None = None

    def render_once(self) -> None:
        self.renderer.reset()
        start, cpu = time.perf_counter(), time.process_time()
        image = self.renderer.render(spp=self.scene.spp)
        seconds, cpu = time.perf_counter() - start, time.process_time() - cpu
        if seconds < self.seconds:
            self.seconds, self.cpu_seconds, self.image = seconds, cpu, image

    @property
    def best_image(self) -> Image:
        """The image of the fastest timed render."""
        if self.image is None:
            raise RuntimeError("no timed render yet (render_once)")
        return self.image

    def row(self) -> dict:
        scene, samples = self.scene, self.scene.width * self.scene.height * self.best_image.spp
        return {
            "renderer": "spectrace",
            "runtime": self.device.report.key,
            "device_name": self.device.report.device_name,
            "width": scene.width,
            "height": scene.height,
            "spp": self.best_image.spp,
            "max_depth": scene.max_depth,
            "seconds": self.seconds,
            "samples_per_second": samples / self.seconds,
            "cpu_seconds": self.cpu_seconds,
            "samples_per_cpu_second": samples / self.cpu_seconds,
            "setup_seconds": self.setup_seconds,
            "kernel_build_seconds": self.build_seconds,
            "kernel_build_cached": self.build_cached,
        }


def run_peer_bench(
    scene_path: Path | None,
    size: int,
    spp: int,
    max_depth: int,
    device: str | None,
    all_devices: bool,
    variants: list[str] | None = None,
    repeats: int = 2,
    log: Callable[[str], None] = lambda text: None,
    peer_sampler: str = "independent",
) -> dict:
    from spectrace.benchmarks.mitsuba_runtime import MitsubaContestant, usable_variants
    from spectrace.interop.mitsuba.export import scene_to_mitsuba_dict

    scene = bench_scene(scene_path, size, spp, max_depth)
    usable = usable_variants(variants)  # before any render: it may set DRJIT_LIBLLVM_PATH
    notes = list(usable.notes) + [f"Mitsuba's sampler: {peer_sampler}; spectrace's: {scene.sampler}"]
    ours = [SpectraceContestant(scene, key) for key in device_keys(device, all_devices)]
    with tempfile.TemporaryDirectory(prefix="spectrace-mitsuba-") as folder:
        theirs: list[MitsubaContestant] = []
        for variant in usable.available:
            import mitsuba as mi

            mi.set_variant(variant)
            scene_dict = scene_to_mitsuba_dict(scene, Path(folder), spp=spp, sampler=peer_sampler)
            theirs.append(MitsubaContestant(scene_dict, variant, spp, seed=scene.seed))
    # Interleaved rounds, spectrace then one Mitsuba variant, so a shared machine's load falls on both alike.
    # Switching Mitsuba's variant makes the next LLVM render re-trace (measured 0.3 s extra at 32x32), so each
    # variant gets its rounds in one go, after one untimed render.
    peers: list[MitsubaContestant | None] = [*theirs] or [None]
    for peer in peers:
        if peer is not None:
            peer.render_untimed()
        for round_index in range(max(1, repeats)):
            contestants: list[SpectraceContestant | MitsubaContestant] = [*ours, *([peer] if peer else [])]
            for contestant in contestants:
                contestant.render_once()
                name = contestant.variant if isinstance(contestant, MitsubaContestant) else contestant.device.report.key
                log(f"round {round_index + 1}: {name} {contestant.seconds:.2f} s (best so far)")
    images = {c.device.report.key: c.best_image.xyz for c in ours}
    our_rows = [c.row() for c in ours]
    their_images: dict[str, np.ndarray] = {}
    their_rows: list[dict[str, Any]] = []
    for contestant in theirs:
        result = contestant.result()
        import mitsuba as mi

        their_rows.append(
            {
                "renderer": "mitsuba",
                "runtime": result.variant,
                "width": scene.width,
                "height": scene.height,
                "spp": result.spp,
                "max_depth": scene.max_depth,
                "seconds": result.seconds,
                "samples_per_second": scene.width * scene.height * result.spp / result.seconds,
                "cpu_seconds": result.cpu_seconds,
                "samples_per_cpu_second": scene.width * scene.height * result.spp / result.cpu_seconds,
                "scene_load_seconds": result.load_seconds,
                "first_render_seconds": result.first_render_seconds,
                "threads": result.threads,
                "mitsuba_version": mi.__version__,
            }
        )
        their_images[result.variant] = result.xyz
    if not their_rows:
        notes.append("no Mitsuba variant ran: only spectrace's figures are shown")
    ratios = [
        {
            "spectrace": a["runtime"],
            "mitsuba": b["runtime"],
            "ratio": a["samples_per_second"] / b["samples_per_second"],
            "cpu_time_ratio": a["samples_per_cpu_second"] / b["samples_per_cpu_second"],
        }
        for a in our_rows
        for b in their_rows
    ]
    regions = regions_for(scene.source)
    agreement: list[dict[str, Any]] = [
        {
            "spectrace": a,
            "mitsuba": b,
            "regions": [r.as_dict() for r in compare_regions(images[a], their_images[b], regions)],
        }
        for a in images
        for b in their_images
    ]
    for pair in agreement:
        pair["agrees"] = all(r["agrees"] for r in pair["regions"])
    return {
        "scene": str(scene.source),
        "width": size,
        "height": size,
        "spp": spp,
        "max_depth": max_depth,
        "rr_depth": scene.rr_depth,
        "repeats": repeats,
        "spectrace": our_rows,
        "mitsuba": their_rows,
        "ratios": ratios,
        "agreement": agreement,
        "sigma_limit": SIGMA_LIMIT,
        "notes": notes,
    }


def peer_tables(result: dict) -> list:
    from rich.table import Table

    timing = Table(
        title=f"spectrace vs Mitsuba 3: {result['width']}x{result['height']}, {result['spp']} spp, "
        f"max_depth {result['max_depth']}, rr_depth {result['rr_depth']} (warm renders, best of "
        f"{result['repeats']})"
    )
    for column in ("renderer", "runtime", "M samples/s", "wall s", "CPU s", "notes"):
        timing.add_column(column, justify="left" if column in ("renderer", "runtime", "notes") else "right")
    for row in result["spectrace"]:
        build = f"build {row['kernel_build_seconds']:.2f} s" + (" (cached)" if row["kernel_build_cached"] else "")
        timing.add_row(
            "spectrace",
            row["runtime"],
            f"{row['samples_per_second'] / 1e6:.3f}",
            f"{row['seconds']:.2f}",
            f"{row['cpu_seconds']:.2f}",
            build,
        )
    for row in result["mitsuba"]:
        first = row["first_render_seconds"]
        note = (f"first (JIT) render {first:.2f} s" if first is not None else "no JIT") + f", {row['threads']} threads"
        timing.add_row(
            f"mitsuba {row['mitsuba_version']}",
            row["runtime"],
            f"{row['samples_per_second'] / 1e6:.3f}",
            f"{row['seconds']:.2f}",
            f"{row['cpu_seconds']:.2f}",
            note,
        )
    tables = [timing]
    if result["ratios"]:
        ratios = Table(title="ratio = spectrace samples/s ÷ Mitsuba samples/s (and per CPU second)")
        for column in ("spectrace", "mitsuba", "ratio", "per CPU s"):
            ratios.add_column(column)
        for r in result["ratios"]:
            ratios.add_row(r["spectrace"], r["mitsuba"], f"{r['ratio']:.2f}x", f"{r['cpu_time_ratio']:.2f}x")
        tables.append(ratios)
    for pair in result["agreement"]:
        table = Table(
            title=f"do the images agree? {pair['spectrace']} vs {pair['mitsuba']}: mean XYZ per region, "
            f"pass when |difference| <= {result['sigma_limit']:g} standard errors"
        )
        for column in ("region", "spectrace X Y Z", "mitsuba X Y Z", "max |Δ|/σ", "max |Δ|/value", "agrees"):
            table.add_column(column)
        for r in pair["regions"]:
            table.add_row(
                r["region"],
                " ".join(f"{v:.4g}" for v in r["ours"]),
                " ".join(f"{v:.4g}" for v in r["theirs"]),
                f"{r['sigmas']:.2f}",
                f"{100 * r['relative_difference']:.2f} %",
                "pass" if r["agrees"] else "FAIL",
            )
        tables.append(table)
    return tables
