"""One core each, for `spectrace bench peer --per-core`: one compute unit of an OpenCL CPU runtime, and Dr.Jit's
thread pool of one thread.

An OpenCL 1.2 device may be split into sub-devices (device fission, clCreateSubDevices); partitioned by counts
[1], the sub-device has one compute unit. With Intel's CPU runtime two threads are then busy for the whole render
(per-thread CPU time from /proc, each equal to the wall time): the pass's and the calling thread, which spins while
it waits. PoCL's CPU driver (system and PyPI builds) accepts the partition, but its sub-device still ran the
kernels on both of its worker threads (0.18 and 0.17 CPU-s in a 0.35 s render, 128x128, 16 spp), and neither
POCL_CPU_MAX_CU_COUNT nor POCL_MAX_CPU_CU_COUNT took its device below two compute units. So the per-core figures
are these: Intel's, the wall clock on a quiet machine (its spinning thread has a core of its own there); PoCL's,
samples per CPU-second (its wall clock had two threads). Samples per CPU-second, which other processes' load
disturbs least, charge Intel's runtime for its spinning thread too: they understate spectrace, never the peer. A
runtime without fission keeps its whole device, which the table says.
"""

from __future__ import annotations

import dataclasses
from contextlib import contextmanager
from typing import TYPE_CHECKING, Any, cast

if TYPE_CHECKING:
    from collections.abc import Iterator

    from spectrace.device.program_cache import Device

FISSION = "sub-device of 1 compute unit (device fission)"
NO_FISSION = "whole device (no device fission here): CPU time of all its threads"


def open_one_compute_unit(key: str | None) -> tuple[Device, str]:
    """The device `key` names reduced to one compute unit where the runtime can split it, and how."""
    import pyopencl as cl

    from spectrace.device import open_device
    from spectrace.device.program_cache import Device

    device = open_device(key)
    props = cl.device_partition_property
    try:
        offered = cast("list[int]", device.cl_device.get_info(cl.device_info.PARTITION_PROPERTIES) or [])
        if props.BY_COUNTS not in offered:
            return device, NO_FISSION
        counts: list[Any] = [props.BY_COUNTS, 1, props.BY_COUNTS_LIST_END]
        (sub,) = device.cl_device.create_sub_devices(counts)
    except (cl.Error, ValueError):
        return device, NO_FISSION
    # Same report otherwise: the sub-device runs the same binaries, so the program cache serves it too.
    return Device(dataclasses.replace(device.report, compute_units=1), sub), FISSION


@contextmanager
def drjit_threads(count: int | None) -> Iterator[None]:
    """Dr.Jit's thread pool (which Mitsuba's scalar and LLVM variants render on) at `count` threads meanwhile;
    None leaves it alone."""
    if count is None:
        yield
        return
    import drjit as dr

    before = dr.thread_count()
    dr.set_thread_count(count)
    try:
        yield
    finally:
        dr.set_thread_count(before)
