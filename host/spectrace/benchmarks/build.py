"""`spectrace bench build`: the BVH build of a large mesh, against Mitsuba 3 loading the same mesh.

spectrace's side is what a render pays, and reports, for its acceleration structure: the binary SAH build
(spectrace.geometry.bvh) and the wide node buffer with its leaf blocks (spectrace.geometry.bvh4), timed in wall
and CPU seconds, with the most memory either allocated at once (tracemalloc, which numpy reports its arrays to).
Mitsuba's side is its whole `load_dict` of the same triangles, written as binary PLY files (or the PLY files given):
reading the files, merging the shapes and building its own BVH (Embree in the scalar variants); or, given the
Mitsuba scene file those PLY files come from, its `load_file` of the whole scene (materials, emitters, textures).
It runs in a child process, so its peak resident size is its own (reported above the child's resident size just
before the load, where /proc tells it); with a scene file, the meshes alone are loaded too (`load_dict`). spectrace
builds with its default threads and, where that is more than one, on one thread too. All alternate, round by
round, so a shared machine's load falls on each; each one's best round is compared, and the medians are given.
"""

import json
import subprocess
import sys
import tempfile
import time
import tracemalloc
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from spectrace.benchmarks.rays import displaced_sphere, subdivisions_for
from spectrace.geometry.bvh import build_bvh, default_build_threads
from spectrace.geometry.bvh4 import LEAF_BLOCK, LEAF_SIZE, device_nodes
from spectrace.geometry.mesh import TriangleMesh, load_mesh

MITSUBA_VARIANT = "scalar_rgb"

# The child: load the PLY files as one scene (or the scene file); print seconds, CPU seconds, memory.
_MITSUBA_CHILD = """
import json, resource, sys, time
import mitsuba as mi
mi.set_variant(sys.argv[1])
if sys.argv[2] == "--xml":  # the scene file itself: everything it declares is loaded too
    load = lambda: mi.load_file(sys.argv[3])
else:
    scene = {"type": "scene"}
    for i, name in enumerate(sys.argv[2:]):
        scene[f"mesh{i}"] = {"type": "ply", "filename": name}
    load = lambda: mi.load_dict(scene)
def resident_kib():
    try:
        with open("/proc/self/status") as status:
            return next(int(line.split()[1]) for line in status if line.startswith("VmRSS:"))
    except OSError:
        return None
peak_before, now_before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss, resident_kib()
wall, cpu = time.perf_counter(), time.process_time()
loaded = load()
wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
peak_after, now_after = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss, resident_kib()
# The load's peak above the size before it, where the load set a new peak (else the import's peak hides it, and
# what stays resident is the lower bound reported).
if now_before is None:
    growth = peak_after - peak_before
else:
    growth = peak_after - now_before if peak_after > peak_before else now_after - now_before
triangles = sum(shape.face_count() for shape in loaded.shapes())
print(json.dumps({"seconds": wall, "cpu_seconds": cpu, "peak_rss_growth_bytes": max(0, growth) * 1024,
                  "triangles": triangles, "version": mi.__version__}))
"""


def read_meshes(paths: list[Path]) -> tuple[TriangleMesh, list[Path]]:
    """The triangles of every mesh file (a folder stands for the .ply files in it) as one mesh, and the files."""
    files: list[Path] = []
    for path in paths:
        files += sorted(path.glob("*.ply")) if path.is_dir() else [path]
    vertices: list[np.ndarray] = []
    faces: list[np.ndarray] = []
    offset = 0
    for file in files:
        mesh = load_mesh(file, where=str(file))  # as a scene's mesh is read
        vertices.append(np.asarray(mesh.vertices, np.float64))
        faces.append(np.asarray(mesh.faces, np.int64) + offset)
        offset += len(mesh.vertices)
    return TriangleMesh(vertices=np.concatenate(vertices), faces=np.concatenate(faces)), files


def spectrace_build(mesh: TriangleMesh, threads: int | None = None) -> dict:
    """The binary build (on `threads` threads, None: the default) and the wide node buffer, as a render makes
    them (and reports them: the vertices put in leaf order between the two are scene assembly, not counted);
    traced once more for the memory."""
    v0, v1, v2 = mesh.triangles()

    def leaf_order_vertices(bvh) -> np.ndarray:
        ordered = np.zeros((len(v0), 3, 4), np.float32)
        for corner, v in enumerate((v0, v1, v2)):
            ordered[:, corner, :3] = v[bvh.prim_order]
        return ordered.reshape(-1, 4)

    cpu = time.process_time()
    bvh = build_bvh(v0, v1, v2, max_leaf_size=LEAF_SIZE, leaf_block=LEAF_BLOCK, threads=threads)
    cpu = time.process_time() - cpu
    vertices = leaf_order_vertices(bvh)
    wall, nodes_cpu = time.perf_counter(), time.process_time()
    nodes = device_nodes(bvh, vertices)
    wall, nodes_cpu = time.perf_counter() - wall, time.process_time() - nodes_cpu
    peaks = []
    for work in (
        lambda: build_bvh(v0, v1, v2, max_leaf_size=LEAF_SIZE, leaf_block=LEAF_BLOCK, threads=threads),
        lambda: device_nodes(bvh, vertices),
    ):
        tracemalloc.start()
        try:
            work()
            peaks.append(tracemalloc.get_traced_memory()[1])
        finally:
            tracemalloc.stop()
    return {
        "seconds": bvh.build_seconds + wall,
        "cpu_seconds": cpu + nodes_cpu,
        "binary_build_seconds": bvh.build_seconds,
        "peak_traced_bytes": int(max(peaks)),
        "nodes": int(len(bvh.nodes)),
        "depth": int(bvh.depth),
        "sah_cost": bvh.sah_cost,
        "node_buffer_bytes": int(nodes.nbytes),
        "threads": default_build_threads() if threads is None else threads,
    }


def mitsuba_load(files: list[Path], scene_file: Path | None = None, variant: str = MITSUBA_VARIANT) -> dict:
    """Mitsuba's load of the PLY files (load_dict), or of a whole scene file (load_file) when one is given."""
    what = ["--xml", str(scene_file)] if scene_file is not None else [str(f) for f in files]
    child = subprocess.run([sys.executable, "-c", _MITSUBA_CHILD, variant, *what], capture_output=True, text=True)
    if child.returncode != 0:
        raise RuntimeError(child.stderr.strip().splitlines()[-1] if child.stderr.strip() else "no output")
    row = json.loads(child.stdout.strip().splitlines()[-1])
    return row


def run_build_bench(
    triangles: int,
    meshes: list[Path],
    rounds: int,
    log: Callable[[str], None] = lambda text: None,
    mitsuba_scene: Path | None = None,
) -> dict:
    """mitsuba_scene: a Mitsuba scene file that uses these meshes, loaded whole (materials, emitters and all)
    instead of the meshes alone."""
    with tempfile.TemporaryDirectory() as folder:
        if meshes:
            mesh, files = read_meshes(meshes)
            source = f"{len(files)} mesh files"
        else:
            mesh = displaced_sphere(subdivisions_for(triangles))
            files = [Path(folder) / "mesh.ply"]
            from spectrace.interop.mitsuba.export import write_binary_ply

            write_binary_ply(TriangleMesh(mesh.vertices, mesh.faces), files[0])  # positions only, as Mitsuba times it
            source = "displaced icosphere"
        log(f"mesh: {source}, {len(mesh.faces)} triangles; {rounds} rounds of each")
        result: dict[str, Any] = {
            "triangles": int(len(mesh.faces)),
            "source": source,
            "mitsuba_loads": str(mitsuba_scene) if mitsuba_scene is not None else "the mesh files (load_dict)",
            "spectrace": [],
            "spectrace_one_thread": [],
            "mitsuba": [],
            "mitsuba_load_dict": [],
            "notes": [],
        }
        threads = default_build_threads()
        for round_index in range(rounds):
            row = spectrace_build(mesh)
            log(
                f"round {round_index + 1}: spectrace, {threads} threads, {row['seconds']:.2f} s"
                f" ({row['cpu_seconds']:.2f} CPU s)"
            )
            result["spectrace"].append(row)
            if threads > 1:
                row = spectrace_build(mesh, threads=1)
                log(
                    f"round {round_index + 1}: spectrace, 1 thread, {row['seconds']:.2f} s"
                    f" ({row['cpu_seconds']:.2f} CPU s)"
                )
                result["spectrace_one_thread"].append(row)
            try:
                import mitsuba  # noqa: F401  (only whether it is there; the child imports it)
            except ImportError:
                result["notes"].append("mitsuba is not installed (pip install 'spectrace[bench]'): no comparison")
                continue
            try:
                peer = mitsuba_load(files, mitsuba_scene)
            except RuntimeError as error:
                result["notes"].append(f"Mitsuba's load failed: {error}")
                continue
            log(f"round {round_index + 1}: Mitsuba {peer['seconds']:.2f} s ({peer['cpu_seconds']:.2f} CPU s)")
            result["mitsuba"].append(peer)
            if mitsuba_scene is not None:
                try:
                    peer = mitsuba_load(files)
                except RuntimeError as error:
                    result["notes"].append(f"Mitsuba's load_dict of the meshes failed: {error}")
                    continue
                log(
                    f"round {round_index + 1}: Mitsuba load_dict {peer['seconds']:.2f} s"
                    f" ({peer['cpu_seconds']:.2f} CPU s)"
                )
                result["mitsuba_load_dict"].append(peer)
    result["best"] = {}
    result["median"] = {}
    for key in ("spectrace", "spectrace_one_thread", "mitsuba", "mitsuba_load_dict"):
        if result[key]:
            result["best"][key] = min(result[key], key=lambda r: r["seconds"])
            result["median"][key] = {
                figure: float(np.median([r[figure] for r in result[key]])) for figure in ("seconds", "cpu_seconds")
            }
    best = result["best"]["spectrace"]
    if result["mitsuba"]:
        peer_best = result["best"]["mitsuba"]
        result["ratio_wall"] = best["seconds"] / peer_best["seconds"]
        result["ratio_cpu"] = best["cpu_seconds"] / max(peer_best["cpu_seconds"], 1e-9)
    return result


def build_tables(result: dict) -> list:
    from rich.table import Table

    table = Table(title=f"BVH build vs Mitsuba 3 load ({MITSUBA_VARIANT}): {result['triangles']} triangles")
    for column in ("", "wall s", "CPU s", "peak MiB", "SAH cost", "nodes", "node buffer MiB"):
        table.add_column(column, justify="left" if not column else "right")
    for key in ("spectrace", "spectrace_one_thread"):
        ours = result["best"].get(key)
        if ours:
            table.add_row(
                f"spectrace build + wide nodes, {ours['threads']} thread" + ("s" if ours["threads"] > 1 else ""),
                f"{ours['seconds']:.2f}",
                f"{ours['cpu_seconds']:.2f}",
                f"{ours['peak_traced_bytes'] / 2**20:.0f} (traced)",
                f"{ours['sah_cost']:.1f}",
                str(ours["nodes"]),
                f"{ours['node_buffer_bytes'] / 2**20:.0f}",
            )
    for key in ("mitsuba", "mitsuba_load_dict"):
        peer = result["best"].get(key)
        if peer:
            whole = key == "mitsuba" and result["mitsuba_loads"].endswith(".xml")
            table.add_row(
                f"Mitsuba {peer['version']} "
                + ("load_file (whole scene)" if whole else "load_dict (files, merge, BVH)"),
                f"{peer['seconds']:.2f}",
                f"{peer['cpu_seconds']:.2f}",
                f"{peer['peak_rss_growth_bytes'] / 2**20:.0f} (RSS growth)",
                "",
                "",
                "",
            )
    if result["best"].get("mitsuba"):
        table.add_row("ratio spectrace / Mitsuba", f"{result['ratio_wall']:.2f}x", f"{result['ratio_cpu']:.2f}x")
    return [table]
