"""One core each, for `spectrace bench peer --per-core`: every thread of the process pinned to one core, one
compute unit of an OpenCL CPU runtime, and Dr.Jit's thread pool of one thread.

An OpenCL 1.2 device may be split into sub-devices (device fission, clCreateSubDevices); partitioned by counts
[1], the sub-device has one compute unit. That alone does not confine a runtime to one core. Intel's CPU runtime
runs a one-unit sub-device's kernels on its worker thread and on the thread that waits for them (clFinish, a
blocking read or clWaitForEvents): that thread runs work-groups until the queue is done, it does not spin. Waiting
instead by polling the event with sleeps left one thread busy and doubled the wall time at the same total CPU time
(Cornell box 128x128, 16 spp: 0.13 s on two busy threads against 0.24 s on one, 0.25 CPU-s both, whole device or
sub-device alike). PoCL's CPU driver accepts the partition but still runs the kernels on both of its worker
threads, and neither POCL_CPU_MAX_CU_COUNT nor POCL_MAX_CPU_CU_COUNT took its device below two compute units. So
`one_core` pins every thread of the process, and those they start, to one core (sched_setaffinity): each
renderer's wall time is then one core's work, whatever threads its runtime keeps. A platform without
sched_setaffinity is not pinned, and the figures to read there are the samples per CPU-second.
"""

from __future__ import annotations

import dataclasses
import os
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


def _thread_ids() -> list[int]:
    return [int(task) for task in os.listdir("/proc/self/task")]


@contextmanager
def one_core() -> Iterator[int | None]:
    """Every thread of this process on one core meanwhile (the highest-numbered it may use; threads started
    meanwhile inherit it), giving that core's number; then each thread back on the cores it had. None where the
    platform cannot pin threads."""
    if not hasattr(os, "sched_setaffinity") or not os.path.isdir("/proc/self/task"):
        yield None
        return
    allowed = os.sched_getaffinity(0)
    core = max(allowed)
    before: dict[int, set[int]] = {}
    for thread in _thread_ids():
        try:  # a thread may end meanwhile
            before[thread] = os.sched_getaffinity(thread)
            os.sched_setaffinity(thread, {core})
        except OSError:
            continue
    try:
        yield core
    finally:
        for thread in _thread_ids():
            try:
                os.sched_setaffinity(thread, before.get(thread, allowed))
            except OSError:
                continue
