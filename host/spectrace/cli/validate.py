"""`spectrace validate`: the laws of radiometry checked numerically against the renderer."""

import json
from typing import Annotated

import typer

from spectrace.cli.common import DeviceOption, JsonOption, console
from spectrace.errors import SpectraceError


def validate(
    case: Annotated[list[str] | None, typer.Option(help="Run only these cases (default: all).")] = None,
    device: DeviceOption = None,
    as_json: JsonOption = False,
    quiet: Annotated[bool, typer.Option("--quiet", "-q", help="No progress bar.")] = False,
) -> None:
    """Check the laws of radiometry numerically: each law, its analytic value, the renderer's measurement ±
    its standard error, and pass/fail (|difference| <= 4 standard errors). Exits 1 if any check fails."""
    from rich.console import Console
    from rich.table import Table

    from spectrace.validation import CASES, run_validation

    unknown = [c for c in case or [] if c not in CASES]
    if unknown:
        raise SpectraceError(f"unknown validation case(s) {', '.join(unknown)}; cases: {', '.join(CASES)}")
    from contextlib import nullcontext

    from spectrace.progress import progress_bar

    count = len(case or CASES)
    bar = nullcontext(None) if quiet else progress_bar(count, 0, console.rich(), unit="cases", label="validating")
    with bar as progress:
        checks = run_validation(case, device, progress=progress)
    if as_json:
        print(json.dumps({"checks": [c.as_dict() for c in checks]}, indent=2))
    else:
        table = Table(title="spectrace validate: the laws of radiometry, measured")
        for column in ("case", "law", "analytic", "measured ± s.e.", "unit", "result"):
            table.add_column(column)
        for c in checks:
            result = {True: "pass", False: "FAIL", None: "(figure)"}[c.passed]
            analytic = "" if c.reported_only else f"{c.analytic:.6g}"
            table.add_row(c.case, c.law, analytic, f"{c.measured:.6g} ± {c.standard_error:.2g}", c.unit, result)
        Console(width=160, markup=False).print(table)
    if any(c.passed is False for c in checks):
        raise typer.Exit(1)
