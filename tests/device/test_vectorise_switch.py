"""SPECTRACE_VECTORISE_ACROSS_ITEMS=1 builds kernels without their vec_type_hint (kernels/kernel_entry.h), as binaries
of their own; unset, every build keeps the hint. Intel's CPU compiler says in its build log whether the hint kept its
vectoriser off, which makes the switch visible there."""

import pyopencl as cl
import pytest

from spectrace.device.program_cache import VECTORISE_VARIABLE, _with_contract, keyed_options
from spectrace.plugins import generated_sources

HINT_REFUSAL = "unsupported vec type hint"


@pytest.mark.parametrize(("value", "defined"), [("1", True), ("", False), ("0", False)])
def test_the_variable_adds_a_define_that_keys_the_build(monkeypatch, value, defined):
    monkeypatch.setenv(VECTORISE_VARIABLE, value)
    defines = _with_contract(None)
    assert (VECTORISE_VARIABLE in defines) is defined
    assert (f"-D {VECTORISE_VARIABLE}=1" in keyed_options(defines, None)) is defined


def test_intel_keeps_its_vectoriser_off_only_while_the_hint_is_there(device, monkeypatch):
    if "intel" not in device.report.runtime.lower() or device.report.device_type != "CPU":
        pytest.skip("the build log's vectoriser lines are Intel's CPU compiler's")
    logs = {}
    for value in ("", "1"):
        monkeypatch.setenv(VECTORISE_VARIABLE, value)
        program = device.build_program("testing/sampler_draws.cl", generated=generated_sources(), from_source=True)
        logs[value] = program.get_build_info(device.cl_device, cl.program_build_info.LOG)
    assert HINT_REFUSAL in logs[""]
    assert HINT_REFUSAL not in logs["1"]
