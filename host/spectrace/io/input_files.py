"""The check shared by every reader of a file named in user input (scene, spectrum, display, mesh, image,
checkpoint): only regular files are read.

A named pipe, a device or a socket given where a file belongs would make a reader wait forever (a FIFO with no
writer) or read without end (/dev/zero, /dev/urandom), so they are refused before anything opens them.
"""

import os
import stat
from pathlib import Path

from spectrace.errors import SpectraceError

_SPECIAL_KINDS = (
    (stat.S_ISFIFO, "a named pipe (FIFO)"),
    (stat.S_ISCHR, "a character device"),
    (stat.S_ISBLK, "a block device"),
    (stat.S_ISSOCK, "a socket"),
)


def regular_file(path: str | Path, where: str | None = None, what: str = "file") -> Path:
    """`path` when it names a regular file (links followed); otherwise a SpectraceError saying whether it is
    missing, a folder, or a pipe, device or socket. `what` is the file's role ("mesh file", "image"). With
    `where` (a scene key) the message quotes the path; without, the path itself is the place named."""
    path = Path(path)
    subject = what if where is None else f"{what} '{path}'"
    where = str(path) if where is None else where
    try:
        mode = os.stat(path).st_mode
    except FileNotFoundError:
        raise SpectraceError(f"{subject} does not exist", where=where) from None
    except OSError as error:
        raise SpectraceError(f"cannot read {subject} ({error.strerror or error})", where=where) from None
    except ValueError:  # no system call takes a name with a NUL character in it
        raise SpectraceError(f"{subject} has a NUL character in its name", where=where) from None
    if stat.S_ISDIR(mode):
        raise SpectraceError(f"{subject} is a folder, not a file", where=where)
    for test, kind in _SPECIAL_KINDS:
        if test(mode):
            raise SpectraceError(f"{subject} is {kind}, not a regular file", where=where)
    if not stat.S_ISREG(mode):
        raise SpectraceError(f"{subject} is not a regular file", where=where)
    return path


def is_regular_file(path: str | Path) -> bool:
    """Whether `path` names a regular file, as a yes or no even for a name the system refuses to look up (too
    long, a NUL byte, a loop of links), where Path.is_file raises."""
    try:
        return stat.S_ISREG(os.stat(path).st_mode)
    except (OSError, ValueError):
        return False
