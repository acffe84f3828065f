"""The check every writer of a file named by the user makes before any work (the command line's outputs, the
Mitsuba importer's TOML): the file can be written at the end, and nothing that is not a replaceable file is lost."""

import errno
import os
import stat
import tempfile
from pathlib import Path

from spectrace.errors import SpectraceError
from spectrace.io.atomic import temporary_name_parts


def _read_only(path: Path) -> bool:
    # Without any write permission bit, the file is meant to be kept even where the process could replace it (the
    # superuser, or an atomic rename in a writable folder, which ignores the file's own permissions).
    return not os.access(path, os.W_OK) or stat.S_IMODE(path.stat().st_mode) & 0o222 == 0


def _check_reachable(path: Path, option: str) -> None:
    """Refuse a path the system will not even look up: one through a loop of symbolic links, or with a name (or as
    a whole) longer than the file system takes. Every later question about it would be such an error."""
    try:
        os.stat(path)
    except (FileNotFoundError, NotADirectoryError):  # a new file, or a file on the way: told below
        return
    except OSError as error:
        if error.errno == errno.ELOOP:
            problem = "a path that leads through a loop of symbolic links"
        elif error.errno == errno.ENAMETOOLONG:
            problem = "a path too long for the file system (a name may have 255 bytes, a whole path some 4096)"
        else:
            problem = f"a path that cannot be looked up ({error.strerror or error})"
        raise SpectraceError(f"{option} names {problem}", where=str(path)) from None
    except ValueError as error:  # a NUL character
        raise SpectraceError(f"{option} names no valid path ({error})", where=str(path)) from None


def check_output_file(path: Path, option: str, create_folders: bool = False) -> None:
    """Refuse an output file that could not be written at the end: a path that cannot be looked up (a loop of
    symbolic links, too long a name), a folder or other non-file, a read-only file, a missing folder (unless
    `create_folders`: then the nearest existing one is checked), or a folder where no file can be created (tried,
    since permission bits do not tell the superuser's rights or a read-only mount's)."""
    where = str(path)
    _check_reachable(path, option)
    if path.is_dir():
        raise SpectraceError(f"{option} names a folder; name a file in it", where=where)
    if path.exists() or path.is_symlink():
        if not path.is_file():
            raise SpectraceError(
                f"{option} names something that is not a regular file (it would be replaced)", where=where
            )
        if _read_only(path):
            raise SpectraceError(
                f"{option} names a read-only file; make it writable or choose another name", where=where
            )
    folder = path.parent if str(path.parent) else Path(".")
    while create_folders and not folder.exists() and folder.parent != folder:
        folder = folder.parent
    if not folder.exists():
        raise SpectraceError(f"the folder {folder} for {option} does not exist", where=where)
    if not folder.is_dir():
        raise SpectraceError(f"{folder} is not a folder, so {option} cannot be written there", where=where)
    try:  # the same kind of file the atomic writer makes: a hidden temporary one next to the output
        prefix, suffix = temporary_name_parts(path, "probe")
        fd, probe = tempfile.mkstemp(prefix=prefix, suffix=suffix, dir=folder)
        os.close(fd)
        os.unlink(probe)
    except OSError as error:
        raise SpectraceError(
            f"cannot create files in the folder {folder} for {option} ({error.strerror or error})", where=where
        ) from None
