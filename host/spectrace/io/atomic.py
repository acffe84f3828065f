"""Atomic file output: readers see the old file or the complete new one, never a torn write."""

import os
import shutil
import stat
import tempfile
from collections.abc import Callable, Mapping
from pathlib import Path, PurePosixPath


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
    _sync_folder(folder)


def _sync_folder(folder: Path) -> None:
    """Make the renames in `folder` durable."""
    try:
        dir_fd = os.open(folder, os.O_RDONLY)
        try:
            os.fsync(dir_fd)
        finally:
            os.close(dir_fd)
    except OSError:
        pass


def _sync_file(path: Path) -> None:
    with open(path, "rb+") as handle:
        os.fsync(handle.fileno())


def write_with_files(
    path: Path,
    files: Mapping[str, Callable[[Path], object]],
    write: Callable[[Path, Mapping[str, str]], object],
) -> None:
    """Write `path` and the files that belong to it (an imported scene's meshes) all or nothing: a failure or an
    interruption at any step before the last renames leaves every earlier file as it was.

    files: each file's name relative to path's folder (`scene_assets/mesh.ply`, `scene.sensor.csv`) -> a function
    writing it to the path it is given. They are written first, into a hidden staging folder beside `path`. Then
    write(temp, staged) writes the main file to a temporary file in path's folder (so that its other relative
    paths lead where they will), where `staged` maps each name in `files` to where that file lies meanwhile,
    relative to the folder; it may check the result there, and raise to leave everything as it was. Only then is
    each top-level entry (the folder `scene_assets`, the file `scene.sensor.csv`) swapped for its earlier version,
    and the main file renamed over `path`; a failed rename puts back what was swapped.
    """
    path = Path(path)
    folder = path.parent if str(path.parent) else Path(".")
    folder.mkdir(parents=True, exist_ok=True)
    prefix, suffix = temporary_name_parts(path)
    staging = Path(tempfile.mkdtemp(prefix=prefix, suffix=".staging", dir=folder))
    swapped: list[tuple[str, bool]] = []  # (top-level entry, whether an earlier version waits in staging/old)
    temp: Path | None = None
    try:
        staged = {}
        for name, write_file in files.items():
            target = staging / "new" / name
            target.parent.mkdir(parents=True, exist_ok=True)
            write_file(target)
            _sync_file(target)
            staged[name] = PurePosixPath(staging.name, "new", name).as_posix()
        fd, temp_name = tempfile.mkstemp(prefix=prefix, suffix=suffix, dir=folder)
        os.close(fd)
        temp = Path(temp_name)
        os.chmod(temp, _mode_for(path))
        write(temp, staged)
        _sync_file(temp)
        (staging / "old").mkdir()
        for top in dict.fromkeys(PurePosixPath(name).parts[0] for name in files):
            earlier = os.path.lexists(folder / top)
            if earlier:
                os.rename(folder / top, staging / "old" / top)
            swapped.append((top, earlier))
            os.rename(staging / "new" / top, folder / top)
        os.replace(temp, path)
    except BaseException:
        for top, earlier in reversed(swapped):
            if not os.path.lexists(staging / "new" / top):  # the new entry got into place
                os.rename(folder / top, staging / "new" / top)
            if earlier:
                os.rename(staging / "old" / top, folder / top)
        if temp is not None:
            temp.unlink(missing_ok=True)
        raise
    finally:
        shutil.rmtree(staging, ignore_errors=True)
    _sync_folder(folder)
