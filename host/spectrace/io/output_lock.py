"""Advisory locks on the files a command is writing, so that a second command naming one of them (two renders to
the same -o or --checkpoint) is refused at once, told who holds it, instead of the last writer silently winning.

Each lock is a hidden file `.NAME.lock` beside the output (after resolving symbolic links, so that two spellings
of one file share it), locked with flock(2) and holding the holder's pid, host and start time for the message.
The kernel drops a flock when its process ends, however it ends (kill -9 included), so a lock file left behind
by a dead holder is stale by construction: the next command locks it and goes on. A holder removes its lock file
when done; a command that opened the file just before it was removed finds, after locking, that the name no
longer leads to the file it locked, and tries again (otherwise two commands could each lock a different file of
the same name). Where the file system does not take flock (some network mounts), nothing is locked.
"""

from __future__ import annotations

import hashlib
import os
import socket
import time
from collections.abc import Mapping
from pathlib import Path
from types import TracebackType

from spectrace.errors import SpectraceError

try:
    import fcntl
except ImportError:  # Windows: no flock; the outputs are then not locked
    fcntl = None  # type: ignore[assignment]

_NAME_MAX = 255


def lock_path_for(path: Path) -> Path:
    """The lock file of the output `path`: `.NAME.lock` beside the file it names (symbolic links resolved); a
    hash of NAME where that would be longer than a file name may be."""
    real = Path(os.path.realpath(path))
    name = f".{real.name}.lock"
    if len(os.fsencode(name)) > _NAME_MAX:
        name = f".{hashlib.sha256(os.fsencode(real.name)).hexdigest()[:32]}.lock"
    return real.parent / name


def _holder(fd: int) -> str:
    try:
        text = os.pread(fd, 512, 0).decode("utf-8", "replace").strip()
    except OSError:
        text = ""
    return text or "a process that has not yet said which"


def _same_file(fd: int, path: Path) -> bool:
    try:
        named, held = os.stat(path), os.fstat(fd)
    except FileNotFoundError:
        return False
    return (named.st_dev, named.st_ino) == (held.st_dev, held.st_ino)


def _lock(path: Path, option: str, command: str) -> tuple[Path, int] | None:
    """Lock `path` for this process: (its lock file, the descriptor holding it), or None where the file system
    cannot lock; a held lock is a SpectraceError naming the option, the file and the holder."""
    lock = lock_path_for(path)
    while True:
        try:
            fd = os.open(lock, os.O_RDWR | os.O_CREAT | getattr(os, "O_CLOEXEC", 0), 0o644)
        except OSError as error:
            raise SpectraceError(
                f"cannot create the lock file {lock.name} beside {option} ({error.strerror or error})",
                where=str(path),
            ) from None
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            holder = _holder(fd)
            os.close(fd)
            raise SpectraceError(
                f"{option} is being written by another command ({holder}); wait for it to end or choose another "
                f"file (the lock is {lock.name} beside it)",
                where=str(path),
            ) from None
        except OSError:  # no flock here (ENOLCK, EOPNOTSUPP): no lock rather than no render
            os.close(fd)
            return None
        if _same_file(fd, lock):
            break
        os.close(fd)  # its holder removed it between our open and our lock: lock the file now under that name
    started = time.strftime("%Y-%m-%d %H:%M:%S %Z", time.localtime())
    os.ftruncate(fd, 0)
    os.pwrite(fd, f"{command}, pid {os.getpid()} on {socket.gethostname()}, since {started}\n".encode(), 0)
    return lock, fd


class OutputLocks:
    """Context manager holding the locks of several outputs (option -> path; None: not written) from its
    creation until it exits, however that happens (an error, Ctrl-C, SIGTERM or SIGHUP ending the render, a
    second signal's KeyboardInterrupt). A lock that is held elsewhere releases the ones taken and raises."""

    def __init__(self, outputs: Mapping[str, Path | None], command: str = "spectrace") -> None:
        self._held: list[tuple[Path, int]] = []
        if fcntl is None:
            return
        try:
            for option, path in outputs.items():
                if path is not None and (held := _lock(path, option, command)) is not None:
                    self._held.append(held)
        except BaseException:
            self.release()
            raise

    def release(self) -> None:
        """Remove the lock files (while still holding them: see the module's docstring) and let go."""
        while self._held:
            lock, fd = self._held.pop()
            try:
                if _same_file(fd, lock):
                    os.unlink(lock)
            except OSError:
                pass
            finally:
                os.close(fd)

    def __enter__(self) -> OutputLocks:
        return self

    def __exit__(
        self, kind: type[BaseException] | None, error: BaseException | None, traceback: TracebackType | None
    ) -> None:
        self.release()
