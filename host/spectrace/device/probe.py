"""Does a device really work? Build a tiny kernel, run it once and check its numbers.

Listing a device proves little: the PyPI PoCL, for instance, lists every CPU but fails to compile any
kernel on CPUs its LLVM does not know ("unknown target CPU 'generic'"). Results are kept per process and on disk
(`probes.json` in the cache folder), keyed by everything that could change the answer: the runtime library's path,
size and modification time, the platform and driver versions, the device's name and pyopencl's compiled module
(its file's size and modification time, known without importing it). A build costs a few tenths of a second per
runtime, which `spectrace devices` and every render would otherwise pay; with every answer remembered, the listing
imports neither numpy nor pyopencl.

Tests replace ``probe_function`` to simulate a broken runtime, then call ``forget_probe_results()``.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
import sys
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from spectrace.device.discovery import FoundDevice, pyopencl_dir

if TYPE_CHECKING:
    from spectrace.device.program_cache import KernelBuildError

_PROBE_SOURCE = """
__kernel void spectrace_probe(__global const float* values, __global float* results, const float scale)
{
    const size_t i = get_global_id(0);
    results[i] = values[i] * scale + 1.0f;
}
"""
_PROBE_SIZE = 64
_FINGERPRINT_FORMAT = "probe-v2"
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
    import tempfile

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
    import numpy as np
    import pyopencl as cl

    from spectrace.device.program_cache import compile_source

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
    from spectrace.device.program_cache import KernelBuildError

    started = time.perf_counter()
    with _captured_stderr() as stderr_text:
        try:
            reason = _run_probe_kernel(found.opencl_device())
        except KernelBuildError as error:
            reason = f"kernel build failed: {_build_failure_cause(error, stderr_text())}"
        except Exception as error:  # noqa: BLE001 - any runtime failure makes the device unusable
            reason = _first_line(error)
    return ProbeResult(reason is None, reason, time.perf_counter() - started)


def _build_failure_cause(error: KernelBuildError, printed: str) -> str:
    from spectrace.device.program_cache import first_error_line

    # Some runtimes leave the build log empty or generic and print the compiler's error to stderr.
    if "error" not in error.build_log.lower() and "error" in printed.lower():
        return first_error_line(printed) or error.message
    return error.message


probe_function: Callable[[FoundDevice], ProbeResult] = probe_kernel_on_device
_results: dict[str, ProbeResult] = {}


def probe(found: FoundDevice) -> ProbeResult:
    """The probe result for `found`, measured once per process (and once per runtime version on disk)."""
    if found.key not in _results:
        _results[found.key] = _remembered_or_probed(found)
    return _results[found.key]


def _remembered_or_probed(found: FoundDevice) -> ProbeResult:
    # Tests that swap in their own probe function must see it called, so only the real probe is remembered.
    fingerprint = _fingerprint(found) if probe_function is probe_kernel_on_device else None
    if fingerprint is None:
        return probe_function(found)
    remembered = _read_remembered().get(fingerprint)
    if isinstance(remembered, dict) and isinstance(remembered.get("ok"), bool):
        return ProbeResult(remembered["ok"], remembered.get("reason"), 0.0)
    result = probe_function(found)
    # A build the compiler refuses fails again next time; other failures (memory, a busy device) may not.
    if result.ok or (result.reason or "").startswith("kernel build failed"):
        _remember(fingerprint, result)
    return result


def _fingerprint(found: FoundDevice) -> str | None:
    """A digest of what could change the probe's answer, or None when something of it cannot be known."""
    if found.device is None or found.platform is None:
        return None
    try:
        parts = [
            _FINGERPRINT_FORMAT,
            found.key,
            *_pyopencl_stamp(),
            found.platform.name,
            found.platform.version,
            found.device.name,
            found.device.version,
            found.device.driver_version,
        ]
        library = found.library if found.library and os.path.isabs(found.library) else _loaded_file(found.library)
        if library is None:
            return None
        status = os.stat(library)
        parts += [library, str(status.st_size), str(status.st_mtime_ns)]
    except Exception:  # noqa: BLE001 - any doubt means probing again, never a failure
        return None
    return hashlib.sha256("\n".join(map(str, parts)).encode()).hexdigest()


def _loaded_file(soname: str | None) -> str | None:
    """The file the dynamic loader took for a runtime named by its soname alone (Debian's PoCL .icd file says
    `libpocl.so.2`), or None where that cannot be asked. The runtime is already loaded (its devices were listed),
    so opening it again costs nothing, and asking the loader is the only way to follow its search exactly."""
    if not soname or not sys.platform.startswith("linux"):
        return None
    import ctypes

    class _LinkMap(ctypes.Structure):  # the head of glibc's struct link_map
        _fields_ = [("l_addr", ctypes.c_void_p), ("l_name", ctypes.c_char_p)]

    rtld_di_linkmap = 2
    try:
        handle = ctypes.CDLL(soname)
        link_map = ctypes.POINTER(_LinkMap)()
        if ctypes.CDLL(None).dlinfo(ctypes.c_void_p(handle._handle), rtld_di_linkmap, ctypes.byref(link_map)) != 0:
            return None
        name = link_map.contents.l_name
    except (OSError, AttributeError, ValueError):
        return None
    return os.path.realpath(name.decode()) if name and name.startswith(b"/") else None


def _pyopencl_stamp() -> list[str]:
    """pyopencl's compiled module (name, size, modification time), which a new pyopencl release replaces: its
    version without importing it."""
    folder = pyopencl_dir()
    if folder is None:
        raise FileNotFoundError("pyopencl is not installed")
    stamp = []
    for module in sorted(folder.glob("_cl.*")):
        status = module.stat()
        stamp += [module.name, str(status.st_size), str(status.st_mtime_ns)]
    if not stamp:
        raise FileNotFoundError(f"no compiled pyopencl module in {folder}")
    return stamp


def _remembered_path() -> Path:
    from spectrace.device.discovery import cache_root

    return cache_root() / "probes.json"


def _read_remembered() -> dict:
    try:
        data = json.loads(_remembered_path().read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return {}
    return data if isinstance(data, dict) else {}


def _remember(fingerprint: str, result: ProbeResult) -> None:
    from spectrace.io.atomic import write_atomically

    remembered = _read_remembered()
    remembered[fingerprint] = {"ok": result.ok, "reason": result.reason}
    text = json.dumps(remembered, indent=1, sort_keys=True)
    with contextlib.suppress(OSError):  # an unwritable cache only costs the probe again next time
        write_atomically(_remembered_path(), lambda temp: temp.write_text(text, encoding="utf-8"))


def forget_probe_results() -> None:
    _results.clear()
