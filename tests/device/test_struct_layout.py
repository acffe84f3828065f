"""The host/device contract: the host dtypes and kernels/types.h agree (a kernel reports sizeof and offsetof of every
field on the device), every build sees the contract values the host defines and no kernel file keeps a copy, and the
scene kernels take the scene buffers in the order the host sets them."""

import re

import numpy as np
import pytest

from spectrace.core.contract import DEVICE_STRUCTS
from spectrace.plugins import generated_sources


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
    program = device.build_program(str(source), generated=generated_sources())
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


def _contract_report_source(names: list[str]) -> str:
    lines = ['#include "types.h"', "__kernel void report_contract(__global float *out)", "{"]
    lines += [f"    out[{k}] = (float)({name});" for k, name in enumerate(names)]
    lines.append("}")
    return "\n".join(lines)


def test_kernels_see_every_contract_value_the_host_defines(device, tmp_path):
    """Each value of the host/device contract reaches a kernel build with its value (a negative code stays one
    number inside an expression, a float keeps every digit)."""
    import pyopencl as cl

    from spectrace.device.program_cache import kernel_contract
    from spectrace.spectral.grid import GRID_MAX_NM, GRID_MIN_NM, GRID_SIZE

    contract = kernel_contract(generated_sources())
    names = sorted(contract)
    source = tmp_path / "report_contract.cl"
    source.write_text(_contract_report_source(names))
    program = device.build_program(str(source), generated=generated_sources())
    out = np.zeros(len(names), np.float32)
    buffer = cl.Buffer(device.context, cl.mem_flags.WRITE_ONLY, out.nbytes)
    program.report_contract(device.queue, (1,), None, buffer)
    cl.enqueue_copy(device.queue, out, buffer)
    device.queue.finish()
    seen = dict(zip(names, out.tolist()))
    expected = {name: float(str(value).strip("()")) for name, value in contract.items()}
    assert seen == expected
    # The grid the spectrum tables are built on is the one the kernels interpolate on.
    assert (seen["GRID_MIN_NM"], seen["GRID_MAX_NM"], seen["GRID_SAMPLES"]) == (GRID_MIN_NM, GRID_MAX_NM, GRID_SIZE)
    assert seen["MATERIAL_NO_SPECTRUM"] == seen["TRIANGLE_NO_MATERIAL"] == -1


def test_no_kernel_file_keeps_its_own_copy_of_a_contract_value():
    import re

    from spectrace import resources
    from spectrace.device.program_cache import kernel_contract

    names = set(kernel_contract(generated_sources()))
    copies = []
    for path in sorted(resources.kernels_dir().rglob("*")):
        if path.suffix in (".cl", ".h"):
            for name in re.findall(r"^\s*#\s*define\s+([A-Za-z_]\w*)", path.read_text(), flags=re.MULTILINE):
                if name in names:
                    copies.append(f"{path.name}: {name}")
    assert copies == []


def test_a_build_without_the_contract_stops_with_a_clear_error(device):
    from spectrace import resources
    from spectrace.device.program_cache import KernelBuildError, build_options, compile_source

    options = build_options(resources.kernels_dir(), None, None)
    with pytest.raises(KernelBuildError, match="contract"):
        compile_source(device.context, device.cl_device, '#include "types.h"\n', options)


@pytest.mark.parametrize("entry", ["material.cl", "texture.cl", "camera.cl", "pixel_filter.cl"])
def test_a_dispatch_built_without_the_registries_sources_stops_with_a_clear_error(device, entry):
    """The device layer adds only the contract; the plugins' codes (and the materials' list) come from their
    registries, and a build not handed them names what it lacks rather than failing somewhere inside a dispatch."""
    from spectrace import resources
    from spectrace.device.program_cache import KernelBuildError, _with_contract, build_options, compile_source

    options = build_options(resources.kernels_dir(), _with_contract(None), None)
    with pytest.raises(KernelBuildError, match="generated sources"):
        compile_source(device.context, device.cl_device, f'#include "{entry}"\n', options)


@pytest.mark.slow
def test_scene_kernels_take_the_scene_buffers_in_the_hosts_order(device):
    """The host sets a scene kernel's first arguments from SCENE_KERNEL_BUFFERS; SCENE_KERNEL_PARAMS (kernels/scene.cl)
    declares them, and its parameter names, as the compiler reports them for a kernel declared with it, must be those
    buffers in that order. A small harness kernel shows them: a source build of a render pass costs seven times as
    long, and every pass kernel opens with the same macro (the next test)."""
    import pyopencl as cl

    from spectrace.core.contract import SCENE_KERNEL_BUFFERS

    program = device.build_program(
        "testing/scene_hits.cl", options=["-cl-kernel-arg-info"], from_source=True, generated=generated_sources()
    )
    k = cl.Kernel(program, "scene_hits")
    names = [k.get_arg_info(i, cl.kernel_arg_info.NAME) for i in range(1 + len(SCENE_KERNEL_BUFFERS))]
    assert names == ["params", *SCENE_KERNEL_BUFFERS]


def _kernel_declarations() -> dict[str, str]:
    """`<file>: <kernel>` -> the parameter list of every KERNEL of the renderer (the kernels folder; the tests'
    harness kernels in kernels/testing/ take what they test as they like)."""
    from spectrace import resources

    found = {}
    for path in sorted(resources.kernels_dir().glob("*.cl")):
        text = path.read_text(encoding="utf-8")
        for match in re.finditer(r"^KERNEL void (\w+)\((.*?)\)\s*\{", text, flags=re.S | re.M):
            found[f"{path.name}: {match[1]}"] = " ".join(match[2].split())
    return found


def test_every_kernel_that_reads_the_scene_opens_with_the_scene_parameters():
    """A kernel that takes the scene's buffers takes them through SCENE_KERNEL_PARAMS, first, so the host's order
    (checked above on one kernel) is every kernel's."""
    declarations = _kernel_declarations()
    assert {"render_pass.cl: render_pass", "meters.cl: measure", "integrator_bdpt.cl: bdpt_pass"} <= set(declarations)
    scene_buffer_types = ("BVHNode", "TriangleInfo", "Material ", "Light ", "AnalyticShape", "Instance ")
    wrong = [
        name
        for name, parameters in declarations.items()
        if not parameters.startswith("SCENE_KERNEL_PARAMS") and any(t in parameters for t in scene_buffer_types)
    ]
    assert wrong == [], f"kernels that take scene buffers without SCENE_KERNEL_PARAMS first: {wrong}"
