"""OpenCL failures at run time (allocation, enqueue, a lost device) as one-line SpectraceErrors that say what to do.

Kernel build failures are not handled here: device.program_cache raises KernelBuildError with the compiler's log.
"""

import functools
from collections.abc import Callable
from typing import TypeVar

import pyopencl as cl

from spectrace.errors import SpectraceError

_OUT_OF_MEMORY = {"MEM_OBJECT_ALLOCATION_FAILURE", "OUT_OF_RESOURCES", "OUT_OF_HOST_MEMORY", "INVALID_BUFFER_SIZE"}
_DEVICE_LOST = {"DEVICE_NOT_AVAILABLE", "INVALID_COMMAND_QUEUE", "INVALID_CONTEXT", "INVALID_DEVICE"}

_OUT_OF_MEMORY_HINT = (
    "the device ran out of memory or resources: lower --width/--height, or choose another device "
    "(`spectrace devices` lists them; pick one with --device or SPECTRACE_DEVICE)"
)
_DEVICE_LOST_HINT = (
    "the device stopped responding (driver reset, GPU watchdog or a lost device): resume from the "
    "last checkpoint with --resume, on this device or another one (--device)"
)

Method = TypeVar("Method", bound=Callable)


def status_name(error: cl.Error) -> str:
    """'OUT_OF_RESOURCES' for an error with status -5; '' when pyopencl gives no code."""
    try:
        code = error.code
    except (AttributeError, IndexError, TypeError):
        return ""
    # pyopencl's stub declares to_string inside the enum, where a type checker takes it for a member.
    return cl.status_code.to_string(code, "<unknown error %d>")  # type: ignore[operator]


def describe_opencl_error(error: BaseException, action: str, device: str) -> str:
    """One line: what failed, on which device, OpenCL's own words, and what to do about it."""
    said = " ".join(str(error).split()) or type(error).__name__
    if isinstance(error, MemoryError):
        return f"out of host memory while {action} on {device}: lower --width/--height"
    name = status_name(error) if isinstance(error, cl.Error) else ""
    hint = (
        _OUT_OF_MEMORY_HINT
        if name in _OUT_OF_MEMORY
        else _DEVICE_LOST_HINT
        if name in _DEVICE_LOST
        else ("see `spectrace devices` for the device's state, or try another one with --device")
    )
    return f"OpenCL error while {action} on {device}: {said}; {hint}"


def translate_opencl_errors(action: str) -> Callable[[Method], Method]:
    """Decorate a method of an object with a `.device` (an opened Device): pyopencl errors and host memory
    exhaustion raised inside become SpectraceErrors saying `action` failed and what to do."""

    def decorate(method: Method) -> Method:
        @functools.wraps(method)
        def wrapper(self, *args, **kwargs):
            try:
                return method(self, *args, **kwargs)
            except (cl.Error, MemoryError) as error:
                report = getattr(getattr(self, "device", None), "report", None)
                device = report.key if report is not None else "the OpenCL device"
                raise SpectraceError(describe_opencl_error(error, action, device)) from None

        return wrapper  # type: ignore[return-value]

    return decorate
