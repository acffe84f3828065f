"""What the commands share: the message console (stderr), the settings of every command group and the options
several of them take."""

import os
import sys
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

    def __getattr__(self, name: str) -> Any:
        return getattr(self.rich(), name)


console: Any = _MessageConsole()

DeviceOption = Annotated[
    str | None,
    typer.Option("--device", "-d", help="Device key or substring (see `spectrace devices`); env SPECTRACE_DEVICE."),
]
JsonOption = Annotated[bool, typer.Option("--json", help="One JSON object on stdout.")]
