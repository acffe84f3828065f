"""Pick the OpenCL device a render runs on.

Order: an explicit spec (``--device``), else ``SPECTRACE_DEVICE``, else a working GPU, else the working
CPU runtime known fastest. Intel's CPU runtime measured about 15x faster than PoCL on a toy kernel;
the system PoCL comes before the PyPI one because it is built for this CPU (the PyPI build may target a
generic CPU, or none). Only devices that pass the probe are ever chosen.
"""

from __future__ import annotations

import dataclasses
import os
from typing import TYPE_CHECKING

from spectrace.device import probe as probing
from spectrace.device.discovery import (
    INTEL_CPU_PIP,
    INTEL_CPU_SYSTEM,
    POCL_PYPI,
    POCL_SYSTEM,
    DeviceNotListedError,
    FoundDevice,
    find_devices,
)
from spectrace.device.report import DeviceReport, describe_device
from spectrace.errors import SpectraceError

if TYPE_CHECKING:  # pyopencl is imported only when a device is opened, not to list them
    from spectrace.device.program_cache import Device

DEVICE_ENV = "SPECTRACE_DEVICE"

INSTALL_HINT = (
    'install a runtime: pip install "spectrace[cpu]" (Intel\'s CPU runtime via pip), '
    "or as root apt-get install -y pocl-opencl-icd (Debian/Ubuntu PoCL), "
    "or your GPU vendor's OpenCL driver; run `spectrace devices` to see why each one failed"
)

_TYPE_RANK = {"GPU": 0, "CPU": 1, "ACCELERATOR": 2}
_CPU_RUNTIME_RANK = {INTEL_CPU_PIP[1]: 0, INTEL_CPU_SYSTEM[1]: 1, POCL_SYSTEM[1]: 2, POCL_PYPI[1]: 3}


class NoWorkingDeviceError(SpectraceError):
    """No OpenCL device matches the request and passes the probe; the message says what to do.

    Given the probed reports instead of a message, it writes the standard one: each failure, then what
    to install.
    """

    def __init__(self, message: str | list[DeviceReport], where: str | None = None):
        if not isinstance(message, str):
            message = _nothing_works_message([r for r in message if not r.ok])
        super().__init__(message, where=where)


def _nothing_works_message(failures: list[DeviceReport]) -> str:
    if not failures:
        return f"no OpenCL runtime found; {INSTALL_HINT}"
    return f"no working OpenCL device ({_failure_list(failures)}); {INSTALL_HINT}"


def preference_rank(report: DeviceReport) -> tuple[int, int]:
    """Smaller is preferred: GPUs (vendor runtimes before PoCL), then CPU runtimes fastest first."""
    type_rank = _TYPE_RANK.get(report.device_type, 3)
    is_pocl = report.runtime in (POCL_SYSTEM[1], POCL_PYPI[1])
    runtime_rank = int(is_pocl) if report.device_type == "GPU" else _CPU_RUNTIME_RANK.get(report.runtime, 4)
    return type_rank, runtime_rank


def matches_spec(spec: str, report: DeviceReport) -> bool:
    """Case-insensitive substring of the key, runtime label, platform or device name."""
    needle = spec.strip().lower()
    fields = (report.key, report.runtime, report.platform_name, report.device_name)
    return any(needle in field.lower() for field in fields)


def _unprobed_report(found: FoundDevice) -> DeviceReport:
    return describe_device(found, ok=found.device is not None, reason=found.load_error)


def _probed_report(found: FoundDevice) -> DeviceReport:
    result = probing.probe(found)
    return describe_device(found, ok=result.ok, reason=result.reason)


def _in_preference_order(found: list[FoundDevice]) -> list[tuple[FoundDevice, DeviceReport]]:
    pairs = [(f, _unprobed_report(f)) for f in found]
    # sorted() is stable: equal ranks keep the loader's order.
    return sorted(pairs, key=lambda pair: preference_rank(pair[1]))


def discover_devices() -> list[DeviceReport]:
    """Every device of every runtime, probed, in the order open_device() would prefer them."""
    return [_probed_report(found) for found, _ in _in_preference_order(find_devices())]


def _failure_list(reports: list[DeviceReport]) -> str:
    return "; ".join(f"{r.key} ({r.reason})" for r in reports)


def _select_candidates(
    spec: str, ordered: list[tuple[FoundDevice, DeviceReport]], request: str
) -> list[tuple[FoundDevice, DeviceReport]]:
    exact = [pair for pair in ordered if pair[1].key.lower() == spec.strip().lower()]
    chosen = exact or [pair for pair in ordered if matches_spec(spec, pair[1])]
    if not chosen:
        keys = ", ".join(report.key for _, report in ordered) or f"none; {INSTALL_HINT}"
        raise NoWorkingDeviceError(
            f"no OpenCL device matches {request}; available devices: {keys} "
            f"(pick one with --device KEY or {DEVICE_ENV}=KEY; `spectrace devices` shows each)"
        )
    return chosen


def _open_first_working(candidates: list[tuple[FoundDevice, DeviceReport]]) -> tuple[Device | None, list]:
    from spectrace.device.program_cache import Device

    failures: list[DeviceReport] = []
    for found, _ in candidates:
        report = _probed_report(found)
        if report.ok and found.device is not None:
            try:
                return Device(report, found.opencl_device()), failures
            except DeviceNotListedError as error:  # a remembered probe answer, but the loader cannot reach it
                report = dataclasses.replace(report, ok=False, reason=str(error))
        failures.append(report)
    return None, failures


def open_device(spec: str | None = None) -> Device:
    """Open the device `spec` names (exact key, or a substring of key/runtime/platform/device name), else
    the one ``SPECTRACE_DEVICE`` names, else the preferred working device."""
    request = f"'{spec}'"
    if not spec:
        spec = os.environ.get(DEVICE_ENV, "").strip() or None
        request = f"{DEVICE_ENV}='{spec}'"
    ordered = _in_preference_order(find_devices())
    candidates = _select_candidates(spec, ordered, request) if spec else ordered
    device, failures = _open_first_working(candidates)
    if device is not None:
        return device
    if spec:
        failed = {report.key for report in failures}
        working = [f.key for f, _ in ordered if f.key not in failed and probing.probe(f).ok]
        raise NoWorkingDeviceError(
            f"no working OpenCL device matches {request}: {_failure_list(failures)}; "
            f"working devices: {', '.join(working) or 'none'}"
        )
    raise NoWorkingDeviceError(failures)
