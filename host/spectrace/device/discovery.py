"""Find every OpenCL runtime (ICD) on the machine and make pyopencl's loader see all of them.

pyopencl's wheel bundles its own ICD loader (ocl-icd). By default it reads only ``/etc/OpenCL/vendors``
(or the folder in ``OCL_ICD_VENDORS``) plus the PyPI PoCL beside itself, so a pip-installed Intel CPU
runtime stays invisible: its shipped ``.icd`` files name a path that does not exist. Before the first
platform query we therefore write one private folder of ``.icd`` files naming every library we found
by full path, and point ``OCL_ICD_VENDORS`` at it. The loader reads that variable once, lazily, at the
first OpenCL call, so this must run before anything enumerates platforms in this process.

The listing itself is read from the runtime libraries without pyopencl (icd_query.py), in the loader's order;
pyopencl's objects are made only for a device that is to be probed or used.
"""

from __future__ import annotations

import ctypes
import hashlib
import importlib.util
import os
import re
import site
import struct
import sys
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from spectrace.cache_folder import cache_root
from spectrace.device.icd_query import DeviceInfo, PlatformInfo, PlatformListing, library_platforms
from spectrace.errors import SpectraceError

if TYPE_CHECKING:  # pyopencl is imported only once the OpenCL environment is prepared, and only to use a device
    import pyopencl as cl

_DEFAULT_VENDORS_DIR = Path("/etc/OpenCL/vendors")
_INTEL_CPU_LIBRARY = "libintelocl.so"
_CONDA_BUILD_PLACEHOLDER = "/anaconda1anaconda2anaconda3/"

# Runtime slugs (the first part of a device key) and their labels for the runtimes we can tell apart.
POCL_SYSTEM = ("pocl-system", "PoCL (system)")
POCL_PYPI = ("pocl-pypi", "PoCL (PyPI)")
INTEL_CPU_PIP = ("intel-cpu", "Intel CPU runtime (pip)")
INTEL_CPU_SYSTEM = ("intel-cpu-system", "Intel CPU runtime (system)")


@dataclass(frozen=True)
class IcdLibrary:
    """One OpenCL runtime library as the ICD loader will dlopen it (a full path, or a soname)."""

    library: str
    found_in: str  # the .icd file or detection rule that named it, for diagnostics
    from_pip: bool  # installed by pip/PyPI (the PoCL beside pyopencl, or Intel's CPU runtime)


@dataclass(frozen=True)
class PreparedEnvironment:
    vendors_dir: Path
    libraries: tuple[IcdLibrary, ...]
    intel_preload_errors: tuple[str, ...]


_prepared: PreparedEnvironment | None = None
_preloaded_handles: list[ctypes.CDLL] = []  # kept alive: dropping a handle could unload a dependency


# ---------------------------------------------------------------------------------------------------------
# Gathering .icd entries


def _read_icd_file(icd_file: Path) -> str | None:
    try:
        text = icd_file.read_text(errors="replace").strip()
    except OSError:
        return None
    first_line = text.splitlines()[0].strip() if text else ""
    return first_line or None


def _icd_files_in(folder: Path) -> list[Path]:
    try:
        return sorted(p for p in folder.iterdir() if p.suffix == ".icd" and p.is_file())
    except OSError:
        return []


def pyopencl_dir() -> Path | None:
    """pyopencl's package folder, located without importing it (so nothing can touch the loader before we are done,
    and `spectrace devices` need not pay for the import)."""
    spec = importlib.util.find_spec("pyopencl")
    if spec is None or not spec.submodule_search_locations:
        return None
    return Path(list(spec.submodule_search_locations)[0])


def _pyopencl_libs_dir() -> Path | None:
    package = pyopencl_dir()
    libs = package / ".libs" if package else None
    return libs if libs and libs.is_dir() else None


def _entries_beside_pyopencl() -> list[IcdLibrary]:
    libs = _pyopencl_libs_dir()
    if libs is None:
        return []
    entries = []
    for icd_file in _icd_files_in(libs):
        name = _read_icd_file(icd_file)
        if name is None:
            continue
        # The bundled pocl.icd names its library by soname; the loader finds it only because it looks
        # beside itself. Our folder must name it by full path.
        if "/" not in name and (libs / name).is_file():
            name = str(libs / name)
        entries.append(IcdLibrary(name, str(icd_file), from_pip=True))
    return entries


def _python_lib_dirs() -> list[Path]:
    """``<prefix>/lib`` of this interpreter, its base, and of every site-packages on the path."""
    candidates = [Path(sys.prefix) / "lib", Path(sys.base_prefix) / "lib"]
    site_dirs = list(site.getsitepackages()) if hasattr(site, "getsitepackages") else []
    if site.ENABLE_USER_SITE:
        site_dirs.append(site.getusersitepackages())
    # <prefix>/lib/pythonX.Y/site-packages -> <prefix>/lib, where pip puts a wheel's data files.
    candidates += [Path(d).parent.parent for d in site_dirs]
    unique: list[Path] = []
    for folder in candidates:
        if folder not in unique:
            unique.append(folder)
    return unique


def pip_intel_cpu_libraries() -> list[Path]:
    """Intel's CPU runtime installed by pip (``intel-opencl-rt``): its ``.icd`` files are unusable, so we
    look for the library itself."""
    found: list[Path] = []
    for folder in _python_lib_dirs():
        library = folder / _INTEL_CPU_LIBRARY
        if library.is_file() and library.resolve() not in [f.resolve() for f in found]:
            found.append(library)
    return found


def _system_vendors_dir() -> Path:
    # ocl-icd lets OPENCL_VENDOR_PATH replace its hard-coded /etc/OpenCL/vendors.
    override = os.environ.get("OPENCL_VENDOR_PATH")
    return Path(override) if override else _DEFAULT_VENDORS_DIR


def _entries_in_vendors_dir(folder: Path, from_pip: bool = False) -> list[IcdLibrary]:
    entries = []
    for icd_file in _icd_files_in(folder):
        name = _read_icd_file(icd_file)
        if name is not None:
            entries.append(IcdLibrary(name, str(icd_file), from_pip))
    return entries


def _entries_from_environment() -> list[IcdLibrary]:
    value = os.environ.get("OCL_ICD_VENDORS", "").strip()
    if not value:
        return []
    path = Path(value)
    if path.is_dir():
        # A folder we wrote earlier (inherited by a child process) is gathered again like any other.
        return _entries_in_vendors_dir(path)
    if path.suffix == ".icd" and path.is_file():
        name = _read_icd_file(path)
        return [IcdLibrary(name, str(path), False)] if name else []
    # ocl-icd also accepts the name of a single library here.
    return [IcdLibrary(value, "OCL_ICD_VENDORS", False)]


def _library_identity(library: str) -> str:
    return os.path.realpath(library) if "/" in library else library


def gather_icd_libraries() -> list[IcdLibrary]:
    """Every runtime library the loader should open, without duplicates (pip-installed ones first)."""
    entries = _entries_beside_pyopencl()
    entries += [IcdLibrary(str(lib), "pip: intel-opencl-rt", True) for lib in pip_intel_cpu_libraries()]
    entries += _entries_in_vendors_dir(_system_vendors_dir())
    entries += _entries_from_environment()
    unique: dict[str, IcdLibrary] = {}
    for entry in entries:
        if _CONDA_BUILD_PLACEHOLDER in entry.library:
            continue  # Intel's pip-installed .icd files name their build machine's prefix
        unique.setdefault(_library_identity(entry.library), entry)
    return list(unique.values())


# ---------------------------------------------------------------------------------------------------------
# The private vendors folder


def _icd_file_name(index: int, library: str) -> str:
    stem = re.sub(r"[^A-Za-z0-9]+", "-", Path(library).name).strip("-") or "runtime"
    return f"{index:02d}-{stem}.icd"


def _vendors_dir_roots() -> Iterator[Path]:
    yield cache_root()
    import tempfile  # only when the cache folder will not do: a listing need not import it

    yield Path(tempfile.gettempdir()) / f"spectrace-{os.getuid()}"


def _write_vendors_dir(libraries: list[IcdLibrary]) -> Path:
    listing = "\n".join(entry.library for entry in libraries)
    digest = hashlib.sha256(listing.encode()).hexdigest()[:16]
    for root in _vendors_dir_roots():
        target = root / "icd" / digest
        if target.is_dir():
            return target  # content is fully determined by the digest
        import tempfile

        try:
            target.parent.mkdir(parents=True, exist_ok=True)
            staging = Path(tempfile.mkdtemp(prefix=f".{digest}-", dir=target.parent))
            for index, entry in enumerate(libraries):
                (staging / _icd_file_name(index, entry.library)).write_text(entry.library + "\n")
            try:
                staging.rename(target)  # atomic: a concurrent process sees no half-written folder
            except OSError:
                # Another process won the race with identical content.
                for leftover in staging.iterdir():
                    leftover.unlink()
                staging.rmdir()
            return target
        except OSError:
            continue  # cache folder not writable: fall back to the temporary folder
    raise OSError("no writable folder for the OpenCL vendors list")


# ---------------------------------------------------------------------------------------------------------
# Preloading the pip Intel runtime's dependencies


def elf_needed_libraries(library: Path) -> list[str]:
    """The DT_NEEDED entries of a 64-bit little-endian ELF shared library (empty if it is not one)."""
    try:
        data = library.read_bytes()
    except OSError:
        return []
    if data[:4] != b"\x7fELF" or data[4] != 2 or data[5] != 1:
        return []
    (section_offset,) = struct.unpack_from("<Q", data, 0x28)
    section_size, section_count = struct.unpack_from("<HH", data, 0x3A)
    sections = [
        struct.unpack_from("<IIQQQQIIQQ", data, section_offset + i * section_size) for i in range(section_count)
    ]
    dynamic_type = 6
    needed_tag = 1
    names: list[str] = []
    for _, kind, _, _, offset, size, link, _, _, entry_size in sections:
        if kind != dynamic_type or entry_size == 0:
            continue
        strings_offset = sections[link][4]
        for position in range(offset, offset + size, entry_size):
            tag, value = struct.unpack_from("<qQ", data, position)
            if tag == 0:
                break
            if tag == needed_tag:
                end = data.index(b"\0", strings_offset + value)
                names.append(data[strings_offset + value : end].decode())
    return names


def _local_dependency_order(library: Path) -> list[Path]:
    """Dependencies of `library` that live beside it (or beside the file a symlink names), each after
    its own dependencies."""
    folders = list(dict.fromkeys((library.parent, library.resolve().parent)))
    ordered: list[Path] = []
    visiting: set[str] = set()

    def visit(path: Path) -> None:
        for name in elf_needed_libraries(path):
            dependency = next((folder / name for folder in folders if (folder / name).is_file()), None)
            if name in visiting or dependency is None:
                continue
            visiting.add(name)
            visit(dependency)
            ordered.append(dependency)

    visit(library)
    return ordered


def preload_dependencies(library: Path) -> list[str]:
    """Make dlopen of `library` by the ICD loader succeed although ``LD_LIBRARY_PATH`` does not name its
    folder: if a plain load fails, load its neighbouring dependencies with RTLD_GLOBAL first. Returns the
    errors left (empty when `library` now loads)."""
    try:
        # Loaded privately, as the ICD loader will; the loader then reuses this handle.
        _preloaded_handles.append(ctypes.CDLL(str(library)))
        return []
    except OSError:
        pass  # e.g. a symlinked library whose $ORIGIN run path points to the wrong folder
    # Global only when needed: later libraries resolve names in these first (libimf defines libm's
    # names). The runtime itself stays private, or its cl* entry points would shadow the ICD loader's.
    pending = _local_dependency_order(library)
    for _ in range(3):  # later rounds catch an order the DT_NEEDED walk could not see
        still_pending = []
        for dependency in pending:
            try:
                _preloaded_handles.append(ctypes.CDLL(str(dependency), mode=ctypes.RTLD_GLOBAL))
            except OSError:
                still_pending.append(dependency)
        if len(still_pending) in (0, len(pending)):
            break
        pending = still_pending
    try:
        _preloaded_handles.append(ctypes.CDLL(str(library)))
    except OSError as error:
        return [str(error)]
    return []


# ---------------------------------------------------------------------------------------------------------
# Entry point


POCL_SPECIALISATION_VARIABLE = "POCL_WORK_GROUP_SPECIALIZATION"


def prepare_opencl_environment() -> PreparedEnvironment:
    """Expose every OpenCL runtime found through one ``OCL_ICD_VENDORS`` folder. Idempotent; call it
    before anything in this process asks OpenCL for its platforms."""
    global _prepared
    if _prepared is not None and os.environ.get("OCL_ICD_VENDORS") == str(_prepared.vendors_dir):
        return _prepared
    # PoCL compiles each kernel once for any work-group size (the build the program cache stores) and, unless told
    # not to, once more for each size, offset and grid class it is launched with: about 7 CPU-s more for a
    # path-tracing megakernel, for the same bits at the same speed (Cornell box 256x256, 4 spp, depth 8, groups of
    # 32, PoCL 3.1: 0.445-0.468 CPU-s a pass either way). A value the user set wins.
    os.environ.setdefault(POCL_SPECIALISATION_VARIABLE, "0")
    libraries = gather_icd_libraries()
    preload_errors: list[str] = []
    for entry in libraries:
        if entry.from_pip and entry.library.endswith(_INTEL_CPU_LIBRARY):
            preload_errors += preload_dependencies(Path(entry.library))
    try:
        vendors_dir = _write_vendors_dir(libraries)
    except OSError:
        # Without a folder the loader's defaults still apply; only the pip Intel runtime is lost.
        vendors_dir = Path(os.environ.get("OCL_ICD_VENDORS", str(_system_vendors_dir())))
    else:
        os.environ["OCL_ICD_VENDORS"] = str(vendors_dir)
    _prepared = PreparedEnvironment(vendors_dir, tuple(libraries), tuple(preload_errors))
    return _prepared


def runtime_identity(
    platform_name: str, vendor: str, library: str | None, has_cpu: bool, library_from_pip: bool
) -> tuple[str, str]:
    """(slug, label) telling the user which runtime a platform is, e.g. ("pocl-pypi", "PoCL (PyPI)")."""
    is_pip = library_from_pip or (library is not None and ("site-packages" in library or "dist-packages" in library))
    if "portable computing language" in platform_name.lower() or (library and "libpocl" in library):
        return POCL_PYPI if is_pip else POCL_SYSTEM
    if (library and _INTEL_CPU_LIBRARY in library) or (platform_name == "Intel(R) OpenCL" and has_cpu):
        return INTEL_CPU_PIP if is_pip else INTEL_CPU_SYSTEM
    vendor_words = re.findall(r"[a-z0-9]+", vendor.lower()) or re.findall(r"[a-z0-9]+", platform_name.lower())
    slug = "amd" if vendor_words[:3] == ["advanced", "micro", "devices"] else (vendor_words or ["opencl"])[0]
    return slug, platform_name.strip()


# ---------------------------------------------------------------------------------------------------------
# Enumerating platforms and devices


class DeviceNotListedError(SpectraceError):
    """pyopencl's loader does not list a device the runtime library offers (the vendors folder could not be written,
    so the loader sees fewer runtimes than the listing)."""


@dataclass(frozen=True, eq=False)
class FoundDevice:
    """One OpenCL device (or, with ``device`` None, a runtime that failed before offering one): what the runtime
    says about it, read without pyopencl; ``opencl_device()`` gives pyopencl's object when it is to be used."""

    key: str  # stable short id for the command line, e.g. "pocl-system:cpu:0"
    runtime: str  # label, e.g. "PoCL (system)"
    library: str | None  # the ICD library that provides it, when known
    platform: PlatformInfo | None
    device: DeviceInfo | None
    load_error: str | None = None

    def opencl_device(self) -> cl.Device:
        """pyopencl's Device for this device: the one its loader lists with the same handle."""
        if self.platform is None or self.device is None:
            raise DeviceNotListedError(f"{self.key} has no device ({self.load_error or 'none listed'})")
        return _opencl_device(self.key, self.platform.handle, self.device.handle)


_found_devices: list[FoundDevice] | None = None
_opencl_devices: dict[tuple[int, int], cl.Device] = {}


def _opencl_device(key: str, platform_handle: int, device_handle: int) -> cl.Device:
    if (platform_handle, device_handle) not in _opencl_devices:
        prepare_opencl_environment()
        import pyopencl as cl

        # Found in the loader's own listing rather than made from the number: the loader must have opened the
        # runtime (it does so at its first call), and a handle it does not list would not be safe to use.
        try:
            platforms = cl.get_platforms()
        except cl.Error:
            platforms = []  # no runtime at all: the loader reports PLATFORM_NOT_FOUND_KHR
        for platform in platforms:
            if platform.int_ptr == platform_handle:
                for device in platform.get_devices():
                    _opencl_devices.setdefault((platform_handle, device.int_ptr), device)
        if (platform_handle, device_handle) not in _opencl_devices:
            raise DeviceNotListedError(f"the OpenCL loader does not list {key}")
    return _opencl_devices[(platform_handle, device_handle)]


def device_kind(type_bits: int) -> str:
    """ "GPU", "CPU", "ACCELERATOR" or "OTHER" from a cl_device_type bit field."""
    for bit, name in ((1 << 2, "GPU"), (1 << 3, "ACCELERATOR"), (1 << 1, "CPU")):
        if type_bits & bit:
            return name
    return "OTHER"


def _unique_slug(slug: str, identity: tuple, owners: dict[str, tuple]) -> str:
    candidate, number = slug, 1
    while candidate in owners and owners[candidate] != identity:
        number += 1
        candidate = f"{slug}-{number}"
    owners[candidate] = identity
    return candidate


def _failed_library_device(entry: IcdLibrary, error: str, owners: dict[str, tuple]) -> FoundDevice:
    name = Path(entry.library).name
    slug, label = runtime_identity(name, "", entry.library, has_cpu=True, library_from_pip=entry.from_pip)
    if label == name:
        slug = re.split(r"[^a-z0-9]+", re.sub(r"^lib", "", name.lower()))[0] or "opencl"
    slug = _unique_slug(slug, ("failed", entry.library), owners)
    return FoundDevice(f"{slug}:none:0", label, entry.library, None, None, f"runtime did not load: {error}")


def _loader_order(prepared: PreparedEnvironment) -> list[IcdLibrary]:
    """The libraries in the order the ICD loader opens them: its vendors folder as the directory lists it (ocl-icd
    reads it with readdir, unsorted), then any it does not name."""
    by_identity = {_library_identity(entry.library): entry for entry in prepared.libraries}
    ordered: list[IcdLibrary] = []
    try:
        names = os.listdir(prepared.vendors_dir)
    except OSError:
        names = []
    for name in names:
        library = _read_icd_file(prepared.vendors_dir / name) if name.endswith(".icd") else None
        entry = by_identity.get(_library_identity(library)) if library else None
        if entry is not None and entry not in ordered:
            ordered.append(entry)
    return ordered + [entry for entry in prepared.libraries if entry not in ordered]


def _device_counts(listing: PlatformListing) -> tuple[int, int, int]:
    """ocl-icd's platform order: most GPUs first, then most CPUs, then most devices (a stable sort)."""
    bits = [device.type_bits or 0 for device in listing.devices]
    gpus = sum(1 for b in bits if b & (1 << 2))
    cpus = sum(1 for b in bits if b & (1 << 1))
    return -gpus, -cpus, -len(bits)


def _enumerate_devices(prepared: PreparedEnvironment) -> list[FoundDevice]:
    listings: list[tuple[IcdLibrary, PlatformListing]] = []
    failed: list[tuple[IcdLibrary, str]] = []
    for entry in _loader_order(prepared):
        result = library_platforms(entry.library)
        if isinstance(result, str):
            failed.append((entry, result))
        else:
            listings += [(entry, listing) for listing in result]
    listings.sort(key=lambda pair: _device_counts(pair[1]))

    found: list[FoundDevice] = []
    seen_handles: set[int] = set()
    seen_identities: set[tuple] = set()
    slug_owners: dict[str, tuple] = {}
    for owner, listing in listings:
        platform, devices = listing.platform, listing.devices
        # A library named twice (by path and by soname) gives the same platform twice.
        if platform.handle in seen_handles:
            continue
        seen_handles.add(platform.handle)
        identity = (platform.name, platform.version, tuple((d.name, d.driver_version) for d in devices))
        if identity in seen_identities:
            continue  # the same runtime installed twice: one copy is enough
        seen_identities.add(identity)
        has_cpu = any(device_kind(d.type_bits or 0) == "CPU" for d in devices)
        slug, label = runtime_identity(platform.name, platform.vendor, owner.library, has_cpu, owner.from_pip)
        slug = _unique_slug(slug, identity, slug_owners)
        if not devices:
            reason = listing.error or "platform offers no devices"
            found.append(FoundDevice(f"{slug}:none:0", label, owner.library, platform, None, reason))
        counters: dict[str, int] = {}
        for device in devices:
            kind = device_kind(device.type_bits or 0).lower()
            index = counters[kind] = counters.get(kind, -1) + 1
            found.append(FoundDevice(f"{slug}:{kind}:{index}", label, owner.library, platform, device))
    found += [_failed_library_device(entry, error, slug_owners) for entry, error in failed]
    return found


def find_devices() -> list[FoundDevice]:
    """Every device of every runtime, de-duplicated, in the loader's order (enumerated once per process)."""
    global _found_devices
    if _found_devices is None:
        _found_devices = _enumerate_devices(prepare_opencl_environment())
    return list(_found_devices)
