"""Does a device really work? Build a tiny kernel, run it once and check its numbers.

Listing a device proves little: the PyPI PoCL, for instance, lists every CPU but fails to compile any
kernel on CPUs its LLVM does not know ("unknown target CPU 'generic'"). Results are kept per process.

Tests replace ``probe_function`` to simulate a broken runtime, then call ``forget_probe_results()``.
"""

from __future__ import annotations

import contextlib
import os
import sys
import tempfile
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass

import numpy as np

from spectrace.device.discovery import FoundDevice
from spectrace.device.program_cache import KernelBuildError, compile_source, first_error_line

_PROBE_SOURCE = """
__kernel void spectrace_probe(__global const float* values, __global float* results, const float scale)
{
    const size_t i = get_global_id(0);
    results[i] = values[i] * scale + 1.0f;
}
"""
_PROBE_SIZE = 64
_PROBE_SCALE = 2.0


@dataclass(frozen=True)
class ProbeResult:
    ok: bool
    reason: str | None = None  # one line, e.g. "kernel build failed: unknown target CPU 'generic'"
    seconds: float = 0.0


@contextlib.contextmanager
def _captured_stderr() -> Iterator[Callable[[], str]]:
    """Collect what native code writes to file descriptor 2 (some runtimes print compiler errors there
    instead of the build log), so it becomes the reason rather than noise on the terminal."""
    try:
        saved = os.dup(2)
    except OSError:
        yield lambda: ""
        return
    with tempfile.TemporaryFile(mode="w+b") as capture:
        sys.stderr.flush()
        os.dup2(capture.fileno(), 2)
        try:
            yield lambda: (capture.seek(0), capture.read().decode(errors="replace"))[1]
        finally:
            sys.stderr.flush()
            os.dup2(saved, 2)
            os.close(saved)


def _first_line(error: BaseException) -> str:
    text = str(error).strip()
    return text.splitlines()[0] if text else type(error).__name__


def _run_probe_kernel(device) -> str | None:
    """Build and run the probe kernel on `device`; the failure reason, or None when it works."""
    import pyopencl as cl

    context = cl.Context([device])
    queue = cl.CommandQueue(context)
    program = compile_source(context, device, _PROBE_SOURCE, "-cl-std=CL1.2")
    values = np.arange(_PROBE_SIZE, dtype=np.float32)
    results = np.zeros_like(values)
    flags = cl.mem_flags
    values_buffer = cl.Buffer(context, flags.READ_ONLY | flags.COPY_HOST_PTR, hostbuf=values)
    results_buffer = cl.Buffer(context, flags.WRITE_ONLY, results.nbytes)
    kernel = cl.Kernel(program, "spectrace_probe")
    kernel.set_args(values_buffer, results_buffer, np.float32(_PROBE_SCALE))
    cl.enqueue_nd_range_kernel(queue, kernel, (_PROBE_SIZE,), None)
    cl.enqueue_copy(queue, results, results_buffer)
    queue.finish()
    # Small integers times 2 plus 1 are exact in float32, so any difference is a broken runtime.
    if not np.array_equal(results, values * np.float32(_PROBE_SCALE) + np.float32(1.0)):
        return "probe kernel returned wrong values"
    return None


def probe_kernel_on_device(found: FoundDevice) -> ProbeResult:
    """The real probe: context, build, run, check."""
    if found.device is None:
        return ProbeResult(False, found.load_error or "no device")
    started = time.perf_counter()
    with _captured_stderr() as stderr_text:
        try:
            reason = _run_probe_kernel(found.device)
        except KernelBuildError as error:
            reason = f"kernel build failed: {_build_failure_cause(error, stderr_text())}"
        except Exception as error:  # noqa: BLE001 - any runtime failure makes the device unusable
            reason = _first_line(error)
    return ProbeResult(reason is None, reason, time.perf_counter() - started)


def _build_failure_cause(error: KernelBuildError, printed: str) -> str:
    # Some runtimes leave the build log empty or generic and print the compiler's error to stderr.
    if "error" not in error.build_log.lower() and "error" in printed.lower():
        return first_error_line(printed) or error.message
    return error.message


probe_function: Callable[[FoundDevice], ProbeResult] = probe_kernel_on_device
_results: dict[str, ProbeResult] = {}


def probe(found: FoundDevice) -> ProbeResult:
    """The probe result for `found`, measured once per process."""
    if found.key not in _results:
        _results[found.key] = probe_function(found)
    return _results[found.key]


def forget_probe_results() -> None:
    _results.clear()
