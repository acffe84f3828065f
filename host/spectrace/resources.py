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


def resolve_scene_path(scene: "str | Path") -> Path:
    """A scene argument as a file: the path itself when it exists, else, for a bare name such as `cornell_box`
    or `cornell_box.toml`, the bundled scene of that name, so that the bundled scenes load from any folder.
    A bare name that is neither raises SpectraceError listing the bundled scenes; a missing path is returned
    as it is, for the loader to report. A folder of that name does not hide the scene: a scene's meshes and
    textures live in a folder named after it (scenes/teapot/ beside scenes/teapot.toml)."""
    from spectrace.errors import SpectraceError

    path = Path(scene)
    try:
        path.exists()
    except (OSError, ValueError):  # a name the system will not look up (too long): the loader's to report
        return path
    if path.is_file() or path.parent != Path(".") or str(path) in ("", "."):
        return path
    if path.exists() and not path.is_dir():
        return path  # a pipe or device: the loader refuses it, naming it
    name = path.name if path.suffix else f"{path.name}.toml"
    if Path(name).is_file():
        return Path(name)
    bundled = scenes_dir() / name
    if path.suffix.lower() in ("", ".toml") and bundled.is_file():
        return bundled
    if path.is_dir():
        return path  # for the loader's "is a folder, not a file"
    raise SpectraceError(
        f"no such scene file, and no bundled scene of that name (bundled: {', '.join(bundled_scene_names())})",
        where=str(scene),
    )
