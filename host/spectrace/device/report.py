"""What `spectrace devices` shows about each OpenCL device: identity, capacity and probe result."""

from __future__ import annotations

from dataclasses import dataclass

from spectrace.device.discovery import FoundDevice, device_kind
from spectrace.device.icd_query import DeviceInfo


@dataclass(frozen=True)
class DeviceReport:
    key: str  # e.g. "pocl-system:cpu:0"; accepted by --device and SPECTRACE_DEVICE
    runtime: str  # e.g. "PoCL (PyPI)", "Intel CPU runtime (pip)", or a GPU vendor's platform name
    platform_name: str
    platform_version: str
    device_name: str
    device_type: str  # "CPU", "GPU", "ACCELERATOR", "OTHER", or "NONE" for a runtime without a device
    driver_version: str
    compute_units: int
    global_mem_bytes: int
    ok: bool
    reason: str | None  # why the probe failed; None when ok
    opencl_version: str = ""  # the device's "OpenCL X.Y ..." string
    library: str | None = None  # the ICD library that provides the device, when known


def _text(value: str | None, fallback: str) -> str:
    # A broken runtime may fail even on info queries (None); the report must still be shown.
    return fallback if value is None else value.strip()


def _device_type(device: DeviceInfo | None) -> str:
    if device is None:
        return "NONE"
    return "OTHER" if device.type_bits is None else device_kind(device.type_bits)


def describe_device(found: FoundDevice, ok: bool, reason: str | None) -> DeviceReport:
    platform, device = found.platform, found.device
    return DeviceReport(
        key=found.key,
        runtime=found.runtime,
        platform_name=platform.name.strip() if platform else "",
        platform_version=platform.version.strip() if platform else "",
        device_name=_text(device.name, "?") if device else "(none)",
        device_type=_device_type(device),
        driver_version=_text(device.driver_version, "") if device else "",
        compute_units=(device.max_compute_units or 0) if device else 0,
        global_mem_bytes=(device.global_mem_size or 0) if device else 0,
        ok=ok,
        reason=None if ok else (reason or "unknown failure"),
        opencl_version=_text(device.version, "") if device else "",
        library=found.library,
    )


def _short_opencl_version(version: str) -> str:
    # "OpenCL 3.0 PoCL 3.1+debian ..." -> "3.0"
    words = version.split()
    return words[1] if len(words) > 1 and words[0] == "OpenCL" else version


def device_table(reports: list[DeviceReport], colour: bool = False) -> str:
    """One row per device: key, runtime, device, type, OpenCL version, probe result or failure reason, as plain
    aligned columns (the last, a failure's reason, as long as it is). Drawn without rich, whose import would cost
    `spectrace devices` a sixth of its run. colour: the probe result green or red (ANSI), for a terminal."""
    header = ("Key", "Runtime", "Device", "Type", "OpenCL", "Probe")
    rows = [
        (
            r.key,
            r.runtime,
            r.device_name,
            r.device_type,
            _short_opencl_version(r.opencl_version),
            "ok" if r.ok else f"failed: {r.reason}",
        )
        for r in reports
    ]
    widths = [max(len(row[i]) for row in [header, *rows]) for i in range(len(header) - 1)]

    def line(row: tuple[str, ...], ok: bool | None = None) -> str:
        probe = row[-1]
        if colour and ok is not None:
            probe = f"\x1b[{32 if ok else 31}m{probe}\x1b[0m"
        return "  ".join(cell.ljust(width) for cell, width in zip(row, widths)) + "  " + probe

    return "\n".join([line(header), *(line(row, r.ok) for row, r in zip(rows, reports))])
