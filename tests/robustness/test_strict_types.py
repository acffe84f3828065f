"""Values of the wrong type are refused, not converted: a command-line number written with a digit separator
('0_2'), as a float where a whole number belongs ('16.0'), as NaN or infinity, or as a word; a scene file's boolean
where a number belongs (`width = true`) and a number where a boolean belongs. One line naming the option or the file
and key, exit status 2.
"""

import typing

import pytest
import typer

from cli_runner import run_here, run_in_process, run_spectrace
from scene_text import glowing_rectangle
from spectrace import cli
from spectrace.cli.common import strict_number_options


def _numeric_options() -> list[tuple[tuple[str, ...], str, type]]:
    """(command path, option, int or float) for every option of every command that takes numbers."""
    found = []

    def walk(command, path):
        for param in command.params:
            annotation = getattr(getattr(param, "type_descriptor", None), "annotation", None)
            items = typing.get_args(annotation) if typing.get_origin(annotation) in (list, tuple) else (annotation,)
            kinds = {item for item in items if item in (int, float)}
            if kinds and param.opts[0].startswith("--"):
                found.append((path, param.opts[0], kinds.pop(), param.nargs))
        for name, sub in getattr(command, "commands", {}).items():
            walk(cli._load_command(name) if not path and name in cli.LAZY_COMMANDS else sub, (*path, name))

    walk(typer.main.get_command(cli.app), ())
    return found


NUMERIC_OPTIONS = _numeric_options()


def test_the_walk_finds_the_options_of_several_commands():
    names = {f"{' '.join(path)} {option}" for path, option, _, _ in NUMERIC_OPTIONS}
    assert {"render --spp", "render --exposure", "bench quality --seconds", "display compare --rgb"} <= names


@pytest.mark.parametrize(
    ("path", "option", "kind", "nargs"),
    NUMERIC_OPTIONS,
    ids=[f"{' '.join(p)}{o}" for p, o, _, _ in NUMERIC_OPTIONS],
)
def test_every_number_option_refuses_a_digit_separator(path, option, kind, nargs, monkeypatch, capsys):
    # Refused while the options are read, before any argument is checked or anything runs.
    status, stderr = run_in_process(monkeypatch, capsys, [*path, option, *(["1_0"] * nargs)])
    assert status == 2 and stderr.count("\n") == 1, stderr
    assert stderr.startswith(f"error: {option}: must be a "), stderr
    assert "'_' is not a digit separator here" in stderr


@pytest.mark.parametrize(
    ("argv", "says"),
    [
        (("--spp", "16.0"), "error: --spp: must be a whole number, got '16.0'"),
        (("--spp", "true"), "error: --spp: must be a whole number, got 'true'"),
        (("--spp", "１６"), "error: --spp: must be a whole number, got '１６'"),
        (("--width", "0x10"), "error: --width: must be a whole number, got '0x10'"),
        (("--exposure", "nan"), "error: --exposure: must be a finite number, got nan"),
        (("--exposure", "-inf"), "error: --exposure: must be a finite number, got -inf"),
        (("--exposure", "1e999"), "error: --exposure: must be a finite number, got 1e999"),
        (("--checkpoint-interval", "Infinity"), "error: --checkpoint-interval: must be a finite number"),
        (("--filter", "gaussian:stddev=0_2"), "error: --filter: stddev must be a number, got '0_2'"),
        (("--filter", "mitchell:b=nan"), "error: --filter: b must be a finite number, got nan"),
        (("--filter", "tent:radius=1_5"), "error: --filter: radius must be a number, got '1_5'"),
    ],
)
def test_render_options_refuse_what_python_would_convert(argv, says, tmp_path, monkeypatch, capsys):
    scene = tmp_path / "scene.toml"
    scene.write_text(glowing_rectangle())
    status, stderr = run_in_process(monkeypatch, capsys, ["render", str(scene), "-o", str(tmp_path / "o.png"), *argv])
    assert status == 2 and stderr.count("\n") == 1, stderr
    assert stderr.startswith(says), stderr
    assert list(tmp_path.iterdir()) == [scene]


@pytest.mark.parametrize("text", ["3_200K", "0_3,0.3"])
def test_a_white_balance_with_a_digit_separator_is_no_temperature_or_chromaticity(text):
    from spectrace.errors import SpectraceError
    from spectrace.film.colour_output import parse_white_balance

    with pytest.raises(SpectraceError, match="unknown white"):
        parse_white_balance(text)


def test_numbers_written_plainly_still_pass():
    """The strict reading refuses only what is not a plain number: signs, points and exponents pass."""
    from spectrace.number_text import integer_problem, number_problem

    assert [integer_problem(t) for t in ("0", "-1", "+16", "2147483647")] == [None] * 4
    assert [number_problem(t) for t in ("0.2", "-1", ".5", "5.", "1e-3", "+2E+2")] == [None] * 6


def test_strictness_is_applied_once():
    command = typer.main.get_command(cli.app).commands["render"]
    strict_number_options(command)
    wrapped = {param.name: param.process_value for param in command.params}
    strict_number_options(command)
    assert {param.name: param.process_value for param in command.params} == wrapped


# ---------------------------------------------------------------- real processes


@pytest.mark.subprocess
def test_a_real_process_refuses_a_filter_with_a_digit_separator(tmp_path):
    scene = tmp_path / "scene.toml"
    scene.write_text(glowing_rectangle())
    result = run_spectrace("render", str(scene), "-o", str(tmp_path / "o.png"), "--filter", "gaussian:stddev=0_2")
    assert result.returncode == 2 and result.stdout == "", result.stderr
    assert result.stderr == "error: --filter: stddev must be a number, got '0_2' ('_' is not a digit separator here)\n"
    assert list(tmp_path.iterdir()) == [scene]


@pytest.mark.parametrize(
    ("old", "new", "where", "says"),
    [
        ("width = 8", "width = true", "film.width", "expected a whole number, got true"),
        (
            "[film]",
            "[integrator]\nmax_depth = true\n\n[film]",
            "integrator.max_depth",
            "expected a whole number, got true",
        ),
        ("[film]", '[sampler]\nspp = "4"\n\n[film]', "sampler.spp", "expected a whole number, got '4'"),
        ("[film]", "[sampler]\nspp = 4.0\n\n[film]", "sampler.spp", "expected a whole number, got 4.0"),
        ("fov = 40", 'fov = "40"', "camera.fov", "expected a number, got '40'"),
        (
            'type = "rectangle"',
            'type = "rectangle"\nface_normals = 1',
            "shapes[0].face_normals",
            "expected true or false, got 1",
        ),
    ],
)
def test_the_file_and_key_of_a_wrongly_typed_value_are_named(old, new, where, says, tmp_path):
    _check_wrongly_typed_value(run_here, old, new, where, says, tmp_path)


@pytest.mark.subprocess
def test_a_real_process_names_the_file_and_key_of_a_wrongly_typed_value(tmp_path):
    _check_wrongly_typed_value(
        run_spectrace, "width = 8", "width = true", "film.width", "expected a whole number, got true", tmp_path
    )


def _check_wrongly_typed_value(run, old, new, where, says, tmp_path):
    text = glowing_rectangle()
    assert old in text
    scene = tmp_path / "scene.toml"
    scene.write_text(text.replace(old, new, 1))
    result = run("render", str(scene), "-o", str(tmp_path / "o.png"))
    assert result.returncode == 2 and result.stdout == "", result.stderr
    assert result.stderr.count("\n") == 1 and "Traceback" not in result.stderr, result.stderr
    assert result.stderr.startswith(f"error: {scene}: {where}: "), result.stderr
    assert says in result.stderr, result.stderr
    assert list(tmp_path.iterdir()) == [scene]
