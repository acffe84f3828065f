"""Read-only device buffers, the large ones on a CPU device in huge pages.

A CPU runtime's kernels read a buffer from the process's own memory, so an incoherent ray's walk through a node
buffer of tens of megabytes misses the TLB at most steps when that memory is in 4 KiB pages (a core's second-level
TLB covers 8 MiB of them). Embree takes 2 MiB pages for its trees on Linux by default. Here a large array is copied
into anonymous memory aligned to 2 MiB and advised for transparent huge pages (madvise MADV_HUGEPAGE: the kernel
backs it with huge pages where its setting allows, `always` or `madvise`), and the buffer uses that memory in place
(CL_MEM_USE_HOST_PTR). Measured on the rays bench's 1.3 M-triangle mesh (72 MiB of nodes and blocks, 60 MiB of
vertices): 1.09x the closest-hit rays/s on Intel's runtime and 1.15x on PoCL; the kernels read the same bytes, so
every image keeps its bits (docs/performance.md). A GPU reads a host-pointer buffer across its bus, and small arrays
gain nothing: those are copied to the runtime's own memory as before.
"""

from __future__ import annotations

import mmap
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    import pyopencl as cl

HUGE_PAGE_BYTES = 2 << 20
HUGE_PAGES_ADVISABLE = hasattr(mmap, "MADV_HUGEPAGE") and hasattr(mmap, "MAP_ANONYMOUS")
# Arrays smaller than this stay in the runtime's own memory: at most a quarter of a huge page-backed copy is then the
# rounding of its last page.
MIN_HUGE_PAGE_ARRAY_BYTES = 8 << 20


def huge_page_array(array: np.ndarray) -> np.ndarray:
    """A copy of `array` in anonymous memory starting on a 2 MiB boundary and advised for huge pages; the copy keeps
    its mapping alive. Needs MADV_HUGEPAGE (HUGE_PAGES_ADVISABLE)."""
    array = np.ascontiguousarray(array)
    pages = -(-max(array.nbytes, 1) // HUGE_PAGE_BYTES)
    # One page more than the data needs, for the alignment: the kernel gives untouched pages no memory.
    mapping = mmap.mmap(-1, (pages + 1) * HUGE_PAGE_BYTES, flags=mmap.MAP_PRIVATE | mmap.MAP_ANONYMOUS)
    mapping.madvise(mmap.MADV_HUGEPAGE)
    raw = np.frombuffer(mapping, np.uint8)
    start = -raw.ctypes.data % HUGE_PAGE_BYTES
    copy = raw[start : start + array.nbytes].view(array.dtype).reshape(array.shape)
    copy[...] = array
    return copy


def wants_huge_pages(context: cl.Context, nbytes: int) -> bool:
    """Whether an array of `nbytes` goes into huge pages for `context`: large, every device of it a CPU, and a system
    that can advise huge pages (Linux)."""
    import pyopencl as cl

    return (
        HUGE_PAGES_ADVISABLE
        and nbytes >= MIN_HUGE_PAGE_ARRAY_BYTES
        and all(device.type & cl.device_type.CPU for device in context.devices)
    )


def read_only_buffer(context: cl.Context, array: np.ndarray) -> cl.Buffer:
    """A read-only buffer holding `array`: on a CPU device a large one in huge pages (the buffer keeps them), else,
    or where the system gives none, copied to the runtime's memory."""
    import pyopencl as cl

    array = np.ascontiguousarray(array)
    if wants_huge_pages(context, array.nbytes):
        try:
            in_huge_pages = huge_page_array(array)
        except OSError:
            # No anonymous mapping to be had (memory or map count exhausted), or a kernel built without transparent
            # huge pages refusing the advice: the huge pages are only a speed-up, so the buffer is copied instead.
            pass
        else:
            return cl.Buffer(context, cl.mem_flags.READ_ONLY | cl.mem_flags.USE_HOST_PTR, hostbuf=in_huge_pages)
    return cl.Buffer(context, cl.mem_flags.READ_ONLY | cl.mem_flags.COPY_HOST_PTR, hostbuf=array)
