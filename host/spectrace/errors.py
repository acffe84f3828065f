"""The project's own error type: every user-facing failure is one of these, shown as one line."""


class SpectraceError(Exception):
    """A failure the user can act on; its message is a single line meant for the terminal.

    `where` names the file and key path (``scene.toml: shapes[2].material``) when the fault lies in input.
    """

    def __init__(self, message: str, where: str | None = None):
        self.message = message
        self.where = where
        super().__init__(f"{where}: {message}" if where else message)
