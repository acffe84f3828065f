"""Atomic file output: readers see the old file or the complete new one, never a torn write."""

import os
import stat
import tempfile
from collections.abc import Callable
from pathlib import Path


def _mode_for(path: Path) -> int:
    """The permission bits of the file being replaced, else those of a new file under the process's umask."""
    try:
        return stat.S_IMODE(path.stat().st_mode)
    except OSError:
        umask = os.umask(0)
        os.umask(umask)
        return 0o666 & ~umask


# Characters of the output's stem and suffix kept in a temporary name: any name the file system takes for the
# output then gives a temporary name it takes too (names are limited to 255 bytes, 4 per character at most).
_TEMP_STEM_CHARS = 32
_TEMP_SUFFIX_CHARS = 16


def temporary_name_parts(path: Path, kind: str = "tmp") -> tuple[str, str]:
    """(prefix, suffix) of the hidden temporary files made beside `path` (`.name.XXXXXXXX.tmp.exr`): its suffix
    kept, since some writers choose the format from it, and both cut short for a long name."""
    return f".{path.stem[:_TEMP_STEM_CHARS]}.", f".{kind}{path.suffix[:_TEMP_SUFFIX_CHARS]}"


def write_atomically(path: Path, write: Callable[[Path], object]) -> None:
    """Call write(temp_path) on a temporary file in path's folder, fsync it, then rename it over path."""
    path = Path(path)
    folder = path.parent if str(path.parent) else Path(".")
    folder.mkdir(parents=True, exist_ok=True)
    prefix, suffix = temporary_name_parts(path)
    fd, temp_name = tempfile.mkstemp(prefix=prefix, suffix=suffix, dir=folder)
    os.close(fd)
    temp = Path(temp_name)
    try:
        os.chmod(temp, _mode_for(path))  # mkstemp makes 0600; the result should look like any other new file
        write(temp)
        with open(temp, "rb+") as handle:
            os.fsync(handle.fileno())
        os.replace(temp, path)
    except BaseException:
        temp.unlink(missing_ok=True)
        raise
    try:  # make the rename itself durable
        dir_fd = os.open(folder, os.O_RDONLY)
        try:
            os.fsync(dir_fd)
        finally:
            os.close(dir_fd)
    except OSError:
        pass
