"""OpenCL devices: find every runtime, probe each device, pick one, build cached programs on it.

Call ``prepare_opencl_environment()`` (every function here does) before anything else in the process
asks OpenCL for its platforms: it decides which runtimes the loader can see.
"""

from spectrace.device.discovery import prepare_opencl_environment
from spectrace.device.program_cache import Device
from spectrace.device.report import DeviceReport, device_table
from spectrace.device.selection import NoWorkingDeviceError, discover_devices, open_device

__all__ = [
    "prepare_opencl_environment",
    "discover_devices",
    "open_device",
    "Device",
    "DeviceReport",
    "NoWorkingDeviceError",
    "device_table",
]
