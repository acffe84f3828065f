"""Mitsuba 3 as a benchmark peer: which spectral variants run here, and timed renders of an exported scene.

`llvm_ad_spectral` runs Mitsuba's vectorised CPU code through Dr.Jit's LLVM backend, which needs a shared
libLLVM that Dr.Jit accepts (recent versions, e.g. LLVM 19; Dr.Jit refused LLVM 15 where we tried). When
DRJIT_LIBLLVM_PATH is unset we look for one in the usual system folders before Mitsuba is imported.
`scalar_spectral` needs no LLVM and is always tried.
"""

import glob
import os
import sys
import time
from dataclasses import dataclass, field

import numpy as np

LLVM_VARIANT = "llvm_ad_spectral"
SCALAR_VARIANT = "scalar_spectral"
# Newest first: Dr.Jit wants a recent LLVM.
_LIBLLVM_PATTERNS = ["/usr/lib/llvm-{v}/lib/libLLVM*.so*", "/usr/lib/x86_64-linux-gnu/libLLVM-{v}.so*",
                     "/usr/lib/x86_64-linux-gnu/libLLVM.so.{v}*", "/usr/lib64/libLLVM-{v}.so*"]
_NEWEST_FIRST = range(22, 15, -1)


def find_libllvm() -> str | None:
    """A libLLVM shared library of version 16 or newer, or None."""
    for version in _NEWEST_FIRST:
        for pattern in _LIBLLVM_PATTERNS:
            found = sorted(p for p in glob.glob(pattern.format(v=version)) if not p.endswith(".a"))
            if found:
                return found[0]
    return None


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
    if "DRJIT_LIBLLVM_PATH" not in os.environ and (path := find_libllvm()):
        os.environ["DRJIT_LIBLLVM_PATH"] = path  # read by Dr.Jit when its LLVM backend first starts
    import mitsuba as mi

    _log_to_stderr(mi)
    available = []
    for variant in wanted or [LLVM_VARIANT, SCALAR_VARIANT]:
        if variant not in mi.variants():
            notes.append(f"{variant}: not in this Mitsuba build")
            continue
        try:
            mi.set_variant(variant)
        except Exception as error:  # Dr.Jit reports a missing or refused libLLVM as ImportError/RuntimeError
            hint = " (install a recent libLLVM, e.g. Debian's libllvm19, or set DRJIT_LIBLLVM_PATH)" \
                if variant.startswith("llvm") else ""
            notes.append(f"{variant}: unusable here: {str(error).splitlines()[0]}{hint}")
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
        mi.set_variant(variant)
        start = time.perf_counter()
        self.scene = mi.load_dict(scene_dict)
        self.load_seconds = time.perf_counter() - start
        self.first_render_seconds = None
        if warm_up if warm_up is not None else not variant.startswith("scalar"):
            start = time.perf_counter()
            self._render()
            self.first_render_seconds = time.perf_counter() - start
        self.seconds, self.cpu_seconds, self.xyz = float("inf"), float("inf"), None

    def _render(self) -> np.ndarray:
        import mitsuba as mi

        mi.set_variant(self.variant)
        image = np.array(mi.render(self.scene, spp=self.spp, seed=self.seed), dtype=np.float64)
        self.rendered_spp = int(self.scene.sensors()[0].sampler().sample_count())
        return image

    def render_untimed(self) -> None:
        self._render()

    def render_once(self) -> None:
        """One timed render; keeps the fastest."""
        start, cpu = time.perf_counter(), time.process_time()
        xyz = self._render()
        seconds, cpu = time.perf_counter() - start, time.process_time() - cpu
        if seconds < self.seconds:
            self.seconds, self.cpu_seconds, self.xyz = seconds, cpu, xyz

    def result(self) -> MitsubaRender:
        import mitsuba as mi
        import drjit as dr

        from spectrace.interop.mitsuba_export import mitsuba_film_xyz

        mi.set_variant(self.variant)
        threads = int(dr.thread_count()) if hasattr(dr, "thread_count") else os.cpu_count() or 1
        return MitsubaRender(self.variant, mitsuba_film_xyz(self.xyz[..., :3], mi), self.load_seconds,
                             self.first_render_seconds, self.seconds, self.cpu_seconds, threads, self.rendered_spp)


def render_with_mitsuba(scene_dict: dict, variant: str, spp: int, seed: int = 0, warm_up: bool | None = None,
                        repeats: int = 1) -> MitsubaRender:
    """Load, warm up (JIT variants) and render `repeats` times; the fastest render's figures and image."""
    contestant = MitsubaContestant(scene_dict, variant, spp, seed, warm_up)
    for _ in range(max(1, repeats)):
        contestant.render_once()
    return contestant.result()
