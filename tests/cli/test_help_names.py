"""Help texts name their choices as a user types them, and the names written out there are the registries'."""

import re

import pytest

from cli_runner import run_spectrace


def test_bench_names_the_integrators_of_the_registry():
    from spectrace.cli.bench import INTEGRATOR_NAMES
    from spectrace.integrators import INTEGRATORS

    assert re.split(r", | or ", INTEGRATOR_NAMES) == list(INTEGRATORS)


@pytest.mark.subprocess
def test_bench_help_shows_the_names_not_a_python_path():
    result = run_spectrace("bench", "--help")
    assert result.returncode == 0, result.stderr
    text = " ".join(result.stdout.split())
    assert "spectrace.integrators" not in text and "INTEGRATOR" not in text
    assert all(name in text for name in ("path", "direct", "light", "bdpt", "sppm"))
