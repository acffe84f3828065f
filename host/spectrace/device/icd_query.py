"""Platforms and devices read from each OpenCL runtime library through ctypes, without pyopencl.

Importing numpy and pyopencl takes about a third of a second, which `spectrace devices` would otherwise pay for a
listing. The ICD loader itself needs nothing but the runtime: every object a runtime hands out starts with a pointer
to its dispatch table (cl_khr_icd), whose first entries are clGetPlatformIDs, clGetPlatformInfo, clGetDeviceIDs and
clGetDeviceInfo (the Khronos ``cl_icd.h`` layout), and the loader calls through that table. We do the same. A
runtime with loader-managed dispatch (cl_khr_icd 2) keeps a tag in the first entry instead and hands out its
functions through ``clIcdGetFunctionAddressForPlatformKHR``.

The checks the loader (ocl-icd) makes before it lists a runtime's platforms are made here too, so this listing and
pyopencl's hold the same platforms.
"""

from __future__ import annotations

import ctypes
import os
from dataclasses import dataclass
from typing import Any

_POINTER_SIZE = ctypes.sizeof(ctypes.c_void_p)
_ICD2_TAG = 0x4F50454E434C3331 if _POINTER_SIZE == 8 else 0x434C3331  # "OPENCL31"

# cl.h / cl_ext.h
_SUCCESS = 0
_DEVICE_NOT_FOUND = -1
_DEVICE_TYPE_ALL = 0xFFFFFFFF
_PLATFORM_VERSION, _PLATFORM_NAME, _PLATFORM_VENDOR, _PLATFORM_EXTENSIONS = 0x0901, 0x0902, 0x0903, 0x0904
_PLATFORM_ICD_SUFFIX_KHR = 0x0920
_DEVICE_TYPE, _DEVICE_MAX_COMPUTE_UNITS, _DEVICE_GLOBAL_MEM_SIZE = 0x1000, 0x1002, 0x101F
_DEVICE_NAME, _DEVICE_DRIVER_VERSION, _DEVICE_VERSION = 0x102B, 0x102D, 0x102F

# The status names pyopencl writes into its messages ("clGetDeviceIDs failed: INVALID_PLATFORM").
_STATUS_NAMES = {
    -1: "DEVICE_NOT_FOUND",
    -2: "DEVICE_NOT_AVAILABLE",
    -5: "OUT_OF_RESOURCES",
    -6: "OUT_OF_HOST_MEMORY",
    -30: "INVALID_VALUE",
    -31: "INVALID_DEVICE_TYPE",
    -32: "INVALID_PLATFORM",
    -33: "INVALID_DEVICE",
    -1001: "PLATFORM_NOT_FOUND_KHR",
}

_PlatformIdsFunction = ctypes.CFUNCTYPE(
    ctypes.c_int32, ctypes.c_uint32, ctypes.POINTER(ctypes.c_void_p), ctypes.POINTER(ctypes.c_uint32)
)
_InfoFunction = ctypes.CFUNCTYPE(
    ctypes.c_int32, ctypes.c_void_p, ctypes.c_uint32, ctypes.c_size_t, ctypes.c_void_p, ctypes.POINTER(ctypes.c_size_t)
)
_DeviceIdsFunction = ctypes.CFUNCTYPE(
    ctypes.c_int32,
    ctypes.c_void_p,
    ctypes.c_uint64,
    ctypes.c_uint32,
    ctypes.POINTER(ctypes.c_void_p),
    ctypes.POINTER(ctypes.c_uint32),
)
_PlatformFunctionAddress = ctypes.CFUNCTYPE(ctypes.c_void_p, ctypes.c_void_p, ctypes.c_char_p)


@dataclass(frozen=True)
class PlatformInfo:
    handle: int  # the cl_platform_id, the same number pyopencl's Platform.int_ptr gives
    name: str
    vendor: str
    version: str


@dataclass(frozen=True)
class DeviceInfo:
    """A device's identity and capacity; None where the runtime would not answer."""

    handle: int  # the cl_device_id, as pyopencl's Device.int_ptr
    name: str | None
    type_bits: int | None  # cl_device_type
    version: str | None
    driver_version: str | None
    max_compute_units: int | None
    global_mem_size: int | None


@dataclass(frozen=True)
class PlatformListing:
    platform: PlatformInfo
    devices: tuple[DeviceInfo, ...]
    error: str | None = None  # why its devices could not be listed, in pyopencl's words


@dataclass(frozen=True)
class _Functions:
    """The entry points a platform's objects dispatch to (ctypes function objects)."""

    platform_info: Any
    device_ids: Any
    device_info: Any


def _status_name(status: int) -> str:
    return _STATUS_NAMES.get(status, str(status))


def _exported(runtime: ctypes.CDLL, name: str) -> int | None:
    try:
        return ctypes.cast(getattr(runtime, name), ctypes.c_void_p).value
    except AttributeError:
        return None


def _extension_function(lookup, runtime: ctypes.CDLL, name: str) -> int | None:
    """As the loader finds a function: through clGetExtensionFunctionAddress, else the exported symbol."""
    address = lookup(name.encode())
    return address or _exported(runtime, name)


def _dispatch_functions(handle: int, runtime: ctypes.CDLL, lookup) -> _Functions | None:
    table = ctypes.c_void_p.from_address(handle).value
    if not table:
        return None
    entries = [ctypes.c_void_p.from_address(table + i * _POINTER_SIZE).value or 0 for i in range(4)]
    if entries[0] == _ICD2_TAG:
        resolver = _extension_function(lookup, runtime, "clIcdGetFunctionAddressForPlatformKHR")
        if not resolver:
            return None
        resolve = _PlatformFunctionAddress(resolver)
        names = (b"clGetPlatformInfo", b"clGetDeviceIDs", b"clGetDeviceInfo")
        entries = [0, *(resolve(handle, name) or 0 for name in names)]
    if not all(entries[1:]):
        return None
    return _Functions(_InfoFunction(entries[1]), _DeviceIdsFunction(entries[2]), _InfoFunction(entries[3]))


def _info_bytes(function, handle: int, name: int) -> bytes | None:
    size = ctypes.c_size_t(0)
    if function(handle, name, 0, None, ctypes.byref(size)) != _SUCCESS:
        return None
    buffer = ctypes.create_string_buffer(max(size.value, 1))
    if function(handle, name, size.value, buffer, None) != _SUCCESS:
        return None
    return buffer.raw[: size.value]


def _info_text(function, handle: int, name: int) -> str | None:
    value = _info_bytes(function, handle, name)
    # pyopencl keeps all but the last byte, the terminating NUL.
    return None if value is None else value[:-1].decode(errors="replace")


def _info_number(function, handle: int, name: int, kind) -> int | None:
    value = kind(0)
    if function(handle, name, ctypes.sizeof(value), ctypes.byref(value), None) != _SUCCESS:
        return None
    return int(value.value)


def _device(functions: _Functions, handle: int) -> DeviceInfo:
    read = functions.device_info
    return DeviceInfo(
        handle=handle,
        name=_info_text(read, handle, _DEVICE_NAME),
        type_bits=_info_number(read, handle, _DEVICE_TYPE, ctypes.c_uint64),
        version=_info_text(read, handle, _DEVICE_VERSION),
        driver_version=_info_text(read, handle, _DEVICE_DRIVER_VERSION),
        max_compute_units=_info_number(read, handle, _DEVICE_MAX_COMPUTE_UNITS, ctypes.c_uint32),
        global_mem_size=_info_number(read, handle, _DEVICE_GLOBAL_MEM_SIZE, ctypes.c_uint64),
    )


def _devices(functions: _Functions, platform: int) -> tuple[tuple[DeviceInfo, ...], str | None]:
    count = ctypes.c_uint32(0)
    status = functions.device_ids(platform, _DEVICE_TYPE_ALL, 0, None, ctypes.byref(count))
    if status == _DEVICE_NOT_FOUND or (status == _SUCCESS and count.value == 0):
        return (), None
    if status != _SUCCESS:
        return (), f"clGetDeviceIDs failed: {_status_name(status)}"
    handles = (ctypes.c_void_p * count.value)()
    status = functions.device_ids(platform, _DEVICE_TYPE_ALL, count.value, handles, None)
    if status != _SUCCESS:
        return (), f"clGetDeviceIDs failed: {_status_name(status)}"
    return tuple(_device(functions, int(h)) for h in handles if h), None


def _listed_by_the_loader(functions: _Functions, handle: int, assume_icd: bool) -> bool:
    # ocl-icd drops a platform that does not name cl_khr_icd or has no function-name suffix.
    if not assume_icd:
        extensions = _info_bytes(functions.platform_info, handle, _PLATFORM_EXTENSIONS)
        if extensions is None or b"cl_khr_icd" not in extensions:
            return False
    return _info_bytes(functions.platform_info, handle, _PLATFORM_ICD_SUFFIX_KHR) is not None


def library_platforms(library: str) -> list[PlatformListing] | str:
    """The platforms `library` offers the ICD loader, with their devices, or why it cannot be loaded. The library is
    opened as the loader opens it (the same instance, so the handles are the ones pyopencl sees)."""
    try:
        runtime = ctypes.CDLL(library)
    except OSError as error:
        return str(error)
    lookup_address = _exported(runtime, "clGetExtensionFunctionAddress")
    if not lookup_address:
        return []  # the loader skips such a library
    lookup = ctypes.CFUNCTYPE(ctypes.c_void_p, ctypes.c_char_p)(lookup_address)
    query_address = _extension_function(lookup, runtime, "clIcdGetPlatformIDsKHR")
    assume_icd = bool(os.environ.get("OCL_ICD_ASSUME_ICD_EXTENSION"))
    if not query_address or not (assume_icd or _extension_function(lookup, runtime, "clGetPlatformInfo")):
        return []
    query = _PlatformIdsFunction(query_address)
    count = ctypes.c_uint32(0)
    if query(0, None, ctypes.byref(count)) != _SUCCESS or count.value == 0:
        return []
    handles = (ctypes.c_void_p * count.value)()
    if query(count.value, handles, None) != _SUCCESS:
        return []
    listings = []
    for handle in (int(h) for h in handles if h):
        functions = _dispatch_functions(handle, runtime, lookup)
        if functions is None or not _listed_by_the_loader(functions, handle, assume_icd):
            continue
        platform = PlatformInfo(
            handle,
            _info_text(functions.platform_info, handle, _PLATFORM_NAME) or "",
            _info_text(functions.platform_info, handle, _PLATFORM_VENDOR) or "",
            _info_text(functions.platform_info, handle, _PLATFORM_VERSION) or "",
        )
        devices, listing_error = _devices(functions, handle)
        listings.append(PlatformListing(platform, devices, listing_error))
    return listings
