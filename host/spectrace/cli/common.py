"""What the commands share: the message console (stderr), the settings of every command group and the options
several of them take."""

import importlib
import os
import sys
import typing
from typing import Annotated, Any

import typer
from typer.core import TyperCommand

# Help in click's plain layout rather than typer's rich panels: rendering those imports rich's markdown, syntax and
# traceback modules, about a third of `spectrace --help`'s whole run. No shell-completion commands, no rich
# tracebacks (errors are one line, cli/__init__.py).
GROUP_SETTINGS: dict[str, Any] = {"add_completion": False, "pretty_exceptions_enable": False, "rich_markup_mode": None}


def help_flag_defaulting_to_false(option: Any) -> Any:
    """The --help option of a command or group, with False rather than None as its value when not given. typer passes
    a flag's bool straight on but sends None through its pydantic-based coercion, and importing pydantic is then the
    largest part of a `spectrace devices` that has nothing else to do (0.18 s measured). The help is the same."""
    if option is not None and option.default is None:
        option.default = False
    return option


class PlainHelpFlagCommand(TyperCommand):
    """A command whose --help flag does not load pydantic when absent (help_flag_defaulting_to_false)."""

    def get_help_option(self, ctx: Any) -> Any:
        return help_flag_defaulting_to_false(super().get_help_option(ctx))


# Help printed to a pipe or a file: click would assume 80 columns when no terminal says otherwise.
PIPED_HELP_COLUMNS = 120


def help_width() -> int | None:
    """COLUMNS when set, else wide enough for the option tables when stdout is no terminal; None (the terminal's own
    width) otherwise."""
    if columns := os.environ.get("COLUMNS", "").strip():
        return int(columns) if columns.isdigit() and int(columns) > 0 else None
    return None if sys.stdout.isatty() else PIPED_HELP_COLUMNS


class _MessageConsole:
    """Messages on stderr: plain lines until something needs rich's Console (a progress bar asks for it with
    `rich()`), then through that Console, so that a message printed while a bar is drawn does not tear it. Importing
    rich costs more than a small render's messages are worth."""

    _console: Any = None
    # -q: what a command says about its work (device, scene, files written, notes) is left out; warnings and errors
    # still print.
    quiet = False

    def rich(self) -> Any:
        """The Console itself, for what keeps it (a progress bar)."""
        if _MessageConsole._console is None:
            from rich.console import Console

            _MessageConsole._console = Console(stderr=True, soft_wrap=True, markup=False)  # long paths: one line
        return _MessageConsole._console

    def print(self, *objects: Any, sep: str = " ", end: str = "\n", **options: Any) -> None:
        """Like Console.print for plain text (messages are never markup, never highlighted, one line each)."""
        if _MessageConsole._console is not None:
            _MessageConsole._console.print(*objects, sep=sep, end=end, **options)
        else:
            print(*objects, sep=sep, end=end, file=sys.stderr, flush=True)

    def say(self, text: str) -> None:
        """A message about the command's work: printed unless -q asked for warnings and errors only."""
        if not self.quiet or text.startswith(("warning:", "error:")):
            self.print(text, highlight=False, markup=False)

    def __getattr__(self, name: str) -> Any:
        return getattr(self.rich(), name)


console: Any = _MessageConsole()

DeviceOption = Annotated[
    str | None,
    typer.Option("--device", "-d", help="Device key or substring (see `spectrace devices`); env SPECTRACE_DEVICE."),
]
JsonOption = Annotated[bool, typer.Option("--json", help="One JSON object on stdout.")]


def click_exceptions() -> Any:
    """Click's exceptions module: recent typer versions carry their own copy of click."""
    try:
        return importlib.import_module("typer._click.exceptions")
    except ImportError:
        return importlib.import_module("click.exceptions")


def _number_kind(param: Any) -> type | None:
    """int or float when `param` takes whole numbers or numbers (alone, or as the items of a list or tuple)."""
    descriptor = getattr(param, "type_descriptor", None)
    if descriptor is not None:  # typer's own conversion, from the annotation
        annotation = descriptor.annotation
        items = typing.get_args(annotation) if typing.get_origin(annotation) in (list, tuple) else (annotation,)
        kinds = {item for item in items if item in (int, float)}
        return kinds.pop() if len(kinds) == 1 else None
    name = type(getattr(param, "type", None)).__name__  # typer releases that convert with click's types
    return int if name in ("IntParamType", "IntRange") else float if name in ("FloatParamType", "FloatRange") else None


def strict_number_options(command: Any) -> Any:
    """`command` (and its sub-commands) with every whole-number and number option reading its text as
    spectrace.number_text does: typer and click convert with int() and float() or pydantic's lax parsing, which take
    '0_2' as 2, '16.0' as an integer and 'nan' or 'inf' as numbers. The option's own range check follows."""
    from spectrace.number_text import integer_problem, number_problem

    for param in getattr(command, "params", ()):
        kind = _number_kind(param)
        if kind is None or getattr(param, "_strict_numbers", False):
            continue
        problem_of = integer_problem if kind is int else number_problem

        def process_value(ctx: Any, value: Any, param: Any = param, problem_of=problem_of, convert=param.process_value):
            for text in value if isinstance(value, (list, tuple)) else (value,):
                if isinstance(text, str) and (problem := problem_of(text)):
                    raise click_exceptions().BadParameter(problem, ctx=ctx, param=param)
            return convert(ctx, value)

        param.process_value = process_value
        param._strict_numbers = True
    for sub_command in getattr(command, "commands", {}).values():
        strict_number_options(sub_command)
    return command
