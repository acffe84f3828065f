"""Which `spectrace bench` modes a command line asked for, running them, and their JSON and tables."""

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from spectrace.errors import SpectraceError

PEERS = ("mitsuba",)
PEER_DEFAULT_SIZE = 512
QUALITY_DEFAULT_SIZE = 128
QUALITY_REFERENCE_SPP = 1024


@dataclass
class BenchRequest:
    scene: Path | None
    sizes: list[int] | None
    spp: int
    max_depth: int
    device: str | None
    all_devices: bool
    peer: str | None = None
    quality: bool = False
    rays: bool = False
    scaling: bool = False
    cold: bool = False
    triangles: int = 1_000_000
    ray_count: int = 1_000_000
    seconds: float = 2.0
    peer_sampler: str = "independent"

    def any_mode(self) -> bool:
        return bool(self.peer or self.quality or self.rays or self.scaling or self.cold)


def _device_keys(request: BenchRequest) -> list[str | None]:
    from spectrace.benchmarks.peer_mitsuba import device_keys

    return device_keys(request.device, request.all_devices)


def run_bench_modes(request: BenchRequest, log: Callable[[str], None]) -> tuple[dict, list]:
    """({mode: result}, rich tables) for every mode asked, in a fixed order."""
    if request.peer is not None and request.peer not in PEERS:
        raise SpectraceError(f"unknown peer '{request.peer}'; peers: {', '.join(PEERS)}", where="--peer")
    output, tables = {}, []
    first_size = request.sizes[0] if request.sizes else None
    if request.cold:
        from spectrace.bench import render_bench_table
        from spectrace.benchmarks.cold_start import run_cold_bench

        log("cold start (empty kernel caches), then warm start, each in a fresh process")
        cold, warm = run_cold_bench(first_size or 256, request.spp, request.max_depth, request.device,
                                    str(request.scene) if request.scene else None)
        output["cold"] = {"cold": cold, "warm": warm}
        tables += [render_bench_table(cold), render_bench_table(warm)]
        tables[-2].title = "cold start (empty kernel caches): build s and to 1st pass s are the cold figures"
        tables[-1].title = "warm start (a fresh process, the cold run's cached binaries)"
        log(f"whole processes (interpreter, imports, devices, scene, build, passes): cold "
            f"{cold[0]['process_seconds']:.2f} s, warm {warm[0]['process_seconds']:.2f} s")
    if request.peer == "mitsuba":
        from spectrace.benchmarks.peer_mitsuba import peer_tables, run_peer_bench

        try:
            result = run_peer_bench(request.scene, first_size or PEER_DEFAULT_SIZE, request.spp, request.max_depth,
                                    request.device, request.all_devices, log=log,
                                    peer_sampler=request.peer_sampler)
        except ImportError:
            raise SpectraceError("the Mitsuba comparison needs mitsuba: pip install 'spectrace[bench]'",
                                 where="--peer") from None
        output["peer"] = result
        tables += peer_tables(result)
    if request.quality:
        from spectrace.benchmarks.quality import quality_tables, run_quality_bench

        result = run_quality_bench(request.scene, first_size or QUALITY_DEFAULT_SIZE, request.max_depth,
                                   request.seconds, QUALITY_REFERENCE_SPP, request.device, log=log,
                                   peer_sampler=request.peer_sampler)
        output["quality"] = result
        tables += quality_tables(result)
    if request.rays:
        from spectrace.benchmarks.rays import rays_tables, run_rays_bench

        result = run_rays_bench(request.triangles, request.ray_count, _device_keys(request), log=log)
        output["rays"] = result
        tables += rays_tables(result)
    if request.scaling:
        from spectrace.benchmarks.scaling import run_scaling_bench, scaling_tables

        result = run_scaling_bench(request.scene, request.sizes, request.spp, request.max_depth, request.device,
                                   request.triangles, log=log)
        output["scaling"] = result
        tables += scaling_tables(result)
    for mode, result in output.items():
        for note in result.get("notes", []) if isinstance(result, dict) else []:
            log(f"note ({mode}): {note}")
    return output, tables
