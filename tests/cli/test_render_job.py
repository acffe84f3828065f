"""`spectrace render` and `spectrace.render` check a render's settings in one place (spectrace.engine.job.RenderJob):
a wrong setting gets the same one-line message from both, before a device opens and before any file is touched,
named as each front end spells it (the option on the command line; in Python the message names the argument)."""

import pytest

import spectrace
from cli_runner import render_cornell_box, run_here
from spectrace.errors import SpectraceError
from spectrace.resources import scenes_dir

EARLIER = b"an earlier image"

# (command-line options, spectrace.render's arguments, where the command line names it, where Python does)
WRONG_SETTINGS = {
    "spp-over-the-limit": (["--spp", "2000000"], {"spp": 2_000_000}, "--spp", None),
    "bands-finer-than-the-grid": (["--spectral-bins", "1000"], {"spectral_bins": 1000}, "--spectral-bins", None),
    "unknown-aov": (["--aov", "albedo,bogus"], {"aovs": "albedo,bogus"}, "--aov", "aovs"),
    "unknown-colour-space": (
        ["--colour-space", "prophoto"],
        {"colour_space": "prophoto"},
        "--colour-space",
        "colour_space",
    ),
    "white-beyond-black-bodies": (
        ["--white-balance", "200K"],
        {"white_balance": "200K"},
        "--white-balance",
        "white_balance",
    ),
    "unknown-adaptation": (
        ["--white-balance", "D50", "--adaptation", "cat02"],
        {"white_balance": "D50", "adaptation": "cat02"},
        "--adaptation",
        "adaptation",
    ),
}


@pytest.fixture
def no_device(monkeypatch):
    """Fails the test if the Python render gets as far as opening a device."""
    import spectrace.engine.renderer as renderer

    def refuse(*args, **kwargs):
        raise AssertionError("a device was opened for a setting that should have been refused")

    monkeypatch.setattr(renderer, "open_device", refuse)


def _python_refusal(arguments: dict) -> SpectraceError:
    scene = spectrace.load_scene(scenes_dir() / "cornell_box.toml").with_overrides(width=8, height=6)
    with pytest.raises(SpectraceError) as raised:
        spectrace.render(scene, progress=False, **arguments)
    return raised.value


@pytest.mark.parametrize(("options", "arguments", "option", "argument"), WRONG_SETTINGS.values(), ids=WRONG_SETTINGS)
def test_a_wrong_setting_gets_one_message_from_the_command_line_and_from_python(
    tmp_path, no_device, options, arguments, option, argument
):
    out = tmp_path / "out.exr"
    out.write_bytes(EARLIER)
    result = run_here(*render_cornell_box(out, 2, 8, 6), *options, "-q")  # the command, in this process
    assert result.returncode == 2, result.stderr
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"error: {option}: "), result.stderr
    assert out.read_bytes() == EARLIER  # refused before anything was written

    refusal = _python_refusal(arguments)
    assert refusal.where == argument
    assert lines[0] == f"error: {option}: {refusal.message}"
