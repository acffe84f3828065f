"""`spectrace bench rays`: closest-hit rays/s on a large mesh, against Embree on the same rays.

The mesh is a noise-displaced icosphere (20·4^s triangles; s = 8 gives 1.3 M), the rays start on a sphere of
radius 3 around it and aim at uniform points inside the unit ball (fixed seed), so nearly all hit and they
cross the mesh from every direction. spectrace traces them with its BVH kernel (the same traversal and
watertight triangle test the path tracer uses, kernels/bvh.cl, through the closest-hit harness kernel);
Embree 4 (the `embreex` package) traces the same float32 rays as the practical limit of CPU ray tracing.
Cores used are measured as process CPU time ÷ wall time during each timed trace, so per-core figures divide
by what each one actually used. Each tracer traces the rays once per round, the tracers in turn within a round, and
the per-core ratio to Embree is taken round by round (median, smallest, largest), so a load that comes and goes falls
on both alike; the load around the rounds is judged as `bench peer` judges it (bench_rounds.py), and a busy machine
is named in the notes and under the table. The BVH build is timed (wall and CPU time), and built once more under
tracemalloc (which numpy reports its arrays to) for its peak memory, with the process's peak resident size; the SAH
cost is spectrace.geometry.bvh's.
"""

import math
import resource
import time
import tracemalloc
from collections.abc import Callable
from typing import Any, TypeVar

import numpy as np
import pyopencl as cl

from spectrace.benchmarks import bench_rounds
from spectrace.device import open_device
from spectrace.device.host_memory import read_only_buffer
from spectrace.engine.launch import launch_shape, render_work_group
from spectrace.geometry.bvh import build_bvh
from spectrace.geometry.bvh4 import (
    BVH8Q_NODE_DTYPE,
    LEAF_BLOCK,
    LEAF_SIZE,
    QUANTISED_NODES,
    TRAVERSAL_WIDTH,
    collapse,
    device_nodes,
    traversal_defines,
)
from spectrace.geometry.mesh import TriangleMesh
from spectrace.geometry.primitives import MAX_SPHERE_SUBDIVISIONS, icosphere
from spectrace.geometry.triangle_blocks import BLOCK_VECTORS
from spectrace.plugins import generated_sources

DISTANCE_CHECK_RAYS = 20000


def subdivisions_for(triangles: int) -> int:
    """Smallest icosphere subdivision level with at least `triangles` triangles (20·4^s)."""
    level = max(0, math.ceil(math.log(max(triangles, 20) / 20.0, 4) - 1e-9))
    return min(level, MAX_SPHERE_SUBDIVISIONS)


def displaced_sphere(subdivisions: int, seed: int = 1) -> TriangleMesh:
    """An icosphere with radial bumps (a sum of random plane waves, ±10 %), so the BVH sees an uneven surface."""
    mesh = icosphere(subdivisions)
    rng = np.random.default_rng(seed)
    directions = rng.normal(size=(6, 3))
    frequencies = rng.uniform(3.0, 12.0, 6)
    phases = rng.uniform(0.0, 2.0 * np.pi, 6)
    waves = np.sin(mesh.vertices @ directions.T * frequencies + phases).sum(axis=1)
    radius = 1.0 + 0.1 * waves / 6.0
    return TriangleMesh(vertices=mesh.vertices * radius[:, None], faces=mesh.faces)


def random_rays(count: int, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """float32 origins on the radius-3 sphere and unit directions toward uniform points in the unit ball."""
    rng = np.random.default_rng(seed)
    starts = rng.normal(size=(count, 3))
    starts *= 3.0 / np.linalg.norm(starts, axis=1, keepdims=True)
    targets = rng.normal(size=(count, 3))
    targets *= (rng.random(count) ** (1.0 / 3.0) / np.linalg.norm(targets, axis=1))[:, None]
    directions = targets - starts
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    return starts.astype(np.float32), directions.astype(np.float32)


T = TypeVar("T")


def _timed(work: Callable[[], T]) -> tuple[T, float, float]:
    """(result, wall seconds, cores used = CPU seconds / wall seconds)."""
    cpu, wall = time.process_time(), time.perf_counter()
    result = work()
    wall = time.perf_counter() - wall
    return result, wall, (time.process_time() - cpu) / wall if wall > 0 else 0.0


def _float4(a: np.ndarray) -> np.ndarray:
    out = np.zeros((len(a), 4), np.float32)
    out[:, :3] = a
    return out


def build_with_memory(mesh: TriangleMesh):
    """(BVH, CPU seconds of an untraced build, peak traced bytes of a second, traced build)."""
    v0, v1, v2 = mesh.triangles()
    cpu = time.process_time()
    bvh = build_bvh(v0, v1, v2, max_leaf_size=LEAF_SIZE, leaf_block=LEAF_BLOCK)
    cpu = time.process_time() - cpu
    tracemalloc.start()
    try:
        build_bvh(v0, v1, v2, max_leaf_size=LEAF_SIZE, leaf_block=LEAF_BLOCK)
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    return bvh, cpu, peak


def _leaf_order_vertices(mesh: TriangleMesh, bvh) -> np.ndarray:
    """(3·M, 4) float32 vertices in BVH leaf order, as the kernels read them."""
    ordered = mesh.vertices[mesh.faces[bvh.prim_order]].astype(np.float32)  # (M, 3, 3)
    vertices = np.zeros((len(ordered), 3, 4), np.float32)
    vertices[..., :3] = ordered
    return vertices.reshape(-1, 4)


def traversal_tree_stats(bvh, node_buffer: np.ndarray) -> dict:
    """The tree the kernel traverses: the wide collapse (TRAVERSAL_WIDTH) and its leaf blocks, and the node buffer's
    size."""
    nodes, depth = collapse(bvh, TRAVERSAL_WIDTH)
    quantised = TRAVERSAL_WIDTH == 8 and QUANTISED_NODES
    node_bytes = len(nodes) * (BVH8Q_NODE_DTYPE.itemsize if quantised else nodes.dtype.itemsize)
    blocks = (node_buffer.nbytes - node_bytes) // (4 * BLOCK_VECTORS * TRAVERSAL_WIDTH)
    return {
        "width": TRAVERSAL_WIDTH,
        "nodes_wide": int(len(nodes)),
        "depth_wide": int(depth),
        "leaf_blocks": int(blocks),
        "node_buffer_bytes": int(node_buffer.nbytes),
    }


def trace_with_spectrace(
    device_key: str | None, bvh, vertices: np.ndarray, node_buffer: np.ndarray, origins, directions
) -> dict:
    """vertices, node_buffer: the kernel's triangle and node buffers (_leaf_order_vertices, device_nodes)."""
    device = open_device(device_key)
    program = device.build_program(
        "testing/closest_hit.cl", defines=traversal_defines() or None, generated=generated_sources()
    )
    kernel = cl.Kernel(program, "closest_hit")
    ctx, queue = device.context, device.queue
    ro = cl.mem_flags.READ_ONLY | cl.mem_flags.COPY_HOST_PTR
    count = len(origins)
    buffers = [
        read_only_buffer(ctx, node_buffer),  # as a render's scene buffers: in huge pages on a CPU
        read_only_buffer(ctx, vertices),
        cl.Buffer(ctx, ro, hostbuf=_float4(origins)),
        cl.Buffer(ctx, ro, hostbuf=_float4(directions)),
    ]
    t_out = cl.Buffer(ctx, cl.mem_flags.WRITE_ONLY, 4 * count)
    hit_out = cl.Buffer(ctx, cl.mem_flags.WRITE_ONLY, 4 * count)
    global_size, local_size = launch_shape(count, render_work_group(device))

    def launch():
        # Arguments set at each launch: the closure holds the buffers for as long as it may launch.
        kernel.set_args(*buffers, t_out, hit_out, np.int32(count))
        cl.enqueue_nd_range_kernel(queue, kernel, global_size, local_size)
        queue.finish()

    launch()  # warm-up: lazy compilation on PoCL, page faults on the buffers; every launch gives these answers
    t = np.empty(count, np.float32)
    hit = np.empty(count, np.int32)
    cl.enqueue_copy(queue, t, t_out)
    cl.enqueue_copy(queue, hit, hit_out)
    queue.finish()
    triangle = np.where(hit >= 0, bvh.prim_order[np.maximum(hit, 0)], -1)
    return {
        "runtime": device.report.key,
        "kernel_build_cached": device.last_build_cached,
        "t": np.where(hit >= 0, t, np.inf),
        "triangle": triangle,
        "trace": launch,
    }


def trace_with_embree(mesh: TriangleMesh, origins, directions) -> dict:
    from embreex import rtcore_scene
    from embreex.mesh_construction import TriangleMesh as EmbreeMesh

    def build():
        scene = rtcore_scene.EmbreeScene()
        EmbreeMesh(scene, mesh.vertices.astype(np.float32), mesh.faces.astype(np.int32))
        scene.run(origins[:1], directions[:1])  # Embree commits (builds) the scene at the first query
        return scene

    scene, build_seconds, _ = _timed(build)

    def trace():
        return scene.run(origins, directions, output=1)

    result = trace()  # warm-up; every run gives these answers
    hit = result["primID"].astype(np.int64)
    hit = np.where(result["geomID"] >= 0, hit, -1)  # a miss has geomID -1 (RTC_INVALID_GEOMETRY_ID)
    t = np.where(hit >= 0, result["tfar"], np.inf)
    return {"runtime": "embree (embreex)", "build_seconds": build_seconds, "t": t, "triangle": hit, "trace": trace}


def time_in_rounds(tracers: list[dict], ray_count: int, rounds: int, pause: Callable[[], None] = lambda: None) -> None:
    """Times each tracer's `trace` `rounds` times, the tracers in turn within each round (as `bench peer` alternates
    its renderers), so a load that comes and goes falls on all alike; sets each one's median seconds, cores used
    (process CPU time ÷ wall time) and rays/s, overall and per core, and its per-round rays/s per core. `pause` is
    called before each trace and after the last (bench_rounds.LoadWatch samples the load there)."""
    for tracer in tracers:
        tracer["round_rays_per_second_per_core"] = []
        tracer["round_seconds"], tracer["round_cores"] = [], []
    for _ in range(rounds):
        for tracer in tracers:
            pause()
            _, seconds, cores = _timed(tracer["trace"])
            tracer["round_seconds"].append(seconds)
            tracer["round_cores"].append(cores)
            tracer["round_rays_per_second_per_core"].append(ray_count / seconds / max(cores, 1e-9))
    pause()
    for tracer in tracers:
        tracer["seconds"] = float(np.median(tracer["round_seconds"]))
        tracer["cores_used"] = float(np.median(tracer["round_cores"]))
        tracer["rays_per_second"] = ray_count / tracer["seconds"]
        tracer["rays_per_second_per_core"] = float(np.median(tracer["round_rays_per_second_per_core"]))


def distance_agreement(ours: dict, theirs: dict, count: int) -> dict:
    """Hit/miss and distances on the first `count` rays: rays that graze an edge may differ, nothing else."""
    a_t, b_t = ours["t"][:count], theirs["t"][:count]
    both = np.isfinite(a_t) & np.isfinite(b_t)
    relative = np.abs(a_t[both] - b_t[both]) / np.maximum(b_t[both], 1e-6)
    return {
        "rays": int(count),
        "same_hit_or_miss": float(np.mean(np.isfinite(a_t) == np.isfinite(b_t))),
        "same_triangle": float(np.mean(ours["triangle"][:count] == theirs["triangle"][:count])),
        "median_relative_distance_difference": float(np.median(relative)) if both.any() else 0.0,
        "within_1e-4": float(np.mean(relative <= 1e-4)) if both.any() else 1.0,
    }


def run_rays_bench(
    triangles: int,
    ray_count: int,
    device_keys: list[str | None],
    with_embree: bool = True,
    log: Callable[[str], None] = lambda text: None,
    rounds: int = 5,
) -> dict:
    watch = bench_rounds.LoadWatch()  # before the build and the kernel builds add the bench's own threads
    subdivisions = subdivisions_for(triangles)
    mesh = displaced_sphere(subdivisions)
    log(f"mesh: displaced icosphere, {len(mesh.faces)} triangles; building the BVH")
    bvh, build_cpu_seconds, peak_bytes = build_with_memory(mesh)
    origins, directions = random_rays(ray_count)
    result: dict[str, Any] = {
        "triangles": int(len(mesh.faces)),
        "rays": int(ray_count),
        "bvh": {
            "build_seconds": bvh.build_seconds,
            "build_cpu_seconds": build_cpu_seconds,
            "peak_traced_bytes": int(peak_bytes),
            "peak_resident_bytes": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024,
            "nodes": int(len(bvh.nodes)),
            "depth": int(bvh.depth),
            "sah_cost": bvh.sah_cost,
        },
        "spectrace": [],
        "embree": None,
        "agreement": [],
        "notes": [],
    }
    # After the build's peak resident size was read: the kernel's buffers, made once for every runtime.
    vertices = _leaf_order_vertices(mesh, bvh)
    node_buffer = device_nodes(bvh, vertices)
    result["bvh"].update(traversal_tree_stats(bvh, node_buffer))
    log(f"BVH: {bvh.build_seconds:.2f} s ({build_cpu_seconds:.2f} s CPU), peak {peak_bytes / 2**20:.0f} MiB traced")
    traced = [trace_with_spectrace(key, bvh, vertices, node_buffer, origins, directions) for key in device_keys]
    embree = None
    if with_embree:
        try:
            embree = trace_with_embree(mesh, origins, directions)
        except ImportError:
            result["notes"].append("embreex is not installed (pip install 'spectrace[bench]'): no Embree figures")
    result["rounds"] = rounds
    watch.start()
    time_in_rounds(traced + ([embree] if embree else []), ray_count, rounds, pause=watch.pause)
    load = watch.check()
    result["load"] = load.as_dict()
    if load.busy:
        result["notes"].append(bench_rounds.load_text(result["load"]))
    for row in traced:
        log(f"spectrace {row['runtime']}: {row['rays_per_second'] / 1e6:.2f} M rays/s")
    unreported = ("t", "triangle", "trace")  # the answers and the timed call: not part of the result
    if embree:
        log(f"embree: {embree['rays_per_second'] / 1e6:.2f} M rays/s")
        result["embree"] = {k: v for k, v in embree.items() if k not in unreported}
        for row in traced:
            agreement = distance_agreement(row, embree, min(DISTANCE_CHECK_RAYS, ray_count))
            agreement["spectrace"] = row["runtime"]
            # Round by round, spectrace's rays/s per core over Embree's in the same round: median (min, max).
            ratios = np.divide(row["round_rays_per_second_per_core"], embree["round_rays_per_second_per_core"])
            agreement["per_core_ratio"] = float(np.median(ratios))
            agreement["per_core_ratio_range"] = [float(ratios.min()), float(ratios.max())]
            result["agreement"].append(agreement)
    result["spectrace"] = [{k: v for k, v in row.items() if k not in unreported} for row in traced]
    return result


def rays_tables(result: dict) -> list:
    from rich.table import Table

    bvh = result["bvh"]
    build = Table(title=f"BVH build: {result['triangles']} triangles (binned SAH, numpy)")
    for column in (
        "build s",
        "build CPU s",
        "peak traced MiB",
        "peak RSS MiB",
        "nodes",
        "depth",
        "SAH cost",
        "wide nodes",
        "wide depth",
        "leaf blocks",
        "node buffer MiB",
    ):
        build.add_column(column, justify="right")
    build.add_row(
        f"{bvh['build_seconds']:.2f}",
        f"{bvh['build_cpu_seconds']:.2f}",
        f"{bvh['peak_traced_bytes'] / 2**20:.0f}",
        f"{bvh['peak_resident_bytes'] / 2**20:.0f}",
        str(bvh["nodes"]),
        str(bvh["depth"]),
        f"{bvh['sah_cost']:.1f}",
        str(bvh["nodes_wide"]),
        str(bvh["depth_wide"]),
        str(bvh["leaf_blocks"]),
        f"{bvh['node_buffer_bytes'] / 2**20:.0f}",
    )
    rays = Table(
        title=f"closest-hit rays: {result['rays']} random rays, {result['triangles']} triangles "
        f"({result['rounds']} alternated rounds: medians)",
        caption=bench_rounds.load_text(result["load"]),
    )
    for column in ("tracer", "M rays/s", "cores used", "M rays/s per core", "time s"):
        rays.add_column(column, justify="left" if column == "tracer" else "right")
    rows = [(f"spectrace {r['runtime']}", r) for r in result["spectrace"]]
    if result["embree"]:
        rows.append(("embree (embreex)", result["embree"]))
    for name, r in rows:
        rays.add_row(
            name,
            f"{r['rays_per_second'] / 1e6:.2f}",
            f"{r['cores_used']:.2f}",
            f"{r['rays_per_second_per_core'] / 1e6:.2f}",
            f"{r['seconds']:.3f}",
        )
    tables = [build, rays]
    if result["agreement"]:
        check = Table(title="same rays, same answers? (spectrace vs Embree)")
        columns = ("spectrace", "rays", "same hit/miss", "same triangle", "|Δt|/t ≤ 1e-4", "per-core ratio (min-max)")
        for column in columns:
            check.add_column(column, justify="left" if column == "spectrace" else "right")
        for a in result["agreement"]:
            check.add_row(
                a["spectrace"],
                str(a["rays"]),
                f"{100 * a['same_hit_or_miss']:.3f} %",
                f"{100 * a['same_triangle']:.3f} %",
                f"{100 * a['within_1e-4']:.3f} %",
                f"{a['per_core_ratio']:.2f}x ({a['per_core_ratio_range'][0]:.2f}-{a['per_core_ratio_range'][1]:.2f})",
            )
        tables.append(check)
    return tables
