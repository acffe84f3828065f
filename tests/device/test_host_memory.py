"""Large read-only buffers in huge pages on CPU devices (spectrace.device.host_memory): the bytes are the array's, the
memory is 2 MiB-aligned and advised for huge pages, only CPU devices and large arrays take it, and a render from such
buffers has the bits of one from copied buffers."""

import sys
from types import SimpleNamespace

import numpy as np
import pyopencl as cl
import pytest

import spectrace
from spectrace.device import host_memory
from spectrace.engine.renderer import Renderer
from spectrace.resources import scenes_dir

linux_only = pytest.mark.skipif(
    not (sys.platform.startswith("linux") and host_memory.HUGE_PAGES_ADVISABLE),
    reason="/proc/self/smaps, MADV_HUGEPAGE",
)


def _vm_flags(address: int) -> list[str]:
    """The VmFlags of this process's mapping holding `address` (/proc/self/smaps)."""
    inside = False
    with open("/proc/self/smaps", encoding="ascii") as smaps:
        for line in smaps:
            head = line.split()[0]
            if "-" in head and not head.endswith(":"):
                start, end = (int(part, 16) for part in head.split("-"))
                inside = start <= address < end
            elif inside and head == "VmFlags:":
                return line.split()[1:]
    raise AssertionError(f"no mapping holds {address:#x}")


@linux_only
def test_a_copy_in_aligned_memory_advised_for_huge_pages():
    array = np.random.default_rng(1).random((300_000, 4)).astype(np.float32)  # 4.6 MiB: three huge pages
    copy = host_memory.huge_page_array(array)
    np.testing.assert_array_equal(copy, array)
    assert copy.dtype == array.dtype and copy.shape == array.shape and copy.flags.c_contiguous
    assert copy.ctypes.data % host_memory.HUGE_PAGE_BYTES == 0
    assert "hg" in _vm_flags(copy.ctypes.data)  # VM_HUGEPAGE: madvise(MADV_HUGEPAGE) took


@linux_only
def test_only_large_arrays_for_cpu_devices_go_to_huge_pages(monkeypatch):
    cpu = SimpleNamespace(devices=[SimpleNamespace(type=cl.device_type.CPU)])
    gpu = SimpleNamespace(devices=[SimpleNamespace(type=cl.device_type.GPU)])
    large, small = host_memory.MIN_HUGE_PAGE_ARRAY_BYTES, host_memory.MIN_HUGE_PAGE_ARRAY_BYTES - 1
    assert host_memory.wants_huge_pages(cpu, large)
    assert not host_memory.wants_huge_pages(cpu, small)
    assert not host_memory.wants_huge_pages(gpu, large)
    monkeypatch.setattr(host_memory, "HUGE_PAGES_ADVISABLE", False)  # a system without madvise's huge pages
    assert not host_memory.wants_huge_pages(cpu, large)


def _uses_host_memory(buffer: cl.Buffer) -> bool:
    return bool(buffer.get_info(cl.mem_info.FLAGS) & cl.mem_flags.USE_HOST_PTR)


@linux_only
def test_a_large_buffer_reads_back_its_array(device):
    if not device.cl_device.type & cl.device_type.CPU:
        pytest.skip("huge pages are for CPU devices; a GPU's buffers are copied")
    array = np.arange(host_memory.MIN_HUGE_PAGE_ARRAY_BYTES // 4, dtype=np.int32)
    buffer = host_memory.read_only_buffer(device.context, array)
    assert _uses_host_memory(buffer)
    assert not _uses_host_memory(host_memory.read_only_buffer(device.context, array[:1000]))
    back = np.empty_like(array)
    cl.enqueue_copy(device.queue, back, buffer)
    np.testing.assert_array_equal(back, array)


@linux_only
def test_a_render_from_huge_page_buffers_has_the_bits_of_one_from_copies(device, monkeypatch):
    if not device.cl_device.type & cl.device_type.CPU:
        pytest.skip("huge pages are for CPU devices; a GPU's buffers are copied")
    scene = spectrace.load_scene(scenes_dir() / "cornell_box.toml").with_overrides(width=24, height=24, spp=4)
    copied = Renderer(scene, device)
    assert not any(_uses_host_memory(buffer) for buffer in copied._scene)  # the Cornell box's are small
    expected = copied.render().xyz
    monkeypatch.setattr(host_memory, "MIN_HUGE_PAGE_ARRAY_BYTES", 0)
    in_place = Renderer(scene, device)
    assert all(_uses_host_memory(buffer) for buffer in in_place._scene)
    np.testing.assert_array_equal(in_place.render().xyz, expected)


@linux_only
@pytest.mark.parametrize("refused", ["mmap", "madvise"])
def test_where_the_system_refuses_huge_pages_the_buffer_is_copied(device, monkeypatch, refused):
    """An anonymous mapping refused (ENOMEM: memory or the map count exhausted), or the advice refused (EINVAL: a
    kernel without transparent huge pages), costs the speed-up only: the buffer is copied and holds the array."""
    import errno
    import mmap

    if not device.cl_device.type & cl.device_type.CPU:
        pytest.skip("huge pages are for CPU devices; a GPU's buffers are copied")
    real_mmap = mmap.mmap

    class Refusing:
        def __init__(self, *args, **kwargs):
            if refused == "mmap":
                raise OSError(errno.ENOMEM, "Cannot allocate memory")
            self._mapping = real_mmap(*args, **kwargs)

        def madvise(self, *args):
            raise OSError(errno.EINVAL, "Invalid argument")

        def __getattr__(self, name):
            return getattr(self._mapping, name)

    monkeypatch.setattr(host_memory.mmap, "mmap", Refusing)
    with pytest.raises(OSError):
        host_memory.huge_page_array(np.zeros(16, np.float32))  # the refusal is real for the copy itself
    array = np.arange(host_memory.MIN_HUGE_PAGE_ARRAY_BYTES // 4, dtype=np.int32)
    buffer = host_memory.read_only_buffer(device.context, array)
    assert not _uses_host_memory(buffer)
    back = np.empty_like(array)
    cl.enqueue_copy(device.queue, back, buffer)
    np.testing.assert_array_equal(back, array)
