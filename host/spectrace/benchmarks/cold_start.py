"""Cold kernel builds: the plain render bench run in a child process whose kernel caches are empty folders.

spectrace caches program binaries under SPECTRACE_CACHE_DIR and PoCL caches its own builds under
POCL_CACHE_DIR; both are read when the runtime starts, hence the fresh process. XDG_CACHE_HOME points at an
empty folder too, so no other per-user cache answers instead. The child also probes its devices afresh.
"""

import json
import os
import subprocess
import sys
import tempfile


def run_cold_bench(size: int, spp: int, max_depth: int, device: str | None, scene: str | None) -> list[dict]:
    with tempfile.TemporaryDirectory(prefix="spectrace-cold-") as folder:
        env = dict(os.environ, SPECTRACE_CACHE_DIR=os.path.join(folder, "spectrace"),
                   POCL_CACHE_DIR=os.path.join(folder, "pocl"), XDG_CACHE_HOME=os.path.join(folder, "xdg"))
        command = [sys.executable, "-m", "spectrace", "bench", "--json", "--size", str(size), "--spp", str(spp),
                   "--max-depth", str(max_depth)]
        if device:
            command += ["--device", device]
        if scene:
            command += ["--scene", scene]
        child = subprocess.run(command, env=env, capture_output=True, text=True)
    if child.returncode != 0:
        from spectrace.errors import SpectraceError

        raise SpectraceError(f"the cold-start bench failed: {child.stderr.strip().splitlines()[-1:]}")
    rows = json.loads(child.stdout)["render"]
    for row in rows:
        row["cold"] = True
    return rows
