"""The kernels compile for a GPU: no GPU driver has built them, and a CPU runtime accepts constructs a GPU compiler
may reject. clang's OpenCL front end checks every kernel file as OpenCL C 1.2 (target spir64, syntax and semantics),
and clang's NVPTX back end compiles the render, wavefront and meter kernels to PTX, with the same generated headers
and host/device contract the renderer's builds get, for each sampler, with and without spectral bands. Skips where no
clang with the NVPTX target is installed (Debian: `apt-get install clang-19`; .ci/run installs it)."""

import itertools
import re
import shutil
import subprocess
from pathlib import Path

import pytest

from spectrace import resources
from spectrace.device.program_cache import _with_contract, build_options
from spectrace.engine.renderer import sampler_defines
from spectrace.film.state import spectral_defines
from spectrace.geometry.bvh4 import traversal_defines
from spectrace.integrators import INTEGRATORS
from spectrace.plugins import generated_sources
from spectrace.scene.model import SAMPLER_TYPES

pytestmark = [pytest.mark.slow, pytest.mark.subprocess]

RENDER_ENTRIES = [program for plugin in INTEGRATORS.values() for program in plugin.PROGRAMS.values()]


def _clang() -> str | None:
    for name in ("clang-19", "clang-20", "clang-18", "clang-17", "clang"):
        path = shutil.which(name)
        if path is None:
            continue
        targets = subprocess.run([path, "--print-targets"], capture_output=True, text=True, timeout=60).stdout
        if "nvptx64" in targets:
            return path
    return None


CLANG = _clang()
needs_clang = pytest.mark.skipif(CLANG is None, reason="no clang with the NVPTX target (apt-get install clang-19)")


def _options(tmp_path: Path, defines: dict) -> list[str]:
    generated = generated_sources()
    for name, text in generated.headers.items():
        (tmp_path / name).write_text(text)
    return build_options(resources.kernels_dir(), _with_contract(defines, generated), None, tmp_path).split()


def _compile(target: list[str], entry: str, options: list[str]) -> None:
    assert CLANG is not None
    command = [CLANG, "-x", "cl", *target, "-Xclang", "-finclude-default-header", *options]
    result = subprocess.run(
        [*command, str(resources.kernels_dir() / entry)], capture_output=True, text=True, timeout=300
    )
    errors = [line for line in result.stderr.splitlines() if "error" in line]
    assert result.returncode == 0 and not errors, f"{entry} ({' '.join(target)}): " + "\n".join(errors[:10])


def _program_files() -> list[str]:
    """Every .cl file that no other includes: the files programs are built from (the rest are read through them,
    some as templates that need their includer's macros). A BSDF built on another's functions (the coated BSDFs on
    the dielectric's, through layered.cl) is read only through the generated material list, which orders it after
    that BSDF; a file it includes says so with an `#error "... included first"`: such files are built through the
    programs' entries (integrator_path.cl's list holds every registered BSDF), not alone."""
    root = resources.kernels_dir()
    files = {p.relative_to(root).as_posix(): p.read_text() for p in root.rglob("*.cl")}
    included = set(re.findall(r'#include\s+"([^"]+)"', "\n".join(files.values())))

    def needs_an_includer(name: str) -> bool:
        reads = [files[name]] + [files.get(i, "") for i in re.findall(r'#include\s+"([^"]+)"', files[name])]
        return any(re.search(r'#error\s+"[^"]*included first', text) for text in reads)

    return sorted(name for name in files if name not in included and not needs_an_includer(name))


@needs_clang
def test_every_kernel_file_is_opencl_c_1_2_for_a_generic_gpu_target(tmp_path):
    entries = _program_files()
    assert "integrator_path.cl" in entries and "testing/bsdf.cl" in entries
    options = _options(tmp_path, traversal_defines())
    for entry in entries:
        _compile(["-target", "spir64", "-fsyntax-only"], entry, options)


# Each sampler once and each film once, paired off rather than crossed: the sampler's code and the film's bands are
# apart in the kernels (a pair of them has no code of its own), and each pair costs a PTX build of every render
# entry (20-25 s).
_SAMPLER_AND_BANDS = list(zip(SAMPLER_TYPES, itertools.cycle([0, 16])))


@needs_clang
@pytest.mark.parametrize(("sampler", "bands"), _SAMPLER_AND_BANDS)
def test_render_kernels_compile_to_ptx(tmp_path, sampler, bands):
    defines = sampler_defines(sampler) | traversal_defines() | spectral_defines(bands, (360.0, 830.0))
    options = _options(tmp_path, defines)
    for entry in RENDER_ENTRIES:
        _compile(["-target", "nvptx64-nvidia-cuda", "-O2", "-S", "-o", str(tmp_path / "out.ptx")], entry, options)


@needs_clang
def test_meter_kernels_compile_to_ptx(tmp_path):
    options = _options(tmp_path, traversal_defines())
    _compile(["-target", "nvptx64-nvidia-cuda", "-O2", "-S", "-o", str(tmp_path / "out.ptx")], "meters.cl", options)


@needs_clang
@pytest.mark.parametrize("width, quantised", [(4, False), (8, True)])
def test_other_traversals_compile_to_ptx(tmp_path, width, quantised):
    """The traversals the renders do not use by default (bvh4.py TRAVERSAL_WIDTH, QUANTISED_NODES) build too."""
    options = _options(tmp_path, traversal_defines(width, quantised))
    for entry in ["testing/closest_hit.cl", "integrator_path.cl"]:
        _compile(["-target", "nvptx64-nvidia-cuda", "-O2", "-S", "-o", str(tmp_path / "out.ptx")], entry, options)
