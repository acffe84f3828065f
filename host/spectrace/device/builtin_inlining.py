"""Which runtimes build the kernels with inline twins of the hot OpenCL builtins (kernels/pocl_inline_builtins.h).

PoCL from PyPI compiles kernels for the CPU LLVM names but links a kernel library built for a family of CPUs
(haswell, skylake-avx512); LLVM refuses to inline across that difference, so each dot, mad, fmax, any or shuffle stays
a call. On that runtime every program is built with the define below and the header included first, whose twins
give PoCL's own bits (the header says how). ``SPECTRACE_INLINE_BUILTINS=0`` builds without them (to compare),
``=1`` with them on any PoCL; the define keys the program cache, so each choice keeps binaries of its own.
"""

from __future__ import annotations

import os
from collections.abc import Mapping

from spectrace.device.report import DeviceReport

INLINE_BUILTINS = "SPECTRACE_INLINE_BUILTINS"  # the define, and the environment variable of the same name
INLINE_BUILTINS_HEADER = "pocl_inline_builtins.h"
_OUT_OF_LINE_RUNTIMES = ("pocl-pypi",)
_POCL_RUNTIMES = ("pocl-pypi", "pocl-system")


def runtime_defines(report: DeviceReport) -> dict[str, int]:
    """The defines a build for `report`'s device gets for its runtime's sake."""
    runtime = report.key.split(":", 1)[0]
    asked = os.environ.get(INLINE_BUILTINS, "").strip()
    if asked == "0":
        return {}
    wanted = _POCL_RUNTIMES if asked == "1" else _OUT_OF_LINE_RUNTIMES
    return {INLINE_BUILTINS: 1} if runtime in wanted else {}


def source_prelude(defines: Mapping[str, object]) -> str:
    """What a program's source says before its entry: the twins' header where the build defines them."""
    return f'#include "{INLINE_BUILTINS_HEADER}"\n' if defines.get(INLINE_BUILTINS) else ""
