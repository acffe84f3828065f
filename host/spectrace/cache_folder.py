"""A temporary stand-in for a cache folder that cannot be written.

spectrace keeps built kernels and its OpenCL vendor list under ``$SPECTRACE_CACHE_DIR`` or
``$XDG_CACHE_HOME/spectrace`` (``~/.cache/spectrace``), and PoCL, pyopencl and matplotlib keep their caches under
``$XDG_CACHE_HOME`` as well. When that folder cannot be written (a read-only home, ``XDG_CACHE_HOME`` naming a
file), PoCL and pyopencl fail to open any device, which would read as "no OpenCL runtime installed". Pointing the
variables at a private temporary folder instead keeps rendering working; kernels are then rebuilt once per boot.
"""

import os
import stat
import sys
from pathlib import Path

_checked = False


def cache_root() -> Path:
    """spectrace's per-user cache folder: ``$SPECTRACE_CACHE_DIR``, else ``$XDG_CACHE_HOME/spectrace``,
    else ``~/.cache/spectrace``."""
    explicit = os.environ.get("SPECTRACE_CACHE_DIR")
    if explicit:
        return Path(explicit).expanduser()
    xdg = os.environ.get("XDG_CACHE_HOME")
    base = Path(xdg).expanduser() if xdg else Path.home() / ".cache"
    return base / "spectrace"


def _unwritable(folder: Path) -> str | None:
    """Why files cannot be created in `folder` (made if missing), or None when they can."""
    if folder.exists() and not folder.is_dir():
        return "it is not a folder"
    try:
        folder.mkdir(parents=True, exist_ok=True)
        # A file of our own made and removed (not the tempfile module: this runs at every start, and importing
        # tempfile and shutil costs more than the check).
        probe = folder / f".spectrace-probe-{os.getpid()}"
        os.close(os.open(probe, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o600))
        os.unlink(probe)
    except OSError as error:
        return error.strerror or str(error)
    return None


def _private_temporary_folder() -> Path:
    """$TMPDIR/spectrace-cache-UID when it is ours alone (so a cache outlives the process), else a fresh one:
    kernel binaries are loaded from it, so nobody else may be able to write there."""
    import tempfile

    folder = Path(tempfile.gettempdir()) / f"spectrace-cache-{os.getuid()}"
    try:
        folder.mkdir(mode=0o700, exist_ok=True)
        status = os.lstat(folder)
        if stat.S_ISDIR(status.st_mode) and status.st_uid == os.getuid() and not status.st_mode & 0o077:
            return folder
    except OSError:
        pass
    return Path(tempfile.mkdtemp(prefix="spectrace-cache-"))


def ensure_usable_cache_folder() -> None:
    """Once per process: for each cache folder that cannot be written ($XDG_CACHE_HOME or ~/.cache, which other
    libraries use too, and $SPECTRACE_CACHE_DIR when set), point its variable at a private temporary folder
    and say so in one line on stderr."""
    global _checked
    if _checked:
        return
    _checked = True
    try:
        base = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache").expanduser()
    except RuntimeError:  # no home folder to be found
        base = None
    folders = [("XDG_CACHE_HOME", base, "")]
    if explicit := os.environ.get("SPECTRACE_CACHE_DIR"):
        folders.append(("SPECTRACE_CACHE_DIR", Path(explicit).expanduser(), "spectrace"))
    for variable, folder, inside in folders:
        reason = "no home folder" if folder is None else _unwritable(folder)
        if reason is None:
            continue
        stand_in = str(_private_temporary_folder() / inside)
        os.environ[variable] = stand_in
        print(
            f"warning: cache folder '{folder or '~/.cache'}' cannot be written ({reason}); using '{stand_in}' "
            f"instead ({variable}), so compiled kernels last only until it is cleared",
            file=sys.stderr,
            flush=True,
        )
