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


# What one scene's includes may read, all files together, counting a file each time it is included (pbrt's
# Include and Import, Mitsuba's <include>). A file that includes the next several times multiplies at every level
# (ten files each including the next ten times: 10^10 readings), which no depth limit stops in time. Real scenes
# include tens to thousands of files, and their text (inline meshes included) stays far below the byte limit,
# which keeps the parsed text within a workstation's memory (the parsers hold several times the text).
MAX_INCLUDED_FILES = 10_000
MAX_INCLUDED_BYTES = 1 << 30


class Inclusions:
    """One scene's reading of itself and its included files: `enter(path, where)` before a file is read refuses,
    with one line naming the file, a file that includes itself (directly or further down), nesting deeper than
    `max_depth` files, and a scene whose files, counted each time they are read, pass MAX_INCLUDED_FILES or
    MAX_INCLUDED_BYTES; `leave()` when its reading is over. `remaining_bytes()` bounds what a compressed file may
    inflate to."""

    def __init__(self, max_depth: int, directive: str):
        self.max_depth = max_depth
        self.directive = directive  # "Include", "<include>": how messages name the mechanism
        self.stack: list[Path] = []
        self.files = 0
        self.bytes = 0
        self.skipped: list[str] | None = None  # pbrt's missing_assets="placeholder": missing includes told here

    def enter(self, path: Path, where: str, size: int | None = None) -> None:
        """Count `path` (of `size` bytes, else its size on disk) as read once more, after the checks."""
        resolved = path.resolve()
        if resolved in self.stack:
            chain = " -> ".join(p.name for p in [*self.stack[self.stack.index(resolved) :], resolved])
            raise SpectraceError(f"'{path}' includes itself ({chain})", where=where)
        if len(self.stack) > self.max_depth:
            raise SpectraceError(f"'{path}': {self.directive} nested more than {self.max_depth} files deep", where)
        self.files += 1
        if self.files > MAX_INCLUDED_FILES:
            raise SpectraceError(
                f"'{path}': the scene reads more than {MAX_INCLUDED_FILES} files through {self.directive} "
                "(a file counts each time it is included): files that include others several times multiply",
                where=where,
            )
        if size is None:
            try:
                size = path.stat().st_size
            except OSError:
                size = 0  # the reader says why it cannot read the file
        self.charge(path, size, where)
        self.stack.append(resolved)

    def charge(self, path: Path, size: int, where: str) -> None:
        self.bytes += size
        if self.bytes > MAX_INCLUDED_BYTES:
            raise SpectraceError(
                f"'{path}': the scene's files come to more than {MAX_INCLUDED_BYTES >> 20} MiB of text through "
                f"{self.directive} (a file counts each time it is included)",
                where=where,
            )

    def leave(self) -> None:
        self.stack.pop()

    def remaining_bytes(self) -> int:
        return max(0, MAX_INCLUDED_BYTES - self.bytes)
