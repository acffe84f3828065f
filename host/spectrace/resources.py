"""Locate the kernels, spectra and scenes folders, from a checkout or from an installed wheel."""

from functools import cache
from pathlib import Path

_PACKAGE_DIR = Path(__file__).resolve().parent


@cache
def _data_root(name: str) -> Path:
    # A wheel carries the folders as package data; an editable install or a checkout has them at the repo root.
    for candidate in (_PACKAGE_DIR / "_data" / name, _PACKAGE_DIR.parent.parent / name):
        if candidate.is_dir():
            return candidate
    raise FileNotFoundError(f"spectrace data folder '{name}' is missing from the installation")


def kernels_dir() -> Path:
    return _data_root("kernels")


def spectra_dir() -> Path:
    return _data_root("spectra")


def scenes_dir() -> Path:
    return _data_root("scenes")


def bundled_scene_names() -> list[str]:
    return sorted(path.stem for path in scenes_dir().glob("*.toml"))


def resolve_scene_path(scene: "str | Path", suffixes: tuple[str, ...] = (".toml",), folder: Path | None = None) -> Path:
    """A scene argument as a file: the path itself when it exists, else, for a bare name such as `cornell_box`
    or `cornell_box.toml`, the file of that name here or the bundled scene of that name, so that the bundled scenes
    load from any folder. `suffixes`: the formats the caller reads, tried in turn for a name without one (a command
    that imports Mitsuba files finds `veach_mis` as veach_mis.xml); `folder`: where a relative path is read from
    (default: the working folder; a sweep's scene is beside its spec). A bare name that is neither raises
    SpectraceError listing the bundled scenes; a missing path is returned as it is, for the loader to report. A
    folder of that name does not hide the scene: a scene's meshes and textures live in a folder named after it
    (scenes/teapot/ beside scenes/teapot.toml)."""
    from spectrace.errors import SpectraceError

    given = Path(scene)
    path = folder / given if folder is not None else given
    try:
        path.exists()
    except (OSError, ValueError):  # a name the system will not look up (too long): the loader's to report
        return path
    if path.is_file() or given.parent != Path(".") or str(given) in ("", "."):
        return path
    if path.exists() and not path.is_dir():
        return path  # a pipe or device: the loader refuses it, naming it
    if path.suffix.lower() in suffixes:
        names = [path.name]
    elif path.suffix:
        names = []
    else:
        names = [f"{path.name}{suffix}" for suffix in suffixes]
    for name in names:
        if (here := path.parent / name).is_file():
            return here
    for name in names:
        if (bundled := scenes_dir() / name).is_file():
            return bundled
    if path.is_dir():
        return path  # for the loader's "is a folder, not a file"
    bundled_names = sorted(
        {found.stem for suffix in suffixes for found in scenes_dir().glob(f"*{suffix}")} or bundled_scene_names()
    )
    raise SpectraceError(
        f"no such scene file, and no bundled scene of that name (bundled: {', '.join(bundled_names)})",
        where=str(scene),
    )
