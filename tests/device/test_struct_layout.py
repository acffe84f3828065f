"""Host dtypes and kernels/types.h agree: a kernel reports sizeof and offsetof of every field on the device."""

import numpy as np

from spectrace.render.device_types import DEVICE_STRUCTS


def _layout_kernel_source() -> str:
    lines = ['#include "types.h"', "__kernel void report_layout(__global int *out)", "{", "    int k = 0;"]
    for struct, dtype in DEVICE_STRUCTS.items():
        lines.append(f"    {{ {struct} s; out[k++] = (int)sizeof({struct});")
        for field in dtype.names:
            lines.append(f"      out[k++] = (int)((__private char *)&s.{field} - (__private char *)&s);")
        lines.append("    }")
    lines.append("}")
    return "\n".join(lines)


def test_device_struct_layout_matches_numpy(device, tmp_path):
    import pyopencl as cl

    source = tmp_path / "report_layout.cl"
    source.write_text(_layout_kernel_source())
    program = device.build_program(str(source))
    expected = []
    for dtype in DEVICE_STRUCTS.values():
        expected.append(dtype.itemsize)
        expected.extend(dtype.fields[name][1] for name in dtype.names)
    out = np.zeros(len(expected), np.int32)
    buffer = cl.Buffer(device.context, cl.mem_flags.WRITE_ONLY, out.nbytes)
    program.report_layout(device.queue, (1,), None, buffer)
    cl.enqueue_copy(device.queue, out, buffer)
    device.queue.finish()
    assert out.tolist() == expected
