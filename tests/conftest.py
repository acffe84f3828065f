"""Shared fixtures. Every test that runs kernels uses one device for the whole session, chosen as the CLI
chooses (SPECTRACE_DEVICE, else the automatic pick); the report header names it."""

import math
import os

import numpy as np
import pyopencl as cl
import pytest

from spectrace.cache_folder import cache_root
from spectrace.device import open_device
from spectrace.engine.launch import is_pocl
from spectrace.plugins import generated_sources

# Renders use the kernels built for every scene unless a test asks for a scene's own (the specialisation tests,
# which check that both give the same bits): one program per integrator and sampler instead of one per scene's
# feature set. A build with a film or polarisation define (a spectral film, AOVs, Stokes, a film range of its own)
# takes the scene's own kernels ("common"): each such general program took 40-100 s on PoCL for the few tests that
# share it, a scene's own 3-9 s; so does BDPT, whose general program took 330-390 s, a scene's own 3-5. Set here,
# so that child processes (the CLI tests) inherit it;
# SPECTRACE_GENERAL_KERNELS=0 runs the suite on the specialised kernels instead, 1 on the general ones alone.
os.environ.setdefault("SPECTRACE_GENERAL_KERNELS", "common")

# The suite starts hundreds of Python processes: its workers and the `python -m spectrace` children of the command
# line tests. Where the environment forbids bytecode files (PYTHONDONTWRITEBYTECODE), each child compiled the package
# from source again (~0.2 s of a 1 s command) and each worker rewrote every test module's assertions (~15 s): they
# keep their bytecode in spectrace's cache folder instead, never beside the sources. Set here, before the workers
# start, so that they and their children inherit it.
if os.environ.get("PYTHONDONTWRITEBYTECODE") and not os.environ.get("PYTHONPYCACHEPREFIX"):
    del os.environ["PYTHONDONTWRITEBYTECODE"]
    os.environ["PYTHONPYCACHEPREFIX"] = str(cache_root() / "pycache")

HARNESS_GROUP = 64


# How long a test is known to take, for the order below: marked slow (over ~1 s: docs pages, Cycles comparisons,
# fuzzers, real processes), then comparisons with a peer renderer, then the rest.
_LONG_MARKS = ("slow", "peer")


def _weight(item: pytest.Item) -> int:
    return next((rank for rank, mark in enumerate(_LONG_MARKS) if item.get_closest_marker(mark)), len(_LONG_MARKS))


def pytest_collection_modifyitems(session, config, items):
    """Modules holding known-long tests run first. xdist hands out the tests in this order (the first quarter
    dealt in turn to the workers, the rest as they ask), so long ones left at the end kept one worker busy while
    the other stood idle. Whole modules move, in their own order, so their module-scoped fixtures are set up once."""
    modules: dict[str, list[pytest.Item]] = {}
    for item in items:
        modules.setdefault(item.nodeid.split("::")[0], []).append(item)
    ranked = sorted(modules.values(), key=lambda group: min(_weight(item) for item in group))
    items[:] = [item for group in ranked for item in group]


def pytest_report_header(config):
    try:
        device = open_device()
    except Exception as exc:  # the header must not hide the real failure, which the tests then report
        return [f"spectrace OpenCL device: none ({exc})"]
    report = device.report
    return [
        f"spectrace OpenCL device: {report.key} | platform: {report.platform_name} {report.platform_version} | "
        f"device: {report.device_name}"
    ]


@pytest.fixture(scope="session")
def device():
    return open_device()


class KernelRunner:
    """Builds a harness kernel file and runs kernels on numpy arrays (inputs copied in, outputs copied back)."""

    def __init__(self, device, entry: str, defines: dict | None = None):
        self.device = device
        self.program = device.build_program(entry, defines=defines or None, generated=generated_sources())
        self.kernels = {}

    def buffer(self, array: np.ndarray, writable: bool = False) -> cl.Buffer:
        flags = (cl.mem_flags.READ_WRITE if writable else cl.mem_flags.READ_ONLY) | cl.mem_flags.COPY_HOST_PTR
        return cl.Buffer(self.device.context, flags, hostbuf=np.ascontiguousarray(array))

    def _local_size(self, global_size: int) -> tuple[int] | None:
        # PoCL compiles a kernel anew for each work-group size, and left to choose it picks one from the global
        # size, so every test's own item count was one more compile. The harness kernels run one work-item per
        # item with no bounds check, so the group divides the global size: one of a few sizes for any count.
        return (math.gcd(global_size, HARNESS_GROUP),) if is_pocl(self.device) else None

    def run(self, name: str, global_size: int, args: list, outputs: dict[int, np.ndarray]) -> None:
        """args: buffers or numpy scalars; outputs: {argument index: host array to read that buffer into}."""
        if name not in self.kernels:
            self.kernels[name] = cl.Kernel(self.program, name)
        kernel = self.kernels[name]
        kernel(self.device.queue, (global_size,), self._local_size(global_size), *args)
        for index, host in outputs.items():
            cl.enqueue_copy(self.device.queue, host, args[index])
        self.device.queue.finish()


@pytest.fixture(scope="session")
def kernel_runner(device):
    cache = {}

    def get(entry: str, defines: dict | None = None) -> KernelRunner:
        key = (entry, tuple(sorted((defines or {}).items())))
        if key not in cache:
            cache[key] = KernelRunner(device, entry, defines)
        return cache[key]

    return get


@pytest.fixture
def mitsuba_scalar_spectral():
    """Mitsuba 3 set to its scalar_spectral variant, for tests that compare with it (a test extra, never needed to
    render); skips when it is missing."""
    mitsuba = pytest.importorskip("mitsuba", reason="the Mitsuba comparison needs `pip install spectrace[test]`")
    if "scalar_spectral" not in mitsuba.variants():
        pytest.skip("this mitsuba build has no scalar_spectral variant")
    mitsuba.set_variant("scalar_spectral")
    return mitsuba
