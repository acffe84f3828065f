"""spectrace.device: runtime discovery, probing, selection and the program binary cache.

These run against the OpenCL runtimes really installed (at least the PyPI PoCL that spectrace depends
on); a broken runtime is simulated by replacing the probe function.
"""

from __future__ import annotations

import dataclasses
import json
import os
import shutil
import subprocess
import sys
import textwrap
import threading
import time
from pathlib import Path

import numpy as np
import pyopencl as cl
import pytest

import spectrace.resources
from spectrace.device import (
    Device,
    DeviceReport,
    NoWorkingDeviceError,
    device_table,
    discover_devices,
    open_device,
    prepare_opencl_environment,
    program_cache,
)
from spectrace.device import probe as probing
from spectrace.device.discovery import elf_needed_libraries, find_devices, pip_intel_cpu_libraries
from spectrace.device.program_cache import KernelBuildError
from spectrace.device.selection import preference_rank
from spectrace.errors import SpectraceError

HOST_DIR = Path(spectrace.resources.__file__).resolve().parent.parent

# Real probe results, measured once per test process: each test may swap in a fake, never re-measure.
_real_probe_results: dict[str, probing.ProbeResult] = {}


def _real_probe(found) -> probing.ProbeResult:
    if found.key not in _real_probe_results:
        _real_probe_results[found.key] = probing.probe_kernel_on_device(found)
    return _real_probe_results[found.key]


def _failing_probe(failing_keys: set[str], reason: str = "simulated: unknown target CPU 'generic'"):
    def probe(found) -> probing.ProbeResult:
        return probing.ProbeResult(False, reason) if found.key in failing_keys else _real_probe(found)

    return probe


@pytest.fixture(autouse=True)
def isolated_device_state(tmp_path, monkeypatch):
    monkeypatch.setenv("SPECTRACE_CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.delenv("SPECTRACE_DEVICE", raising=False)
    monkeypatch.setattr(probing, "probe_function", _real_probe)
    monkeypatch.setattr(program_cache, "_SHARED", {})  # as a fresh process: no program built yet
    probing.forget_probe_results()
    yield
    probing.forget_probe_results()


def _working_keys() -> list[str]:
    return [report.key for report in discover_devices() if report.ok]


def _require_working_devices(count: int) -> list[str]:
    keys = _working_keys()
    if len(keys) < count:
        pytest.skip(f"needs {count} working OpenCL devices, found {len(keys)}")
    return keys


# --- discovery -------------------------------------------------------------------------------------------


def test_vendors_folder_names_every_default_runtime_by_path():
    prepared = prepare_opencl_environment()
    assert os.environ["OCL_ICD_VENDORS"] == str(prepared.vendors_dir)
    assert prepare_opencl_environment() is prepared  # idempotent
    listed = {p.read_text().strip() for p in prepared.vendors_dir.glob("*.icd")}
    system_vendors = Path("/etc/OpenCL/vendors")
    for icd_file in sorted(system_vendors.glob("*.icd")) if system_vendors.is_dir() else []:
        assert icd_file.read_text().strip().splitlines()[0].strip() in listed
    bundled = Path(cl.__file__).parent / ".libs"
    for icd_file in bundled.glob("*.icd"):
        # The bundled loader finds these beside itself; our folder must name them by full path.
        assert str(bundled / icd_file.read_text().strip()) in listed
    for library in pip_intel_cpu_libraries():
        assert str(library) in listed


def test_platforms_are_deduplicated_and_none_is_lost():
    reports = [r for r in discover_devices() if r.device_type != "NONE"]
    identities = [(r.platform_name, r.platform_version, r.device_name, r.driver_version) for r in reports]
    assert len(identities) == len(set(identities))
    assert len({r.key for r in reports}) == len(reports)
    # Reference: the loader's own listing, which may name one runtime twice.
    loader_listing = {
        (p.name.strip(), p.version.strip(), d.name.strip(), d.driver_version.strip())
        for p in cl.get_platforms()
        for d in p.get_devices()
    }
    assert set(identities) == loader_listing


def test_the_listing_read_without_pyopencl_equals_pyopencls():
    """Platforms and devices are read from the runtime libraries through ctypes; pyopencl's own enumeration through
    its loader is the reference for every value, for the platforms' order, and for the Device a probe or render
    gets."""
    listed = [found for found in find_devices() if found.device is not None]  # first: it prepares the loader
    assert listed, "no OpenCL device to compare"
    reference = {}
    loader_order = []
    for platform in cl.get_platforms():
        if platform.int_ptr not in loader_order:
            loader_order.append(platform.int_ptr)
        for device in platform.get_devices():
            reference[platform.int_ptr, device.int_ptr] = (platform, device)
    for found in listed:
        platform, device = reference[found.platform.handle, found.device.handle]
        assert (found.platform.name, found.platform.vendor, found.platform.version) == (
            platform.name,
            platform.vendor,
            platform.version,
        )
        info = found.device
        assert (info.name, info.type_bits, info.version, info.driver_version) == (
            device.name,
            device.type,
            device.version,
            device.driver_version,
        )
        assert (info.max_compute_units, info.global_mem_size) == (device.max_compute_units, device.global_mem_size)
        opened = found.opencl_device()
        assert opened == device and opened.int_ptr == device.int_ptr
    # Every device of the loader's is listed, less copies of a runtime listed twice (same name and versions).
    identities = {(found.platform.name, found.platform.version, found.device.name) for found in listed}
    assert {(p.name, p.version, d.name) for p, d in reference.values()} == identities
    # In the loader's order: it decides which copy of a duplicated runtime is kept and how ties are preferred.
    listed_platforms = list(dict.fromkeys(found.platform.handle for found in listed))
    assert listed_platforms == [handle for handle in loader_order if handle in listed_platforms]


def test_the_two_pocls_are_told_apart():
    bundled = (Path(cl.__file__).parent / ".libs").resolve()
    for report in discover_devices():
        if report.platform_name != "Portable Computing Language":
            continue
        from_pyopencl_wheel = report.library is not None and Path(report.library).resolve().parent == bundled
        assert report.runtime == ("PoCL (PyPI)" if from_pyopencl_wheel else "PoCL (system)")
        assert report.key.startswith("pocl-pypi:" if from_pyopencl_wheel else "pocl-system:")


@pytest.mark.subprocess
def test_elf_needed_libraries_match_readelf():
    readelf = shutil.which("readelf")
    if readelf is None:
        pytest.skip("readelf is not installed")
    library = Path(cl._cl.__file__)  # noqa: SLF001 - any shared object will do
    listing = subprocess.run([readelf, "-d", str(library)], capture_output=True, text=True, check=True).stdout
    expected = [line.split("[", 1)[1].rstrip("]") for line in listing.splitlines() if "(NEEDED)" in line]
    assert expected and elf_needed_libraries(library) == expected


def _fresh_python(code: str, tmp_path: Path) -> subprocess.CompletedProcess:
    environment = {k: v for k, v in os.environ.items() if k not in ("LD_LIBRARY_PATH", "OCL_ICD_VENDORS")}
    environment["PYTHONPATH"] = os.pathsep.join([str(HOST_DIR), environment.get("PYTHONPATH", "")])
    environment["SPECTRACE_CACHE_DIR"] = str(tmp_path / "fresh-cache")
    return subprocess.run(
        [sys.executable, "-c", textwrap.dedent(code)], capture_output=True, text=True, env=environment, timeout=120
    )


@pytest.mark.subprocess
@pytest.mark.parametrize("given", [None, "1"])
def test_pocl_work_group_specialisation_is_off_unless_the_user_sets_it(tmp_path, given, monkeypatch):
    # PoCL's compile per work-group size, offset and grid class doubled a cold program's cost for the same bits.
    monkeypatch.delenv("POCL_WORK_GROUP_SPECIALIZATION", raising=False)
    if given is not None:
        monkeypatch.setenv("POCL_WORK_GROUP_SPECIALIZATION", given)
    result = _fresh_python(
        """
        import os
        from spectrace.device import prepare_opencl_environment
        prepare_opencl_environment()
        print(os.environ["POCL_WORK_GROUP_SPECIALIZATION"])
        """,
        tmp_path,
    )
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == (given or "0")


@pytest.mark.subprocess
@pytest.mark.skipif(not pip_intel_cpu_libraries(), reason="Intel's CPU runtime is not pip-installed")
def test_pip_intel_runtime_works_in_a_fresh_process(tmp_path):
    result = _fresh_python(
        """
        import json
        from spectrace.device import discover_devices
        print(json.dumps([[r.key, r.runtime, r.ok, r.reason] for r in discover_devices()]))
        """,
        tmp_path,
    )
    assert result.returncode == 0, result.stderr
    reports = json.loads(result.stdout.strip().splitlines()[-1])
    intel = [r for r in reports if r[1] == "Intel CPU runtime (pip)"]
    assert intel and all(ok for _, _, ok, _ in intel), reports


@pytest.mark.subprocess
@pytest.mark.slow
def test_a_runtime_that_cannot_load_is_listed_with_the_reason(tmp_path):
    vendors = tmp_path / "vendors"
    vendors.mkdir()
    (vendors / "broken.icd").write_text(str(tmp_path / "libbrokenvendor-opencl.so") + "\n")
    result = _fresh_python(
        f"""
        import json, os
        os.environ["OCL_ICD_VENDORS"] = {str(vendors)!r}
        from spectrace.device import discover_devices
        print(json.dumps([[r.key, r.ok, r.reason] for r in discover_devices()]))
        """,
        tmp_path,
    )
    assert result.returncode == 0, result.stderr
    reports = json.loads(result.stdout.strip().splitlines()[-1])
    [broken] = [r for r in reports if r[0].startswith("brokenvendor:")]
    assert broken[1] is False and "runtime did not load" in broken[2] and "libbrokenvendor-opencl.so" in broken[2]


@pytest.mark.subprocess
@pytest.mark.skipif(not pip_intel_cpu_libraries(), reason="Intel's CPU runtime is not pip-installed")
def test_preloading_dependencies_rescues_a_runtime_its_run_path_misses(tmp_path):
    # A symlink elsewhere makes $ORIGIN point to the wrong folder: the plain dlopen fails.
    link = tmp_path / "libintelocl.so"
    link.symlink_to(pip_intel_cpu_libraries()[0])
    plain = _fresh_python(f"import ctypes; ctypes.CDLL({str(link)!r})", tmp_path)
    if plain.returncode == 0:
        pytest.skip("this dynamic loader resolves the run path through the symlink")
    rescued = _fresh_python(
        f"""
        import ctypes
        from pathlib import Path
        from spectrace.device.discovery import preload_dependencies
        assert preload_dependencies(Path({str(link)!r})) == []
        ctypes.CDLL({str(link)!r})
        """,
        tmp_path,
    )
    assert rescued.returncode == 0, rescued.stderr


# --- selection -------------------------------------------------------------------------------------------


def _report(key: str, runtime: str, device_type: str) -> DeviceReport:
    return DeviceReport(
        key=key,
        runtime=runtime,
        platform_name="",
        platform_version="",
        device_name="",
        device_type=device_type,
        driver_version="",
        compute_units=1,
        global_mem_bytes=1,
        ok=True,
        reason=None,
    )


def test_preference_is_gpu_then_intel_then_system_pocl_then_pypi_pocl():
    expected = [
        _report("nvidia:gpu:0", "NVIDIA CUDA", "GPU"),
        _report("pocl-system:gpu:0", "PoCL (system)", "GPU"),
        _report("intel-cpu:cpu:0", "Intel CPU runtime (pip)", "CPU"),
        _report("pocl-system:cpu:0", "PoCL (system)", "CPU"),
        _report("pocl-pypi:cpu:0", "PoCL (PyPI)", "CPU"),
    ]
    scrambled = [expected[i] for i in (4, 2, 0, 3, 1)]
    assert sorted(scrambled, key=preference_rank) == expected


def test_broken_runtime_is_skipped_with_its_reason(monkeypatch):
    keys = _require_working_devices(2)
    preferred = open_device().report.key
    monkeypatch.setattr(probing, "probe_function", _failing_probe({preferred}))
    probing.forget_probe_results()
    chosen = open_device()
    assert isinstance(chosen, Device)
    assert chosen.report.key != preferred and chosen.report.key in keys
    broken = next(r for r in discover_devices() if r.key == preferred)
    assert not broken.ok and "unknown target CPU 'generic'" in broken.reason
    table_text = device_table(discover_devices())
    assert preferred in table_text and "unknown target CPU 'generic'" in table_text


def test_no_working_device_says_what_to_install(monkeypatch):
    all_keys = {found.key for found in find_devices()}
    monkeypatch.setattr(probing, "probe_function", _failing_probe(all_keys))
    probing.forget_probe_results()
    with pytest.raises(NoWorkingDeviceError) as caught:
        open_device()
    message = str(caught.value)
    assert isinstance(caught.value, SpectraceError)
    assert "\n" not in message
    assert 'pip install "spectrace[cpu]"' in message
    assert "apt-get install -y pocl-opencl-icd" in message
    assert "spectrace devices" in message
    # The CLI's `spectrace devices` raises the same error from the reports it has shown.
    assert str(NoWorkingDeviceError(discover_devices())) == message


def test_no_opencl_runtime_at_all_says_what_to_install(monkeypatch, tmp_path, capsys):
    from spectrace import cli
    from spectrace.device import selection

    monkeypatch.setattr(selection, "find_devices", lambda: [])
    monkeypatch.delenv("SPECTRACE_DEVICE", raising=False)
    with pytest.raises(NoWorkingDeviceError) as caught:
        open_device()
    message = str(caught.value)
    assert "no OpenCL runtime found" in message and "\n" not in message
    assert 'pip install "spectrace[cpu]"' in message and "apt-get install -y pocl-opencl-icd" in message

    scene = spectrace.resources.scenes_dir() / "cornell_box.toml"
    monkeypatch.setattr(sys, "argv", ["spectrace", "render", str(scene), "-o", str(tmp_path / "x.png"), "-q"])
    with pytest.raises(SystemExit) as exit_info:
        cli.main()
    stderr = capsys.readouterr().err
    assert exit_info.value.code == 2 and stderr.count("\n") == 1 and "Traceback" not in stderr
    assert stderr.startswith("error: no OpenCL runtime found"), stderr


def test_unknown_device_spec_lists_the_available_keys():
    with pytest.raises(NoWorkingDeviceError) as caught:
        open_device("no-such-device")
    message = str(caught.value)
    assert "no-such-device" in message
    for found in find_devices():
        assert found.key in message


def test_spec_matching_only_broken_devices_is_refused(monkeypatch):
    target = _require_working_devices(1)[0]
    monkeypatch.setattr(probing, "probe_function", _failing_probe({target}, "simulated failure"))
    probing.forget_probe_results()
    with pytest.raises(NoWorkingDeviceError) as caught:
        open_device(target)
    assert target in str(caught.value) and "simulated failure" in str(caught.value)


def test_environment_variable_picks_the_device_and_an_explicit_spec_wins(monkeypatch):
    keys = _working_keys()
    if not keys:
        pytest.skip("no working OpenCL device")
    least_preferred = keys[-1]
    monkeypatch.setenv("SPECTRACE_DEVICE", least_preferred)
    assert open_device().report.key == least_preferred
    assert open_device(keys[0]).report.key == keys[0]


def test_substring_spec_matches_runtime_case_insensitively():
    pocl_keys = [key for key in _working_keys() if key.startswith("pocl-")]
    if not pocl_keys:
        pytest.skip("no working PoCL")
    assert open_device("PoCL").report.key == pocl_keys[0]


# --- program cache ---------------------------------------------------------------------------------------


@pytest.fixture
def kernels_folder(tmp_path, monkeypatch) -> Path:
    folder = tmp_path / "kernels"
    (folder / "tests").mkdir(parents=True)
    (folder / "scale.h").write_text("#define SCALE_FACTOR 3.0f\n")
    (folder / "tests" / "affine.cl").write_text(
        textwrap.dedent("""\
        #include "scale.h"
        __kernel void affine(__global float* out)
        {
            const size_t i = get_global_id(0);
            out[i] = (float)i * SCALE_FACTOR + OFFSET;
        }
        """)
    )
    monkeypatch.setattr(spectrace.resources, "kernels_dir", lambda: folder)
    return folder


@pytest.fixture
def device() -> Device:
    try:
        return open_device()
    except NoWorkingDeviceError as error:
        pytest.skip(str(error))


def _run_affine(device: Device, program: cl.Program, count: int = 16) -> np.ndarray:
    out = np.zeros(count, dtype=np.float32)
    buffer = cl.Buffer(device.context, cl.mem_flags.WRITE_ONLY, out.nbytes)
    kernel = cl.Kernel(program, "affine")
    kernel.set_args(buffer)
    cl.enqueue_nd_range_kernel(device.queue, kernel, (count,), None)
    cl.enqueue_copy(device.queue, out, buffer)
    device.queue.finish()
    return out


def _cached_binaries() -> list[Path]:
    return sorted((Path(os.environ["SPECTRACE_CACHE_DIR"]) / "kernels").glob("*.bin"))


def test_second_build_comes_from_the_cache_and_works(device, kernels_folder):
    first = device.build_program("tests/affine.cl", {"OFFSET": 0.5})
    assert device.last_build_cached is False and device.last_build_seconds > 0
    second = device.build_program("tests/affine.cl", {"OFFSET": 0.5})
    assert device.last_build_cached is True
    expected = np.arange(16, dtype=np.float32) * 3.0 + 0.5
    np.testing.assert_array_equal(_run_affine(device, second), expected)
    np.testing.assert_array_equal(_run_affine(device, first), expected)
    assert len(_cached_binaries()) == 1


def test_changing_a_define_or_a_header_changes_the_cache_key(device, kernels_folder):
    device.build_program("tests/affine.cl", {"OFFSET": 0.5})
    other = device.build_program("tests/affine.cl", {"OFFSET": 2})
    assert device.last_build_cached is False and len(_cached_binaries()) == 2
    np.testing.assert_array_equal(_run_affine(device, other), np.arange(16, dtype=np.float32) * 3.0 + 2.0)

    (kernels_folder / "scale.h").write_text("#define SCALE_FACTOR 5.0f\n")
    rescaled = device.build_program("tests/affine.cl", {"OFFSET": 2})
    assert device.last_build_cached is False and len(_cached_binaries()) == 3
    np.testing.assert_array_equal(_run_affine(device, rescaled), np.arange(16, dtype=np.float32) * 5.0 + 2.0)


@pytest.mark.parametrize(
    "damage",
    [
        lambda entry: b"not a program binary",
        lambda entry: entry[: len(entry) // 2],  # a truncated copy
        lambda entry: entry[:-1] + bytes([entry[-1] ^ 1]),  # one bit of the binary flipped
        lambda entry: b"",
    ],
    ids=["garbage", "truncated", "flipped-bit", "empty"],
)
def test_a_corrupt_cached_binary_is_rebuilt(device, kernels_folder, damage):
    device.build_program("tests/affine.cl", {"OFFSET": 1})
    [binary] = _cached_binaries()
    whole = binary.read_bytes()
    binary.write_bytes(damage(whole))
    device = Device(device.report, device.cl_device, private=True)  # as the next process: it reads the disk
    program = device.build_program("tests/affine.cl", {"OFFSET": 1})
    assert device.last_build_cached is False
    np.testing.assert_array_equal(_run_affine(device, program), np.arange(16, dtype=np.float32) * 3.0 + 1.0)
    # The rebuilt entry replaced the damaged one (a build need not give the same bytes twice: compare its use).
    assert binary.read_bytes() != damage(whole)
    again = device.build_program("tests/affine.cl", {"OFFSET": 1})
    assert device.last_build_cached is True
    np.testing.assert_array_equal(_run_affine(device, again), np.arange(16, dtype=np.float32) * 3.0 + 1.0)


@pytest.mark.slow
def test_two_builders_of_one_program_build_it_once(device, kernels_folder, monkeypatch):
    """A second builder of the same program (another test worker, a parallel sweep) waits for the first one's
    binary instead of building it too: each device here has a context of its own, as in two processes."""
    builds = []
    original = Device._build_from_source

    def slow_build(self, *args):
        builds.append(self)
        time.sleep(1.0)  # holds the build open, so that the other builder surely finds no binary when it starts
        return original(self, *args)

    monkeypatch.setattr(Device, "_build_from_source", slow_build)
    builders = [Device(device.report, device.cl_device, private=True) for _ in range(2)]
    start = threading.Barrier(len(builders))
    programs = {}

    def build(builder):
        start.wait()
        programs[id(builder)] = builder.build_program("tests/affine.cl", {"OFFSET": 4})

    threads = [threading.Thread(target=build, args=(builder,)) for builder in builders]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    assert len(builds) == 1 and len(_cached_binaries()) == 1
    assert sorted(builder.last_build_cached for builder in builders) == [False, True]
    for builder in builders:
        expected = np.arange(16, dtype=np.float32) * 3.0 + 4.0
        np.testing.assert_array_equal(_run_affine(builder, programs[id(builder)]), expected)


@pytest.mark.parametrize("where", ["elsewhere", "a folder with spaces"])
def test_the_same_kernels_in_another_folder_reuse_the_cached_binary(
    device, kernels_folder, tmp_path, monkeypatch, where
):
    """The cache is keyed by the kernels' content, not their path: a fresh clone or a second checkout of the same
    sources builds nothing, while the compiler still gets the folder it must include from."""
    device.build_program("tests/affine.cl", {"OFFSET": 0.25})
    assert device.last_build_cached is False
    [binary] = _cached_binaries()
    copy = tmp_path / where / "kernels"
    shutil.copytree(kernels_folder, copy)
    shutil.rmtree(kernels_folder)  # nothing may still be read from the first folder
    monkeypatch.setattr(spectrace.resources, "kernels_dir", lambda: copy)
    program = device.build_program("tests/affine.cl", {"OFFSET": 0.25})
    assert device.last_build_cached is True and _cached_binaries() == [binary]
    np.testing.assert_array_equal(_run_affine(device, program), np.arange(16, dtype=np.float32) * 3.0 + 0.25)
    # The copy builds from source in its own folder (an include the first folder lacked is found there).
    (copy / "scale.h").write_text('#include "factor.h"\n')
    (copy / "factor.h").write_text("#define SCALE_FACTOR 7.0f\n")
    rebuilt = device.build_program("tests/affine.cl", {"OFFSET": 0.25})
    assert device.last_build_cached is False and len(_cached_binaries()) == 2
    np.testing.assert_array_equal(_run_affine(device, rebuilt), np.arange(16, dtype=np.float32) * 7.0 + 0.25)


def test_a_process_builds_a_program_once_for_every_device_it_opens(device, kernels_folder, monkeypatch):
    """Devices opened on one OpenCL device in one process share its context and the programs built there: the
    second device's build neither compiles nor loads the binary again, and renders with a queue of its own."""
    first = device.build_program("tests/affine.cl", {"OFFSET": 0.75})
    loads = []
    original = Device._load_cached
    monkeypatch.setattr(Device, "_load_cached", lambda self, *args: loads.append(args) or original(self, *args))
    other = open_device()
    assert other.queue is not device.queue and other.context is device.context
    program = other.build_program("tests/affine.cl", {"OFFSET": 0.75})
    assert program is first and other.last_build_cached is True and loads == []
    np.testing.assert_array_equal(_run_affine(other, program), np.arange(16, dtype=np.float32) * 3.0 + 0.75)
    # A build from source is never answered from what the process holds, nor replaces it.
    fresh = other.build_program("tests/affine.cl", {"OFFSET": 0.75}, from_source=True)
    assert fresh is not first and other.build_program("tests/affine.cl", {"OFFSET": 0.75}) is first


def test_a_process_keeps_a_bounded_number_of_programs(device, kernels_folder, monkeypatch):
    monkeypatch.setattr(program_cache, "_PROGRAMS_KEPT", 2)
    programs = [device.build_program("tests/affine.cl", {"OFFSET": k}) for k in range(3)]
    assert device.build_program("tests/affine.cl", {"OFFSET": 2}) is programs[2]
    assert device.build_program("tests/affine.cl", {"OFFSET": 0}) is not programs[0]  # the oldest was let go
    assert device.last_build_cached is True  # from the binary on disk
    np.testing.assert_array_equal(_run_affine(device, programs[1]), np.arange(16, dtype=np.float32) * 3.0 + 1.0)


def test_a_failing_build_raises_with_the_compiler_log(device, kernels_folder):
    with pytest.raises(KernelBuildError) as caught:
        device.build_program("tests/affine.cl")  # OFFSET undefined
    assert isinstance(caught.value, SpectraceError)
    assert "OFFSET" in caught.value.build_log and "OFFSET" in str(caught.value)
    assert caught.value.where == "tests/affine.cl"


def test_a_missing_entry_or_bad_define_is_a_spectrace_error(device, kernels_folder):
    with pytest.raises(SpectraceError):
        device.build_program("tests/missing.cl")
    with pytest.raises(SpectraceError):
        device.build_program("tests/affine.cl", {"OFFSET": float("nan")})
    with pytest.raises(SpectraceError):
        device.build_program("tests/affine.cl", {"OFF SET": 1})


def test_the_probe_answer_is_remembered_per_runtime_version(monkeypatch, tmp_path):
    """The probe's build is paid once per runtime version, not by every `spectrace devices` and render; a remembered
    answer is used only while the runtime library and versions are the ones it was measured on."""
    monkeypatch.setenv("SPECTRACE_CACHE_DIR", str(tmp_path))
    found = next(f for f in find_devices() if f.device is not None and f.library and os.path.isabs(f.library))
    calls = []
    real_run = probing._run_probe_kernel
    monkeypatch.setattr(probing, "_run_probe_kernel", lambda device: calls.append(1) or real_run(device))
    monkeypatch.setattr(probing, "probe_function", probing.probe_kernel_on_device)  # the file's fixture memoises
    probing.forget_probe_results()
    assert probing.probe(found).ok and len(calls) == 1
    probing.forget_probe_results()
    assert probing.probe(found).ok and len(calls) == 1  # from disk: no second build

    # Another library file is another runtime version: probed again (the device object stays the same here).
    copy = tmp_path / Path(found.library).name
    shutil.copyfile(found.library, copy)
    probing.forget_probe_results()
    assert probing.probe(dataclasses.replace(found, library=str(copy))).ok and len(calls) == 2

    # A damaged file is ignored, never an error.
    (tmp_path / "probes.json").write_text("{not json", encoding="utf-8")
    probing.forget_probe_results()
    assert probing.probe(found).ok and len(calls) == 3
    probing.forget_probe_results()
