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
