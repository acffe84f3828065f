"""The radiometry validation cases: every law holds within 4 standard errors of the renderer's estimate.

The analytic side of each case is the closed-form law (E = Φ cos θ / 4πr², E = kπ, Φ = πLA, ...), computed
independently of the renderer; the measured side comes from the renderer's sensors and images."""

import json
import os
import subprocess
import sys

import pytest

from spectrace.validation import CASES, run_validation


@pytest.mark.parametrize("case", list(CASES))
def test_law_holds(device, case):
    checks = run_validation([case], device)
    assert checks
    for check in checks:
        assert check.passed is not False, check.as_dict()


def test_validate_command_reports_every_case():
    result = subprocess.run([sys.executable, "-m", "spectrace", "validate", "--case", "inverse-square", "--case",
                             "flux", "--json"], capture_output=True, text=True, env=os.environ.copy(), timeout=600)
    assert result.returncode == 0, result.stderr
    checks = json.loads(result.stdout)["checks"]
    assert {c["case"] for c in checks} == {"point light", "flux meter"}
    assert all(c["passed"] for c in checks)
