"""Cold and warm starts: the plain render bench run twice in child processes that share one set of kernel caches,
empty before the first.

spectrace caches program binaries under SPECTRACE_CACHE_DIR and PoCL caches its own builds under
POCL_CACHE_DIR; both are read when the runtime starts, hence fresh processes. XDG_CACHE_HOME points at an empty
folder too, so no other per-user cache answers instead. The first child builds everything from source (and
probes its devices afresh); the second starts as a user's next run would, from the binaries the first left.
"""

import json
import os
import subprocess
import sys
import tempfile
import time

from spectrace.errors import SpectraceError


def _child_bench(env: dict, size: int, spp: int, max_depth: int, device: str | None, scene: str | None) -> list[dict]:
    command = [
        sys.executable,
        "-m",
        "spectrace",
        "bench",
        "--json",
        "--size",
        str(size),
        "--spp",
        str(spp),
        "--max-depth",
        str(max_depth),
    ]
    if device:
        command += ["--device", device]
    if scene:
        command += ["--scene", scene]
    start = time.perf_counter()
    child = subprocess.run(command, env=env, capture_output=True, text=True)
    process_seconds = time.perf_counter() - start
    if child.returncode != 0:
        last = child.stderr.strip().splitlines()[-1:] or ["no message"]
        raise SpectraceError(f"the cold-start bench failed: {last[0]}")
    rows = json.loads(child.stdout)["render"]
    for row in rows:
        # The whole child: interpreter start, imports, device discovery, scene load, build, the bench's passes.
        row["process_seconds"] = process_seconds
    return rows


def run_cold_bench(
    size: int, spp: int, max_depth: int, device: str | None, scene: str | None
) -> tuple[list[dict], list[dict]]:
    """(cold rows, warm rows) of the plain bench."""
    with tempfile.TemporaryDirectory(prefix="spectrace-cold-") as folder:
        env = dict(
            os.environ,
            SPECTRACE_CACHE_DIR=os.path.join(folder, "spectrace"),
            POCL_CACHE_DIR=os.path.join(folder, "pocl"),
            XDG_CACHE_HOME=os.path.join(folder, "xdg"),
        )
        cold = _child_bench(env, size, spp, max_depth, device, scene)
        warm = _child_bench(env, size, spp, max_depth, device, scene)
    return cold, warm


def cold_tables(cold: list[dict], warm: list[dict]) -> list:
    from spectrace.benchmarks.render import render_bench_table

    tables = [render_bench_table(cold), render_bench_table(warm)]
    tables[0].title = "cold start (empty kernel caches): build s and to 1st pass s are the cold figures"
    tables[1].title = "warm start (a fresh process, the cold run's cached binaries)"
    return tables
