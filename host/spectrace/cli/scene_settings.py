"""`--set KEY.PATH=VALUE`: values of a scene replaced from the command line, as Mitsuba's `-D` sets a parameter. The
key path is the scene file's (`film.width`, `materials.red.reflectance`, `shapes.0.material`); the loader checks it
and the value as it checks the file, naming the key."""

import tomllib
from collections.abc import Iterable
from pathlib import Path

from spectrace.errors import SpectraceError


def parse_value(text: str) -> object:
    """`text` as a TOML value (`1`, `0.5`, `true`, `[0.6, 0.1, 0.1]`, `"bdpt"`), or as the text itself when it is no
    TOML value (`bdpt`), so that names need no quotes through the shell."""
    try:
        return tomllib.loads(f"value = {text}")["value"]
    except tomllib.TOMLDecodeError:
        return text


def parse_settings(items: list[str], option: str) -> dict[str, object]:
    """{dotted key path: value} of `option`'s KEY.PATH=VALUE items, in order (a later item replaces an earlier)."""
    settings: dict[str, object] = {}
    for item in items:
        key, separator, text = item.partition("=")
        key = key.strip()
        parts = key.split(".")
        if not separator or not key or not all(part.strip() for part in parts):
            raise SpectraceError(f"expected KEY.PATH=VALUE (such as film.width=64), got '{item}'", where=option)
        settings[key] = parse_value(text.strip())
    return settings


def override_at_fault(error: SpectraceError, scene_file: Path, keys: Iterable[str]) -> str | None:
    """The key among `keys` (dotted key paths set on the scene: `--set`, a sweep's grid) whose value `error` is about
    (the error names that key path of `scene_file`), or None when the error lies elsewhere in the scene."""
    from spectrace.scene.loader import key_path

    if not error.where or not error.where.startswith(f"{scene_file}: "):
        return None
    location = error.where[len(f"{scene_file}: ") :]
    for name in keys:
        forms = {name, key_path(tuple(int(part) if part.isdigit() else part for part in name.split(".")))}
        if any(location == form or location.startswith((f"{form}.", f"{form}[")) for form in forms):
            return name
    return None


def named_by_option(error: SpectraceError, scene_file: Path, settings: dict[str, object], option: str):
    """`error` named by `option` and the key when its value came from there (`--set film.width: must be ≥ 1, got
    0`), else `error` as it is (the scene's own fault, named with its file and key path)."""
    key = override_at_fault(error, scene_file, settings)
    return error if key is None else SpectraceError(error.message, where=f"{option} {key}")
