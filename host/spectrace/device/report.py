"""What `spectrace devices` shows about each OpenCL device: identity, capacity and probe result."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

from spectrace.device.discovery import FoundDevice, device_kind
from spectrace.device.icd_query import DeviceInfo

if TYPE_CHECKING:  # rich is imported only to draw the table: `spectrace devices --json` does without it
    from rich.table import Table


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


def device_table(reports: list[DeviceReport]) -> Table:
    """One row per device: key, runtime, device, type, OpenCL version, probe result or failure reason."""
    from rich.table import Table
    from rich.text import Text

    table = Table(title="OpenCL devices")
    for column in ("Key", "Runtime", "Device", "Type", "OpenCL", "Probe"):
        table.add_column(column, overflow="fold")
    for report in reports:
        probe = Text("ok", style="green") if report.ok else Text(f"failed: {report.reason}", style="red")
        # Text, not markup: device names and compiler messages may contain square brackets.
        table.add_row(
            Text(report.key),
            Text(report.runtime),
            Text(report.device_name),
            Text(report.device_type),
            Text(_short_opencl_version(report.opencl_version)),
            probe,
        )
    return table
