"""The radiometry validation cases: every law holds within 4 standard errors of the renderer's estimate.

The analytic side of each case is the closed-form law (E = Φ cos θ / 4πr², E = kπ, Φ = πLA, ...), computed
independently of the renderer; the measured side comes from the renderer's sensors and images."""

import json

import numpy as np
import pytest

from cli_runner import run_here
from spectrace.validation import CASES, prism_deviation_degrees, prism_window_centre_degrees, run_validation

SLOW_CASES = {"dispersion", "medium-furnace"}  # over 5 s each on a loaded two-core machine


@pytest.mark.parametrize("case", [pytest.param(c, marks=pytest.mark.slow) if c in SLOW_CASES else c for c in CASES])
def test_law_holds(device, case):
    checks = run_validation([case], device)
    assert checks
    for check in checks:
        assert check.passed is not False, check.as_dict()


def test_validate_command_reports_every_case():
    """What the command writes and its status (a process's own exit is other commands' tests')."""
    result = run_here("validate", "--case", "inverse-square", "--case", "flux", "--json")
    assert result.returncode == 0, result.stderr
    checks = json.loads(result.stdout)["checks"]
    assert {c["case"] for c in checks} == {"point light", "flux meter"}
    assert all(c["passed"] for c in checks)


@pytest.mark.parametrize("n", [1.5168, 1.78472])
def test_prism_deviation_meets_the_minimum_deviation_formula(n):
    """The dispersion case's analytic side: at the symmetric passage, sin θ1 = n sin(A/2), the deviation is the
    textbook minimum 2θ1 − A, and any other incidence deviates more; a vanishing source's window centre is δ."""
    theta1 = np.degrees(np.arcsin(n * np.sin(np.radians(30.0))))
    minimum = prism_deviation_degrees(n, theta1)
    assert minimum == pytest.approx(2 * theta1 - 60.0, abs=1e-9)
    assert prism_deviation_degrees(n, theta1 - 1.0) > minimum < prism_deviation_degrees(n, theta1 + 1.0)
    assert prism_window_centre_degrees(n, theta1 + 5.0, 1e-4) == pytest.approx(
        prism_deviation_degrees(n, theta1 + 5.0), abs=1e-7
    )
