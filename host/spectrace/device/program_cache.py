"""An opened OpenCL device and its kernel builds, with an on-disk cache of program binaries.

A binary is reused only when everything that could change it is unchanged: every ``*.cl``/``*.h`` file
in the kernels folder and every header generated from the host's registries (handed to a build as
`GeneratedSources`: this layer does not read the registries), the entry file,
the build options (defines included) and the device's identity (platform name and version, device name, driver
version). pyopencl's own cache is bypassed so that only this one decides.

The key names the kernels by their content, not by where they lie: the ``-I`` folders the compiler is given are left
out of it, so a fresh clone, a wheel's copy or a second worktree with the same sources reuses the binaries already
built (the binaries carry no path: builds are without debug information). A cached file carries the digest of its
binary, so a damaged entry is rebuilt without ever reaching the runtime's loader. Within a process, the devices opened
on one OpenCL device share a context and the programs already built in it.
"""

from __future__ import annotations

import contextlib
import hashlib
import math
import os
import re
import tempfile
import threading
import time
import warnings
from collections import OrderedDict
from collections.abc import Iterator, Mapping
from pathlib import Path
from typing import TYPE_CHECKING, cast

import pyopencl as cl

from spectrace import resources
from spectrace.device.builtin_inlining import runtime_defines, source_prelude
from spectrace.device.discovery import cache_root
from spectrace.device.report import DeviceReport
from spectrace.errors import SpectraceError

if TYPE_CHECKING:
    from spectrace.core.contract import GeneratedSources

try:
    import fcntl
except ImportError:  # Windows: no flock; processes building one program at once then both build it
    fcntl = None  # type: ignore[assignment]

_CACHE_FORMAT = b"spectrace-program-cache-v2"
_BASE_OPTIONS = ("-cl-std=CL1.2",)  # no -cl-fast-relaxed-math: the kernels rely on IEEE inf/nan
_LOG_LINES = 40
_DEFINE_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")
# Names a file to which each build from source appends one line (seconds, entry, its own defines): what a test run
# built and what that cost, to find the programs that differ by a define alone.
BUILD_LOG_VARIABLE = "SPECTRACE_BUILD_LOG"
# Set to 1: kernels are declared without vec_type_hint (kernels/kernel_entry.h), so a compiler may vectorise them
# across work-items. A define, so such builds have cache keys of their own.
VECTORISE_VARIABLE = "SPECTRACE_VECTORISE_ACROSS_ITEMS"

DefineValue = int | float | str

# Programs a process keeps built, most recently used last: loading even a cached binary costs the runtime tens of
# milliseconds (PoCL: ~60 ms for the path program), and one process renders the same program many times (a session's
# edits, a sweep, a test run). Bounded, because a long session that respecialises its kernels makes new ones.
_PROGRAMS_KEPT = 32


class _SharedContext:
    """The one OpenCL context a process opens on a device, and the programs built in it: every `Device` opened on
    that device shares them (each with a queue of its own), so a program built for one is built for all."""

    def __init__(self, cl_device: cl.Device):
        self.context = cl.Context([cl_device])
        self.programs: OrderedDict[str, cl.Program] = OrderedDict()
        self.lock = threading.Lock()

    def kept(self, key: str) -> cl.Program | None:
        with self.lock:
            program = self.programs.get(key)
            if program is not None:
                self.programs.move_to_end(key)
            return program

    def keep(self, key: str, program: cl.Program) -> None:
        with self.lock:
            self.programs[key] = program
            self.programs.move_to_end(key)
            while len(self.programs) > _PROGRAMS_KEPT:
                self.programs.popitem(last=False)


# Keyed by process too: a forked child must not use its parent's context.
_SHARED: dict[tuple[int, int], _SharedContext] = {}
_SHARED_LOCK = threading.Lock()


def _shared_context(cl_device: cl.Device) -> _SharedContext:
    key = (os.getpid(), cl_device.int_ptr)
    with _SHARED_LOCK:
        shared = _SHARED.get(key)
        if shared is None:
            shared = _SHARED[key] = _SharedContext(cl_device)
        return shared


class KernelBuildError(SpectraceError):
    """The OpenCL compiler rejected a program; ``build_log`` holds its first lines."""

    def __init__(self, message: str, build_log: str, where: str | None = None):
        self.build_log = build_log
        super().__init__(message, where=where)


def first_error_line(log: str) -> str | None:
    """The compiler's first error, without its location prefix: "unknown target CPU 'generic'"."""
    lines = [line.strip() for line in log.splitlines() if line.strip()]
    for line in lines:
        match = re.search(r"error:\s*(.*)", line, flags=re.IGNORECASE)
        if match and match.group(1):
            return match.group(1)[:200]
    return lines[0][:200] if lines else None


def compiler_log(program, device) -> str:
    """What the compiler said while building `program` for `device` (warnings included)."""
    try:
        return str(program.get_build_info(device, cl.program_build_info.LOG)).strip()
    except cl.Error:
        return ""


def _build_quietly(program, device, options: str) -> None:
    # pyopencl warns on any compiler output ("Compilation started", ...); callers read the log instead.
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", cl.CompilerWarning)
        program.build(options.encode(), [device])


def compile_source(context, device, source: str, options: str) -> cl.Program:
    """Build `source` for one device; raises KernelBuildError with the compiler's log."""
    # The low-level program object builds without pyopencl's cache and without its extra include path.
    program = cl._cl._Program(context, source)  # noqa: SLF001
    try:
        _build_quietly(program, device, options)
    except cl.Error as error:
        log = compiler_log(program, device) or str(error)
        raise KernelBuildError(first_error_line(log) or "build failed", log) from None
    return cl.Program(program)


def _load_binary(context, device, binary: bytes, options: str) -> cl.Program | None:
    try:
        program = cl._cl._Program(context, [device], [binary])  # noqa: SLF001
        _build_quietly(program, device, options)
    except cl.Error:
        return None  # stale or foreign binary: rebuild from source
    return cl.Program(program)


def kernels_digest(kernels_dir: Path) -> str:
    """Hash of every ``*.cl`` and ``*.h`` file under `kernels_dir` (names and contents)."""
    return files_digest(kernels_dir, (".cl", ".h"))


# Each folder's last digest, with the listing (names, sizes, times, inodes) it was made from.
_DIGESTS: dict[tuple[Path, tuple[str, ...]], tuple[tuple, str]] = {}


def files_digest(folder: Path, suffixes: tuple[str, ...]) -> str:
    """Hash of every file under `folder` whose name ends in one of `suffixes` (relative names and contents)."""
    # Every build asks (~7 ms to read and hash the kernels): the files are read again only when one of them was
    # written, added, removed or replaced since, as far as their sizes, times and inodes tell.
    stats = tuple(sorted(_listing(folder, suffixes)))
    known = _DIGESTS.get((folder, suffixes))
    if known is not None and known[0] == stats:
        return known[1]
    digest = hashlib.sha256()
    for path in sorted(folder / name for name, _ in stats):  # in path order, as the digest always was
        content = path.read_bytes()
        digest.update(path.relative_to(folder).as_posix().encode() + b"\0")
        digest.update(len(content).to_bytes(8, "little") + content)
    _DIGESTS[(folder, suffixes)] = (stats, digest.hexdigest())
    return digest.hexdigest()


def _listing(folder: Path, suffixes: tuple[str, ...], prefix: str = "") -> Iterator[tuple[str, tuple[int, ...]]]:
    """(name relative to `folder`, size, times and inode) of each file under it whose name ends in one of
    `suffixes`: one stat per file, where a path walk takes three."""
    with os.scandir(folder) as entries:
        for entry in entries:
            if entry.is_dir(follow_symlinks=False):
                yield from _listing(Path(entry.path), suffixes, f"{prefix}{entry.name}/")
            elif entry.name.endswith(suffixes) and entry.is_file():
                status = entry.stat()
                yield f"{prefix}{entry.name}", (status.st_size, status.st_mtime_ns, status.st_ctime_ns, status.st_ino)


def _define_value(name: str, value: DefineValue) -> str:
    if isinstance(value, (bool, int)):
        return str(int(value))
    if isinstance(value, float):
        if not math.isfinite(value):
            raise SpectraceError(f"kernel define {name}={value} is not a finite number")
        return f"{value!r}f"  # a float literal: double literals need fp64 in OpenCL C 1.2
    if isinstance(value, str) and value and not any(c.isspace() for c in value):
        return value
    raise SpectraceError(f"kernel define {name}={value!r} must be an int, a float or a string without spaces")


def _include_option(folder: Path) -> list[str]:
    text = str(folder)
    return ["-I", f'"{text}"' if any(c.isspace() for c in text) else text]


def _define_options(defines: Mapping[str, DefineValue] | None) -> list[str]:
    options: list[str] = []
    for name, value in sorted((defines or {}).items()):
        if not _DEFINE_NAME.fullmatch(name):
            raise SpectraceError(f"kernel define name '{name}' is not a C identifier")
        options += ["-D", f"{name}={_define_value(name, value)}"]
    return options


def build_options(
    kernels_dir: Path,
    defines: Mapping[str, DefineValue] | None,
    extra: list[str] | None,
    generated_dir: Path | None = None,
) -> str:
    options = [*_BASE_OPTIONS, *_include_option(kernels_dir)]
    if generated_dir is not None:
        options += _include_option(generated_dir)
    return " ".join(options + _define_options(defines) + list(extra or []))


def keyed_options(defines: Mapping[str, DefineValue] | None, extra: list[str] | None) -> str:
    """`build_options` less the include folders: what the cache key names, so that it depends on the sources'
    content (named by their digest) and not on where they lie."""
    return " ".join([*_BASE_OPTIONS, *_define_options(defines), *(extra or [])])


def kernel_contract(generated: GeneratedSources | None = None) -> dict[str, DefineValue]:
    """Every value of the host/device contract, which every build gets as defines: the struct codes, wavelength
    grid and buffer layouts (spectrace.core.contract) and the registries' type codes the build is handed."""
    # Not at import: the contract loads numpy tables.
    from spectrace.core.contract import device_contract_defines

    return device_contract_defines() | dict(generated.defines if generated is not None else {})


# Contract values a render may set for itself: the wavelength grid of the spectrum table, which a film with a range
# of its own (film.wavelengths, spectrace.film.response) moves; the host builds that table on the same grid.
RENDER_SETTABLE_CONTRACT = frozenset({"GRID_MIN_NM", "GRID_MAX_NM", "GRID_SAMPLES"})


def _with_contract(
    defines: Mapping[str, DefineValue] | None, generated: GeneratedSources | None = None
) -> dict[str, DefineValue]:
    """`defines` plus the host/device contract, which every build gets: the kernels keep no copy of those numbers."""
    contract = kernel_contract(generated)
    clash = sorted((set(contract) - RENDER_SETTABLE_CONTRACT) & set(defines or {}))
    if clash:
        raise SpectraceError(f"kernel define {clash[0]} is fixed by the host/device contract")
    across_items = {VECTORISE_VARIABLE: 1} if os.environ.get(VECTORISE_VARIABLE, "").strip() == "1" else {}
    return contract | across_items | dict(defines or {})


def _headers_digest(headers: Mapping[str, str]) -> str:
    digest = hashlib.sha256()
    for name, text in sorted(headers.items()):
        digest.update(name.encode() + b"\0" + text.encode() + b"\0")
    return digest.hexdigest()


def _write_generated_headers(headers: Mapping[str, str], digest: str) -> Path:
    """The folder holding `headers`, named by their digest so that a build's options (and so its cache key) name
    their content; written once, atomically."""
    folder = program_cache_dir() / "generated" / digest[:24]
    for name, text in headers.items():
        path = folder / name
        try:
            present = path.is_file() and path.read_bytes() == text.encode()
        except OSError:
            present = False
        if not present:
            _write_atomically(path, text.encode())
            if not path.is_file():
                raise SpectraceError("cannot write a generated kernel header", where=str(path))
    return folder


def device_identity(report: DeviceReport) -> str:
    return "\n".join((report.platform_name, report.platform_version, report.device_name, report.driver_version))


def program_cache_key(sources_digest: str, entry: str, options: str, identity: str) -> str:
    digest = hashlib.sha256(_CACHE_FORMAT)
    for part in (sources_digest, entry, options, identity):
        digest.update(b"\0" + part.encode())
    return digest.hexdigest()[:40]


def program_cache_dir() -> Path:
    return cache_root() / "kernels"


def _cache_entry(binary: bytes) -> bytes:
    """A cache file's content: the format tag, the binary's SHA-256, then the binary."""
    return _CACHE_FORMAT + b"\n" + hashlib.sha256(binary).digest() + binary


def _cached_binary(entry: bytes) -> bytes | None:
    """The binary of a cache file, or None when the file is not whole (truncated, overwritten, another format): a
    damaged binary is never handed to the runtime, whose loader need not survive one."""
    head = _CACHE_FORMAT + b"\n"
    if not entry.startswith(head):
        return None
    digest, binary = entry[len(head) : len(head) + 32], entry[len(head) + 32 :]
    return binary if binary and hashlib.sha256(binary).digest() == digest else None


@contextlib.contextmanager
def _building(cache_file: Path) -> Iterator[None]:
    """Held while one process builds the program of `cache_file`: another that wants the same program (a second
    test worker, a parallel sweep) waits and then loads the binary instead of building it too. Where the lock file
    cannot be made or locked, builds go on unlocked: the cache is only ever a saving."""
    fd = None
    if fcntl is not None:
        try:
            cache_file.parent.mkdir(parents=True, exist_ok=True)
            fd = os.open(cache_file.with_suffix(".lock"), os.O_RDWR | os.O_CREAT | getattr(os, "O_CLOEXEC", 0), 0o644)
            fcntl.flock(fd, fcntl.LOCK_EX)
        except OSError:
            if fd is not None:
                os.close(fd)
            fd = None
    try:
        yield
    finally:
        if fd is not None:
            os.close(fd)  # closing drops the lock; the empty file stays for the next build of this key


def _write_atomically(path: Path, data: bytes) -> None:
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        handle, temporary = tempfile.mkstemp(prefix=f".{path.name}-", dir=path.parent)
        with os.fdopen(handle, "wb") as stream:
            stream.write(data)
        os.replace(temporary, path)  # readers see the old file or the whole new one, never a part
    except OSError:
        pass  # an unwritable cache costs a rebuild next time, nothing more


def _log_build(entry: str, own_options: str, seconds: float, cpu_seconds: float) -> None:
    """One line in $SPECTRACE_BUILD_LOG per build from source: wall and process CPU seconds, entry and the build's
    own defines and options (the contract's, which every build gets alike, left out). An unwritable log is skipped."""
    path = os.environ.get(BUILD_LOG_VARIABLE, "").strip()
    if not path:
        return
    line = f"{seconds:.2f}\t{cpu_seconds:.2f}\t{os.getpid()}\t{entry}\t{own_options}\n"
    with contextlib.suppress(OSError), open(path, "a", encoding="utf-8") as stream:
        stream.write(line)  # one short write in append mode: lines of parallel workers do not interleave


def _program_binary(program: cl.Program) -> bytes | None:
    try:
        # get_info's answer depends on the query: BINARIES is one bytes object per device.
        binaries = cast("list[bytes]", program.get_info(cl.program_info.BINARIES))
    except cl.Error:
        return None
    return bytes(binaries[0]) if binaries and binaries[0] else None


class Device:
    """One opened OpenCL device: its context, in-order queue, report, and cached program builds."""

    def __init__(self, report: DeviceReport, cl_device: cl.Device, private: bool = False):
        """`private`: a context of its own, as another process would have, which reuses no program built by
        another device (the binaries on disk it does)."""
        self.report = report
        self.cl_device = cl_device
        self._shared = _SharedContext(cl_device) if private else _shared_context(cl_device)
        self.context = self._shared.context
        self.queue = cl.CommandQueue(self.context)
        self.last_build_seconds: float | None = None
        self.last_build_cached: bool | None = None
        self.last_build_log: str = ""  # the compiler's messages of the last source build

    def __repr__(self) -> str:
        return f"Device({self.report.key!r}, {self.report.device_name!r})"

    def build_program(
        self,
        entry: str,
        defines: Mapping[str, DefineValue] | None = None,
        options: list[str] | None = None,
        from_source: bool = False,
        generated: GeneratedSources | None = None,
    ) -> cl.Program:
        """Build ``kernels/<entry>`` with ``-I kernels``, ``-I`` the folder of the generated headers and
        ``-D name=value`` for each define and each value of the host/device contract (`kernel_contract`, with the
        registries' codes and headers in `generated`, which kernels that dispatch over a registry need), reusing a
        cached binary when sources, generated headers, options and device are unchanged, unless `from_source` (a
        program loaded from a binary may lack what only the compiler knows: Intel's CPU runtime then reports no
        kernel argument names although built with -cl-kernel-arg-info)."""
        started = time.perf_counter()
        kernels_dir = resources.kernels_dir()
        if not (kernels_dir / entry).is_file():
            raise SpectraceError(f"kernel file '{entry}' not found in the kernels folder", where=entry)
        headers = dict(generated.headers) if generated is not None else {}
        headers_digest = _headers_digest(headers)
        all_defines = _with_contract(defines, generated) | runtime_defines(self.report)
        sources_digest = hashlib.sha256(f"{kernels_digest(kernels_dir)} {headers_digest}".encode()).hexdigest()
        key_options = keyed_options(all_defines, options)
        key = program_cache_key(sources_digest, entry, key_options, device_identity(self.report))
        kept = None if from_source else self._shared.kept(key)
        if kept is not None:  # built in this process already: nothing to write, read or load
            self.last_build_cached = True
            self.last_build_seconds = time.perf_counter() - started
            return kept

        generated_dir = _write_generated_headers(headers, headers_digest) if headers else None
        option_text = build_options(kernels_dir, all_defines, options, generated_dir)
        cache_file = program_cache_dir() / f"{key}.bin"
        program = None if from_source else self._load_cached(cache_file, option_text)
        if program is None:
            with contextlib.nullcontext() if from_source else _building(cache_file):
                # Another process may have built it while this one waited for the lock.
                program = None if from_source else self._load_cached(cache_file, option_text)
                if program is None:
                    own = " ".join(_define_options(defines) + list(options or []))
                    prelude = source_prelude(all_defines)
                    program = self._build_and_store(entry, sources_digest, option_text, cache_file, own, prelude)
        if not from_source:
            self._shared.keep(key, program)
        self.last_build_seconds = time.perf_counter() - started
        return program

    def _load_cached(self, cache_file: Path, option_text: str) -> cl.Program | None:
        try:
            binary = _cached_binary(cache_file.read_bytes()) if cache_file.is_file() else None
        except OSError:
            binary = None
        program = None if binary is None else _load_binary(self.context, self.cl_device, binary, option_text)
        self.last_build_cached = program is not None
        return program

    def _build_and_store(
        self, entry: str, sources_digest: str, option_text: str, cache_file: Path, own_options: str, prelude: str = ""
    ) -> cl.Program:
        self.last_build_cached = False
        started = time.perf_counter(), time.process_time()
        program = self._build_from_source(entry, sources_digest, option_text, prelude)
        self.last_build_log = compiler_log(program, self.cl_device)
        binary = _program_binary(program)  # PoCL compiles every kernel of the program to answer this
        _log_build(entry, own_options, time.perf_counter() - started[0], time.process_time() - started[1])
        if binary is not None:
            _write_atomically(cache_file, _cache_entry(binary))
        return program

    def _build_from_source(self, entry: str, sources_digest: str, option_text: str, prelude: str = "") -> cl.Program:
        # Including the entry (rather than pasting its text) keeps file names in compiler messages; the
        # digest line makes any runtime's own source-keyed cache miss when an included header changes.
        source = f'// spectrace kernels {sources_digest}\n{prelude}#include "{entry}"\n'
        try:
            return compile_source(self.context, self.cl_device, source, option_text)
        except KernelBuildError as error:
            log = "\n".join(error.build_log.splitlines()[:_LOG_LINES])
            raise KernelBuildError(
                f"kernel build failed on {self.report.key}: {error.message}\n{log}", log, where=entry
            ) from None
