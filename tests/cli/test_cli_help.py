"""`spectrace --help` and every subcommand's help are complete: each command and each of its options and arguments
says what it does."""

import os
import subprocess
import sys

import pytest
import typer.main
from typer.testing import CliRunner

from cli_runner import run_spectrace
from spectrace.cli import app


def _commands(command, path):
    yield path, command
    for name, sub in (getattr(command, "commands", None) or {}).items():
        yield from _commands(sub, [*path, name])


ALL_COMMANDS = list(_commands(typer.main.get_command(app), []))


def test_every_command_and_parameter_has_help():
    missing = []
    for path, command in ALL_COMMANDS:
        if not (command.help or "").strip():
            missing.append(" ".join(path) or "spectrace")
        missing += [
            f"{' '.join(path)} {param.name}"
            for param in command.params
            if not (getattr(param, "help", None) or "").strip()
        ]
    assert not missing, missing


def test_help_of_every_command_prints():
    runner = CliRunner()
    for path, _command in ALL_COMMANDS:
        result = runner.invoke(app, [*path, "--help"])
        assert result.exit_code == 0, (path, result.output)
        assert "Usage" in result.output


@pytest.mark.subprocess
def test_top_level_help_lists_every_command():
    result = subprocess.run(
        [sys.executable, "-m", "spectrace", "--help"],
        capture_output=True,
        text=True,
        env={**os.environ, "COLUMNS": "200"},
        timeout=600,
    )
    assert result.returncode == 0, result.stderr
    for path, _ in ALL_COMMANDS:
        if len(path) == 1:
            assert path[0] in result.stdout


@pytest.mark.subprocess
@pytest.mark.parametrize("group", [[], ["spectra"], ["display"]])
@pytest.mark.slow
def test_a_group_without_a_command_prints_its_help(group):
    result = run_spectrace(*group)
    assert result.returncode == 2
    assert "Usage" in result.stderr and "Commands" in result.stderr, result.stderr
