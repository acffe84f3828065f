"""The project's own error type: every user-facing failure is one of these, shown as one line."""

import re

# Line breaks and other control characters (in a file name, say) would split the line or move the cursor: the C0
# and C1 controls (NEL, U+0085, is a line break to Python and many terminals) and the Unicode line separators.
_CONTROL = re.compile("[\x00-\x1f\x7f-\x9f\u2028\u2029]")


def one_line(text: str) -> str:
    """`text` with control characters written as escapes (a newline as \\n), so it prints as one line."""
    return _CONTROL.sub(lambda match: repr(match.group())[1:-1], text)


class SpectraceError(Exception):
    """A failure the user can act on; its message is a single line meant for the terminal.

    `where` names the file and key path (``scene.toml: shapes[2].material``) when the fault lies in input.
    """

    def __init__(self, message: str, where: str | None = None):
        self.message = message
        self.where = where
        super().__init__(one_line(f"{where}: {message}" if where else message))
