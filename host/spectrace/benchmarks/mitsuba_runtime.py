"""Mitsuba 3 as a benchmark peer: which spectral variants run here, and timed renders of an exported scene.

`llvm_ad_spectral` runs Mitsuba's vectorised CPU code through Dr.Jit's LLVM backend, which needs a shared
libLLVM that Dr.Jit accepts (recent versions, e.g. LLVM 19; with Debian 12's LLVM 15 Dr.Jit aborts the process
compiling its first kernel). When DRJIT_LIBLLVM_PATH is unset we look for one in the usual system folders before
Mitsuba is imported. Each variant is first tried in a child process (`probe_variant`), so a variant that would
abort is reported as unavailable with the reason. `scalar_spectral` needs no LLVM and is always tried.
"""

import glob
import json
import os
import re
import signal
import subprocess
import sys
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np

LLVM_VARIANT = "llvm_ad_spectral"
SCALAR_VARIANT = "scalar_spectral"
# Newest first: Dr.Jit wants a recent LLVM.
_LIBLLVM_PATTERNS = [
    "/usr/lib/llvm-{v}/lib/libLLVM*.so*",
    "/usr/lib/x86_64-linux-gnu/libLLVM-{v}.so*",
    "/usr/lib/x86_64-linux-gnu/libLLVM.so.{v}*",
    "/usr/lib64/libLLVM-{v}.so*",
]
_NEWEST_FIRST = range(22, 15, -1)


def find_libllvm() -> str | None:
    """A libLLVM shared library of version 16 or newer, or None."""
    for version in _NEWEST_FIRST:
        for pattern in _LIBLLVM_PATTERNS:
            found = sorted(p for p in glob.glob(pattern.format(v=version)) if not p.endswith(".a"))
            if found:
                return found[0]
    return None


LIBLLVM_HINT = (
    "Dr.Jit needs a recent shared libLLVM: install one (Debian/Ubuntu: `apt-get install libllvm19`) "
    "or point DRJIT_LIBLLVM_PATH at one"
)

# Run in a child process: Dr.Jit compiles the first kernel with whatever libLLVM it loaded, and an LLVM that cannot
# select one of the instructions it emits (LLVM 15 and `fminimum`, measured) aborts the whole process, which no
# `except` can catch. The child loads the variant, names the libLLVM it mapped, and renders a few pixels.
_PROBE_CODE = r"""
import sys
import mitsuba as mi
variant = sys.argv[1]
mi.set_variant(variant)
if variant.startswith("llvm"):
    import drjit as dr
    dr.eval(dr.llvm.Float(1.0, 2.0) + 1.0)
    with open("/proc/self/maps") as maps:
        names = sorted({line.split()[-1] for line in maps if "libLLVM" in line})
    print("libllvm:", names[0] if names else "", flush=True)
scene = mi.cornell_box()
scene["sensor"]["film"].update(width=4, height=4)
image = mi.render(mi.load_dict(scene), spp=1)
print("ok", flush=True)
"""
_PROBE_TIMEOUT_SECONDS = 300


@dataclass
class VariantProbe:
    ok: bool
    reason: str = ""  # why not, one line
    libllvm: str = ""  # the libLLVM the child loaded (LLVM variants)
    timed_out: bool = False


def _probe_cache_file() -> Path:
    from spectrace.device.discovery import cache_root

    return cache_root() / "mitsuba-variants.json"


def libllvm_to_use() -> str:
    """The libLLVM Dr.Jit is to load: DRJIT_LIBLLVM_PATH, else one found here, else "" (Dr.Jit's own search)."""
    return os.environ.get("DRJIT_LIBLLVM_PATH") or find_libllvm() or ""


def _probe_key(variant: str, libllvm: str) -> str:
    """What the answer depends on: Mitsuba's and Dr.Jit's versions and the libLLVM asked for (with its size and
    time, so an upgraded package is probed again)."""
    try:
        from importlib.metadata import version

        versions = f"mitsuba {version('mitsuba')} drjit {version('drjit')}"
    except Exception:
        versions = "mitsuba ?"
    try:
        stat = os.stat(libllvm) if libllvm else None
    except OSError:
        stat = None
    stamp = f"{stat.st_size}:{int(stat.st_mtime)}" if stat else ""
    return f"{variant} | {versions} | {sys.executable} | libllvm {libllvm} {stamp}"


def _probe_in_child(variant: str, libllvm: str) -> VariantProbe:
    env = dict(os.environ, **({"DRJIT_LIBLLVM_PATH": libllvm} if libllvm else {}))
    try:
        result = subprocess.run(
            [sys.executable, "-c", _PROBE_CODE, variant],
            capture_output=True,
            text=True,
            timeout=_PROBE_TIMEOUT_SECONDS,
            env=env,
        )
    except subprocess.TimeoutExpired:
        return VariantProbe(False, f"a 4x4 test render took over {_PROBE_TIMEOUT_SECONDS} s", timed_out=True)
    libllvm = next(
        (line.split(":", 1)[1].strip() for line in result.stdout.splitlines() if line.startswith("libllvm:")), ""
    )
    if result.returncode == 0 and "ok" in result.stdout.split():
        return VariantProbe(True, libllvm=libllvm)
    lines = [line.strip() for line in result.stderr.splitlines() if line.strip()]
    # LLVM's own message names what failed; a Python error's last line says it; else the exit status alone.
    cause = next((line for line in lines if line.startswith("LLVM ERROR")), lines[-1] if lines else "")
    # LLVM's node addresses differ every run: without them the reason is the same each time.
    cause = " ".join(word for word in cause.split() if not re.fullmatch(r"0x[0-9a-fA-F]+[:,]?", word))
    if len(cause) > 160:
        cause = cause[:157] + "..."
    if result.returncode < 0:
        try:
            status = f"the test render died of {signal.Signals(-result.returncode).name}"
        except ValueError:
            status = f"the test render died of signal {-result.returncode}"
    else:
        status = f"loading it failed (exit status {result.returncode})"
    reason = f"{status}: {cause}" if cause else status
    if libllvm:
        reason += f" (with {libllvm})"
    return VariantProbe(False, reason, libllvm)


def probe_variant(variant: str) -> VariantProbe:
    """Whether `variant` loads and renders here, found in a child process (an abort there is a reason, not a crash
    here) and remembered per Mitsuba version and libLLVM in the user cache: the child takes a second or more.
    Reasons for LLVM variants end with how to get a libLLVM that works."""
    libllvm = libllvm_to_use()
    key = _probe_key(variant, libllvm)
    cache_file = _probe_cache_file()
    try:
        cached = json.loads(cache_file.read_text())
    except (OSError, ValueError):
        cached = {}
    if not isinstance(cached, dict):
        cached = {}
    if isinstance(entry := cached.get(key), dict):
        return VariantProbe(bool(entry.get("ok")), str(entry.get("reason", "")), str(entry.get("libllvm", "")))
    probe = _probe_in_child(variant, libllvm)
    if not probe.ok and variant.startswith("llvm"):
        probe.reason += f"; {LIBLLVM_HINT}"
    if probe.timed_out:
        return probe  # perhaps a busy machine: ask again next time
    cached[key] = asdict(probe)
    try:
        from spectrace.io.atomic import write_atomically

        text = json.dumps(cached, indent=1)
        write_atomically(cache_file, lambda temp: temp.write_text(text))
    except OSError:
        pass  # an unwritable cache costs a child process next time, nothing more
    return probe


def _log_to_stderr(mi) -> None:
    """Sends Mitsuba's log (e.g. a sampler rounding its sample count) to stderr, where spectrace's progress goes:
    by default Mitsuba writes it to stdout, which `spectrace bench --json` keeps for its one JSON object."""

    class StderrAppender(mi.Appender):
        def append(self, level, text):
            print(text, file=sys.stderr)

        def log_progress(self, progress, name, formatted, eta, ptr=None):
            pass

    logger = mi.logger()
    logger.clear_appenders()
    logger.add_appender(StderrAppender())


@dataclass
class MitsubaVariants:
    available: list[str]
    notes: list[str] = field(default_factory=list)


def usable_variants(wanted: list[str] | None = None) -> MitsubaVariants:
    """The spectral variants that load here, in the order asked (default: LLVM first, then scalar), with a note
    for each one that does not. Imports mitsuba; raises ImportError when it is not installed."""
    notes = []
    if path := libllvm_to_use():
        os.environ["DRJIT_LIBLLVM_PATH"] = path  # read by Dr.Jit when its LLVM backend first starts
    import mitsuba as mi

    _log_to_stderr(mi)
    available = []
    for variant in wanted or [LLVM_VARIANT, SCALAR_VARIANT]:
        if variant not in mi.variants():
            notes.append(f"{variant}: variant unavailable: not in this Mitsuba build")
            continue
        probe = probe_variant(variant)
        if not probe.ok:
            notes.append(f"{variant}: variant unavailable: {probe.reason}")
            continue
        if probe.libllvm and "DRJIT_LIBLLVM_PATH" not in os.environ:
            # This process may have other LLVMs loaded by then (OpenCL runtimes): use the one the child tested.
            os.environ["DRJIT_LIBLLVM_PATH"] = probe.libllvm
        try:
            mi.set_variant(variant)
        except Exception as error:  # Dr.Jit reports a missing or refused libLLVM as ImportError/RuntimeError
            notes.append(f"{variant}: variant unavailable: {str(error).splitlines()[0]}")
            continue
        available.append(variant)
    if LLVM_VARIANT not in available and available:
        notes.append(f"comparing with {', '.join(available)} only; Mitsuba's fast CPU variant is {LLVM_VARIANT}")
    return MitsubaVariants(available, notes)


@dataclass
class MitsubaRender:
    variant: str
    xyz: np.ndarray  # (height, width, 3) film XYZ in spectrace's normalisation (see mitsuba_film_xyz)
    load_seconds: float
    first_render_seconds: float | None  # the warm-up: JIT compilation (or Dr.Jit's disk cache) and the render
    seconds: float  # the best timed render, wall clock, film included
    cpu_seconds: float  # process CPU time (all threads) of that render
    threads: int
    spp: int  # samples per pixel rendered: some samplers round the count asked for (multijitter, stratified)


class MitsubaContestant:
    """A loaded Mitsuba scene that renders on demand, for timing rounds interleaved with other renderers.

    For JIT variants one identical warm-up render comes first, so the timed ones reuse the compiled kernels
    (the same seed gives the same kernel and the same image). Dr.Jit launches asynchronously: the clock stops
    once the image is copied out, which waits for the render."""

    def __init__(self, scene_dict: dict, variant: str, spp: int, seed: int = 0, warm_up: bool | None = None):
        import mitsuba as mi

        self.variant, self.spp, self.seed = variant, spp, seed
        self.name = variant
        mi.set_variant(variant)
        start = time.perf_counter()
        self.scene = mi.load_dict(scene_dict)
        self.load_seconds = time.perf_counter() - start
        self.first_render_seconds = None
        if warm_up if warm_up is not None else not variant.startswith("scalar"):
            start = time.perf_counter()
            self._render()
            self.first_render_seconds = time.perf_counter() - start
        self.seconds, self.cpu_seconds = float("inf"), float("inf")
        self.xyz: np.ndarray | None = None

    def _render(self) -> np.ndarray:
        import mitsuba as mi

        mi.set_variant(self.variant)
        # Mitsuba's stubs type the seed as its UInt32 array; a Python int converts implicitly.
        image = np.array(
            mi.render(self.scene, spp=self.spp, seed=self.seed),  # type: ignore[arg-type]
            dtype=np.float64,
        )
        self.rendered_spp = int(self.scene.sensors()[0].sampler().sample_count())
        return image

    def render_untimed(self) -> None:
        self._render()

    renderer = "mitsuba"

    def render_timed(self) -> tuple[float, float]:
        """One timed render: (wall seconds, process CPU seconds); keeps the fastest's figures and image."""
        start, cpu = time.perf_counter(), time.process_time()
        xyz = self._render()
        seconds, cpu = time.perf_counter() - start, time.process_time() - cpu
        if seconds < self.seconds:
            self.seconds, self.cpu_seconds, self.xyz = seconds, cpu, xyz
        return seconds, cpu

    def render_once(self) -> None:
        self.render_timed()

    def result(self) -> MitsubaRender:
        import drjit as dr
        import mitsuba as mi

        from spectrace.interop.mitsuba.export import mitsuba_film_xyz

        if self.xyz is None:
            raise RuntimeError("result() needs a timed render first (render_once)")
        mi.set_variant(self.variant)
        threads = int(dr.thread_count()) if hasattr(dr, "thread_count") else os.cpu_count() or 1
        return MitsubaRender(
            self.variant,
            mitsuba_film_xyz(self.xyz[..., :3], mi),
            self.load_seconds,
            self.first_render_seconds,
            self.seconds,
            self.cpu_seconds,
            threads,
            self.rendered_spp,
        )


def render_with_mitsuba(
    scene_dict: dict, variant: str, spp: int, seed: int = 0, warm_up: bool | None = None, repeats: int = 1
) -> MitsubaRender:
    """Load, warm up (JIT variants) and render `repeats` times; the fastest render's figures and image."""
    contestant = MitsubaContestant(scene_dict, variant, spp, seed, warm_up)
    for _ in range(max(1, repeats)):
        contestant.render_once()
    return contestant.result()
