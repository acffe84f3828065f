"""`spectrace bench peer`: the same scene rendered by spectrace and by Mitsuba 3, timed side by side.

Both render the scene exported by spectrace.interop.mitsuba.export (same triangles, camera, measured spectra,
resolution, spp, max_depth and Russian roulette start). Figures are times of warm renders, film read-back
included, in `rounds` rounds (default 5) that alternate spectrace and Mitsuba (bench_rounds.py): the median and
spread of each, and ratios taken round by round, with the load around them and a warning when other processes
kept the machine busy. spectrace's renders follow its kernel build and one 1-spp warm-up pass; Mitsuba's JIT variant
follows one identical warm-up render (its first render compiles kernels, or loads them from Dr.Jit's disk cache).
samples/s = pixels × spp / time. The images must agree (mean XYZ of a few regions within 4 standard errors), so
that the ratio compares equal work. The process CPU time of the same renders (all threads) gives a second ratio,
which a shared machine's load disturbs less. With Intel's runtime the thread that waits for a pass is busy for the
whole pass: it runs work-groups beside the runtime's own worker threads, its CPU time is the render's.
`per_core` runs each renderer on one core (single_core.py): every thread of the process pinned to one core, one
compute unit of each OpenCL runtime against Dr.Jit with one thread.
"""

from __future__ import annotations

import contextlib
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any, cast

import numpy as np

from spectrace.benchmarks import bench_rounds
from spectrace.benchmarks.bench_rounds import DEFAULT_ROUNDS, alternate_rounds, paired_ratios, timing_summary
from spectrace.benchmarks.image_agreement import SIGMA_LIMIT, compare_regions, regions_for
from spectrace.device import discover_devices, open_device
from spectrace.engine.renderer import Renderer
from spectrace.resources import resolve_scene_path, scenes_dir
from spectrace.scene import load_scene
from spectrace.scene.model import Scene

if TYPE_CHECKING:
    from spectrace.benchmarks.mitsuba_runtime import MitsubaContestant
    from spectrace.device.program_cache import Device
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
    """A renderer with its kernels built and warmed up, rendering the scene on demand."""

    renderer = "spectrace"

    def __init__(self, scene: Scene, device_key: str | None, device: Device | None = None, how: str = ""):
        self.scene = scene
        self.device = device if device is not None else open_device(device_key)
        self.name = self.device.report.key
        self.how = how  # how the device was restricted (per-core runs), else ""
        start = time.perf_counter()
        self.engine = Renderer(scene, self.device)
        self.setup_seconds = time.perf_counter() - start
        self.build_seconds, self.build_cached = self.device.last_build_seconds, self.device.last_build_cached
        self.engine.run_pass(1)  # warm-up: PoCL compiles kernels lazily at the first launch
        self.image: Image | None = None

    def render_timed(self) -> tuple[float, float]:
        """One render: (wall seconds, process CPU seconds). Every render of the same seed is the same image; the
        first is kept."""
        self.engine.reset()
        start, cpu = time.perf_counter(), time.process_time()
        image = self.engine.render(spp=self.scene.spp)
        seconds, cpu = time.perf_counter() - start, time.process_time() - cpu
        if self.image is None:
            self.image = image
        return seconds, cpu

    @property
    def first_image(self) -> Image:
        if self.image is None:
            raise RuntimeError("no timed render yet (render_timed)")
        return self.image

    @property
    def samples(self) -> int:
        return self.scene.width * self.scene.height * self.first_image.spp

    def row(self, timings: list) -> dict:
        scene = self.scene
        return {
            "renderer": "spectrace",
            "runtime": self.name,
            "device_name": self.device.report.device_name,
            "compute_units": self.device.report.compute_units,
            "restricted": self.how,
            "width": scene.width,
            "height": scene.height,
            "spp": self.first_image.spp,
            "max_depth": scene.max_depth,
            **timing_summary(timings, self.name, self.samples),
            "setup_seconds": self.setup_seconds,
            "kernel_build_seconds": self.build_seconds,
            "kernel_build_cached": self.build_cached,
        }


def _our_contestants(scene: Scene, keys: list[str | None], per_core: bool) -> list[SpectraceContestant]:
    if not per_core:
        return [SpectraceContestant(scene, key) for key in keys]
    from spectrace.benchmarks.single_core import open_one_compute_unit

    return [SpectraceContestant(scene, key, *open_one_compute_unit(key)) for key in keys]


def run_peer_bench(
    scene_path: Path | None,
    size: int,
    spp: int,
    max_depth: int,
    device: str | None,
    all_devices: bool,
    variants: list[str] | None = None,
    rounds: int = DEFAULT_ROUNDS,
    log: Callable[[str], None] = lambda text: None,
    peer_sampler: str = "independent",
    per_core: bool = False,
) -> dict:
    from spectrace.benchmarks.mitsuba_runtime import MitsubaContestant, usable_variants
    from spectrace.benchmarks.single_core import drjit_threads, one_core
    from spectrace.interop.mitsuba.export import scene_to_mitsuba_dict

    watch = bench_rounds.LoadWatch()  # before the builds and JIT warm-ups add the bench's own threads
    with one_core() if per_core else contextlib.nullcontext() as core:
        scene = bench_scene(scene_path, size, spp, max_depth)
        usable = usable_variants(variants)  # before any render: it may set DRJIT_LIBLLVM_PATH
        notes = list(usable.notes) + [f"Mitsuba's sampler: {peer_sampler}; spectrace's: {scene.sampler}"]
        ours = _our_contestants(scene, device_keys(device, all_devices), per_core)
        with drjit_threads(1 if per_core else None):
            with tempfile.TemporaryDirectory(prefix="spectrace-mitsuba-") as folder:
                theirs: list[MitsubaContestant] = []
                for variant in usable.available:
                    import mitsuba as mi

                    mi.set_variant(variant)
                    scene_dict = scene_to_mitsuba_dict(scene, Path(folder), spp=spp, sampler=peer_sampler)
                    theirs.append(MitsubaContestant(scene_dict, variant, spp, seed=scene.seed))
            # Switching Mitsuba's variant makes the next LLVM render re-trace (measured 0.3 s extra at 32x32), so
            # each variant gets its rounds in one block, after one untimed render.
            watch.start()
            warm_up = lambda peer: cast("MitsubaContestant", peer).render_untimed()  # noqa: E731
            timings = alternate_rounds(ours, theirs, max(1, rounds), log, before_block=warm_up, pause=watch.pause)
            load = watch.check()
            their_results = [contestant.result() for contestant in theirs]
    if load.busy:
        notes.append(bench_rounds.load_text(load.as_dict()))
    images = {c.name: c.first_image.xyz for c in ours}
    our_rows = [c.row(timings) for c in ours]
    their_images: dict[str, np.ndarray] = {}
    their_rows: list[dict[str, Any]] = []
    for result in their_results:
        import mitsuba as mi

        samples = scene.width * scene.height * result.spp
        their_rows.append(
            {
                "renderer": "mitsuba",
                "runtime": result.variant,
                "width": scene.width,
                "height": scene.height,
                "spp": result.spp,
                "max_depth": scene.max_depth,
                **timing_summary(timings, result.variant, samples),
                "scene_load_seconds": result.load_seconds,
                "first_render_seconds": result.first_render_seconds,
                "threads": result.threads,
                "mitsuba_version": mi.__version__,
            }
        )
        their_images[result.variant] = result.xyz
    if not their_rows:
        notes.append("no Mitsuba variant ran: only spectrace's figures are shown")
    samples_of = {c.name: c.samples for c in ours} | {
        r.variant: scene.width * scene.height * r.spp for r in their_results
    }
    ratios = [paired_ratios(timings, a, samples_of[a], b, samples_of[b]) for a in images for b in their_images]
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
        "width": scene.width,
        "height": scene.height,
        "spp": spp,
        "max_depth": max_depth,
        "rr_depth": scene.rr_depth,
        "rounds": max(1, rounds),
        "per_core": per_core,
        "core": core,
        "load": load.as_dict(),
        "order": [f"{t.renderer} {t.name}" for t in timings],
        "spectrace": our_rows,
        "mitsuba": their_rows,
        "ratios": ratios,
        "agreement": agreement,
        "sigma_limit": SIGMA_LIMIT,
        "notes": notes,
    }


def _median_and_spread(figure: dict) -> str:
    return f"{figure['median']:.3g} ({figure['min']:.3g}-{figure['max']:.3g})"


def peer_tables(result: dict) -> list:
    from rich.table import Table

    from spectrace.benchmarks.bench_rounds import load_text

    per_core = result.get("per_core", False)
    pinned = f"every thread on core {result['core']}, " if result.get("core") is not None else ""
    mode = f"one core each: {pinned}sub-device of 1 compute unit vs Dr.Jit 1 thread, " if per_core else ""
    timing = Table(
        title=f"spectrace vs Mitsuba 3: {result['width']}x{result['height']}, {result['spp']} spp, "
        f"max_depth {result['max_depth']}, rr_depth {result['rr_depth']} ({mode}warm renders, {result['rounds']} "
        f"alternated rounds: median (min-max))",
        caption=load_text(result["load"]),
    )
    for column in ("renderer", "runtime", "M samples/s", "wall s", "CPU s", "cores used", "notes"):
        timing.add_column(column, justify="left" if column in ("renderer", "runtime", "notes") else "right")
    for row in result["spectrace"]:
        build = f"build {row['kernel_build_seconds']:.2f} s" + (" (cached)" if row["kernel_build_cached"] else "")
        note = f"{row['restricted']}; {build}" if row.get("restricted") else build
        timing.add_row(
            "spectrace",
            row["runtime"],
            f"{row['samples_per_second'] / 1e6:.3f}",
            _median_and_spread(row["seconds"]),
            _median_and_spread(row["cpu_seconds"]),
            f"{row['cores_used']:.2f}",
            note,
        )
    for row in result["mitsuba"]:
        first = row["first_render_seconds"]
        note = (f"first (JIT) render {first:.2f} s" if first is not None else "no JIT") + f", {row['threads']} threads"
        timing.add_row(
            f"mitsuba {row['mitsuba_version']}",
            row["runtime"],
            f"{row['samples_per_second'] / 1e6:.3f}",
            _median_and_spread(row["seconds"]),
            _median_and_spread(row["cpu_seconds"]),
            f"{row['cores_used']:.2f}",
            note,
        )
    tables: list = [timing]
    if result["ratios"]:
        ratios = Table(
            title="ratio = spectrace samples/s ÷ Mitsuba samples/s, round by round: median (min-max)"
            + (", one core each" if per_core else ""),
            caption=load_text(result["load"]),
        )
        for column in ("spectrace", "mitsuba", "wall clock", "per CPU second"):
            ratios.add_column(column)
        for r in result["ratios"]:
            ratios.add_row(
                r["spectrace"],
                r["mitsuba"],
                _median_and_spread(r["ratio"]) + "x",
                _median_and_spread(r["cpu_time_ratio"]) + "x",
            )
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
