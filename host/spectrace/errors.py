"""The project's own error type: every user-facing failure is one of these, shown as one line."""


def one_line(text: str) -> str:
    """`text` with every character Python does not count as printable written as an escape (a newline as \\n), so
    it prints as one line: line breaks and other controls (in a file name, say) would split the line or move the
    cursor (NEL, U+0085, and the Unicode line separators break lines too), and invisible ones would hide."""
    if text.isprintable():
        return text
    return "".join(c if c.isprintable() else repr(c)[1:-1] for c in text)


class SpectraceError(Exception):
    """A failure the user can act on; its message is a single line meant for the terminal.

    `where` names the file and key path (``scene.toml: shapes[2].material``) when the fault lies in input.
    """

    def __init__(self, message: str, where: str | None = None):
        self.message = message
        self.where = where
        super().__init__(one_line(f"{where}: {message}" if where else message))


class SpectraceWarning(UserWarning):
    """Something the user may not have meant that spectrace goes on with (a scene in which nothing emits); the
    Python API warns with it, the command line prints it as one "warning:" line."""
