"""OpenCL devices: find every runtime, probe each device, pick one, build cached programs on it.

Call ``prepare_opencl_environment()`` (every function here does) before anything else in the process
asks OpenCL for its platforms: it decides which runtimes the loader can see.

Listing devices needs neither numpy nor pyopencl; ``Device`` (an opened device, pyopencl's context and queue) loads
them on first use.
"""

from typing import TYPE_CHECKING

from spectrace.device.discovery import prepare_opencl_environment
from spectrace.device.report import DeviceReport, device_table
from spectrace.device.selection import NoWorkingDeviceError, discover_devices, open_device
from spectrace.lazy_names import lazy_names

if TYPE_CHECKING:
    from spectrace.device.program_cache import Device

__getattr__, __dir__ = lazy_names(__name__, {"Device": "spectrace.device.program_cache"})

__all__ = [
    "prepare_opencl_environment",
    "discover_devices",
    "open_device",
    "Device",
    "DeviceReport",
    "NoWorkingDeviceError",
    "device_table",
]
