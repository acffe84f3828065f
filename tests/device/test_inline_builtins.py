"""PoCL from PyPI cannot inline its own builtins, so its builds include inline twins of the hot ones
(kernels/pocl_inline_builtins.h, spectrace.device.builtin_inlining). The twins must give PoCL's bits: each is run
against the builtin it replaces on values at the edges of their arithmetic (signed zeros, subnormals, squares that
underflow or overflow, infinities, NaN), on every PoCL here, and a render must not change by a bit."""

import numpy as np
import pyopencl as cl
import pytest

from spectrace.device import discover_devices, open_device
from spectrace.device.builtin_inlining import INLINE_BUILTINS, runtime_defines, source_prelude
from spectrace.device.report import DeviceReport
from spectrace.engine.renderer import Renderer
from spectrace.plugins import generated_sources
from spectrace.resources import scenes_dir
from spectrace.scene import load_scene

OUTPUTS = 20  # INLINE_BUILTIN_OUTPUTS of kernels/testing/inline_builtins.cl
ITEMS = 4096
GROUP = 64


def _report(key: str) -> DeviceReport:
    return DeviceReport(key, "", "", "", "", "CPU", "", 1, 0, True, None)


@pytest.mark.parametrize(
    ("key", "variable", "defined"),
    [
        ("pocl-pypi:cpu:0", "", True),
        ("pocl-system:cpu:0", "", False),
        ("intel-cpu:cpu:0", "", False),
        ("pocl-pypi:cpu:0", "0", False),
        ("pocl-system:cpu:0", "1", True),
        ("intel-cpu:cpu:0", "1", False),
    ],
)
def test_the_twins_are_built_where_the_runtime_calls_its_builtins(monkeypatch, key, variable, defined):
    monkeypatch.setenv(INLINE_BUILTINS, variable)
    defines = runtime_defines(_report(key))
    assert (INLINE_BUILTINS in defines) is defined
    assert ("pocl_inline_builtins.h" in source_prelude(defines)) is defined


def _pocl_keys() -> list[str]:
    keys: dict[str, str] = {}
    for report in discover_devices():
        runtime = report.key.split(":")[0]
        if report.ok and runtime.startswith("pocl") and report.device_type == "CPU":
            keys.setdefault(runtime, report.key)
    return list(keys.values())


def _edge_inputs(rng: np.random.Generator) -> np.ndarray:
    """(3, ITEMS, 4) float32: x, y, z of every item, drawn from values where the builtins' arithmetic has edges."""
    specials = np.array(
        [0.0, -0.0, 1.0, -1.0, 0.5, 1e-45, -1e-45, 1e-40, 1.2e-38, 1e-20, -1e-20, 1e19, 1e20, -1e25, 3e38, -3e38]
        + [np.inf, -np.inf, np.nan, 2.0**-70, 2.0**64, 1.5, -2.5, 7.0, 1e-30],
        dtype=np.float32,
    )
    values = np.where(
        rng.random((3, ITEMS, 4)) < 0.4,
        rng.choice(specials, size=(3, ITEMS, 4)),
        (rng.standard_normal((3, ITEMS, 4)) * 10.0 ** rng.integers(-25, 25, size=(3, ITEMS, 4))),
    )
    return values.astype(np.float32)


def _run_builtins(device, inputs: np.ndarray) -> np.ndarray:
    program = device.build_program("testing/inline_builtins.cl", generated=generated_sources())
    flags = cl.mem_flags.READ_ONLY | cl.mem_flags.COPY_HOST_PTR
    buffers = [cl.Buffer(device.context, flags, hostbuf=np.ascontiguousarray(part)) for part in inputs]
    out = np.zeros((ITEMS, OUTPUTS, 4), np.float32)
    out_buffer = cl.Buffer(device.context, cl.mem_flags.WRITE_ONLY, out.nbytes)
    cl.Kernel(program, "builtin_values")(device.queue, (ITEMS,), (GROUP,), *buffers, out_buffer)
    cl.enqueue_copy(device.queue, out, out_buffer)
    device.queue.finish()
    return out.view(np.uint32)


@pytest.mark.parametrize("key", _pocl_keys() or ["no PoCL"])
def test_the_twins_give_pocls_bits(monkeypatch, key):
    if key == "no PoCL":
        pytest.skip("no working PoCL CPU device here: the twins are built for PoCL only")
    device = open_device(key)
    inputs = _edge_inputs(np.random.default_rng(37))
    found = {}
    for variable in ("0", "1"):
        monkeypatch.setenv(INLINE_BUILTINS, variable)
        found[variable] = _run_builtins(device, inputs)
    library, twins = found["0"], found["1"]
    # A NaN may carry another NaN's payload: where both operands of a sum are NaN the CPU returns the first, and
    # the compiler orders a commutative operation either way. Every other result must match bit for bit.
    both_nan = np.isnan(library.view(np.float32)) & np.isnan(twins.view(np.float32))
    differing = np.argwhere((library != twins) & ~both_nan)
    assert differing.size == 0, (
        f"{len(differing)} values differ, first at item {differing[0][0]}, output {differing[0][1]}: "
        f"inputs {inputs[:, differing[0][0]]}, library {library[tuple(differing[0])]:#x}, "
        f"twin {twins[tuple(differing[0])]:#x}"
    )
    # The inputs reach the edges: some lengths underflowed or overflowed before rescaling, some results are NaN.
    lengths = library[:, 1, 0].view(np.float32)
    assert np.isnan(lengths).any() and np.isinf(lengths).any() and (lengths[np.isfinite(lengths)] < 1e-30).any()


@pytest.mark.slow
def test_a_render_keeps_its_bits_with_the_twins(monkeypatch):
    """On PoCL from PyPI, where the twins are built unasked; other PoCLs are held to them by the test above."""
    key = next((key for key in _pocl_keys() if key.startswith("pocl-pypi:")), None)
    if key is None:
        pytest.skip("PoCL from PyPI (pocl-binary-distribution) is not a working runtime here")
    scene = load_scene(scenes_dir() / "cornell_box.toml").with_overrides(width=16, height=16, max_depth=5, spp=4)
    images = {}
    for variable in ("0", ""):
        monkeypatch.setenv(INLINE_BUILTINS, variable)
        renderer = Renderer(scene, open_device(key))  # builds this setting's program
        renderer.render(spp=4)
        images[variable] = renderer.image().xyz
    assert images["0"].mean() > 1e-3
    assert images["0"].tobytes() == images[""].tobytes()
