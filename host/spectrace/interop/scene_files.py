"""Any scene file as a `Scene`: a spectrace TOML scene, or a Mitsuba 3, pbrt-v4, glTF 2.0 or Blender file imported on
the way in. The one door every command that takes a scene goes through (`render`, `bench`, `display metamerism`), so
that each takes the same files and the same bare names.

The format is read from the suffix; a suffix no format claims (or none) is settled by the file's first bytes, so
that a Mitsuba file saved as `scene.txt` is imported rather than reported as a TOML syntax error."""

from __future__ import annotations

import re
import tempfile
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

from spectrace.errors import SpectraceError

if TYPE_CHECKING:
    from spectrace.scene.model import Scene

TOML, MITSUBA, PBRT, GLTF, BLENDER = "toml", "mitsuba", "pbrt", "gltf", "blender"

SUFFIX_FORMATS = {
    ".toml": TOML,
    ".xml": MITSUBA,
    ".pbrt": PBRT,
    ".gltf": GLTF,
    ".glb": GLTF,
    ".blend": BLENDER,
}
# A bare name tries these in turn, TOML first (the bundled scenes).
SCENE_SUFFIXES = tuple(SUFFIX_FORMATS)

_SNIFFED_BYTES = 4096
# pbrt-v4's scene-wide and world directives (pbrt-v4 file format, "Scene-wide rendering options" and "Describing the
# scene"): a file whose first word is one of these, followed by what a directive takes, is a pbrt file.
_PBRT_DIRECTIVES = frozenset(
    [
        "LookAt",
        "Camera",
        "Sampler",
        "Film",
        "Integrator",
        "PixelFilter",
        "Accelerator",
        "ColorSpace",
        "Option",
        "WorldBegin",
        "AttributeBegin",
        "Attribute",
        "Shape",
        "Material",
        "MakeNamedMaterial",
        "NamedMaterial",
        "Texture",
        "LightSource",
        "AreaLightSource",
        "Translate",
        "Scale",
        "Rotate",
        "Transform",
        "ConcatTransform",
        "CoordinateSystem",
        "CoordSysTransform",
        "Include",
        "Import",
        "ObjectBegin",
        "ObjectInstance",
        "MakeNamedMedium",
        "MediumInterface",
        "ReverseOrientation",
        "Identity",
        "TransformTimes",
        "ActiveTransform",
    ]
)
# The first word and what follows it: a TOML key is followed by `=` or `.` (`Camera = 1`, `Film.x = 2`).
_PBRT_FIRST_WORD = re.compile(r"([A-Za-z]+)[ \t]*([^ \t]?)")


def _first_meaningful_text(text: str, comment: str) -> str:
    """`text` from its first character that is neither blank nor inside a line comment starting with `comment`."""
    for line in text.splitlines():
        stripped = line.strip()
        if stripped and not stripped.startswith(comment):
            return text[text.index(line) :].lstrip()
    return ""


def sniff_format(head: bytes) -> str:
    """The format the first bytes of a file say it is in (TOML when they say none of the others)."""
    if head.startswith(b"glTF"):
        return GLTF
    if head.startswith(b"BLENDER") or head.startswith(b"\x28\xb5\x2f\xfd"):  # a .blend, or a zstd-packed one
        return BLENDER
    text = head.decode("utf-8-sig", errors="replace")
    start = text.lstrip()
    if start.startswith("<"):  # <?xml ...?>, <!-- -->, <scene version=...>
        return MITSUBA
    if start.startswith("{"):  # a JSON object: a .gltf (a TOML file cannot begin with a brace)
        return GLTF
    meaningful = _first_meaningful_text(text, "#")
    match = _PBRT_FIRST_WORD.match(meaningful)
    if match is not None and match.group(1) in _PBRT_DIRECTIVES and match.group(2) not in ("=", "."):
        return PBRT
    return TOML


def scene_format(path: Path) -> str:
    """The format of the scene file at `path`: by its suffix (`.pbrt.gz` as pbrt), else by its first bytes. A file
    that cannot be read is TOML here, for the loader to report in its own words."""
    suffixes = [suffix.lower() for suffix in path.suffixes[-2:]]
    if suffixes and suffixes[-1] in SUFFIX_FORMATS:
        return SUFFIX_FORMATS[suffixes[-1]]
    if suffixes[-2:] == [".pbrt", ".gz"]:
        return PBRT
    try:
        with open(path, "rb") as file:
            head = file.read(_SNIFFED_BYTES)
    except (OSError, ValueError):
        return TOML
    return sniff_format(head)


_FORMAT_NAMES = {MITSUBA: "a Mitsuba 3 XML scene", PBRT: "a pbrt-v4 scene", GLTF: "a glTF file", BLENDER: "a .blend"}


def _with_format_hint(error: SpectraceError, path: Path) -> SpectraceError:
    """A TOML syntax error in a file named .toml whose first bytes say it is another format: the error says which,
    so that the fix (its own suffix) is plain."""
    if not error.message.startswith("TOML syntax error"):
        return error
    try:
        with open(path, "rb") as file:
            kind = sniff_format(file.read(_SNIFFED_BYTES))
    except OSError:
        return error
    if kind == TOML:
        return error
    suffix = next(suffix for suffix, format_kind in SUFFIX_FORMATS.items() if format_kind == kind)
    return SpectraceError(
        f"{error.message}; the file starts like {_FORMAT_NAMES[kind]}: name it {path.stem}{suffix} to import it",
        where=error.where,
    )


def _importer(kind: str) -> Callable[[Path, Path], object]:
    """The import that writes a TOML scene (and its assets beside it) from a file of `kind`."""
    if kind == MITSUBA:
        from spectrace.interop.mitsuba import import_mitsuba

        return import_mitsuba
    if kind == PBRT:
        from spectrace.interop.pbrt import import_pbrt

        return import_pbrt
    if kind == GLTF:
        from spectrace.interop.gltf import import_gltf

        return import_gltf
    from spectrace.interop.blender import import_blend

    return import_blend


def _import_lines(result: object) -> list[str]:
    """An import's warnings and notes as lines ("warning: ...", "note: ..."): pbrt's import returns (warnings,
    notes), the others one list whose warnings carry their prefix."""
    if isinstance(result, tuple):
        warnings, notes = result
        return [f"warning: {text}" for text in warnings] + [f"note: {text}" for text in notes]
    return [text if text.startswith("warning: ") else f"note: {text}" for text in result or ()]  # type: ignore[attr-defined]


def load_any_scene(
    scene: str | Path, overrides: dict[str, object] | None = None, report: Callable[[str], None] | None = None
) -> Scene:
    """The scene in the file `scene` (or the bundled scene of that bare name), whatever its format; `overrides`
    replace values at dotted key paths of the scene as a TOML file holds it (`film.width`, `integrator.type`; for an
    imported file, of the TOML its import writes). Errors name `scene`, never a temporary file. `report`: given each
    line of an import's warnings ("warning: ...") and notes ("note: ..."), and the loaded scene's warnings
    (spectrace.scene.scene_warnings)."""
    from spectrace.resources import resolve_scene_path
    from spectrace.scene.loader import load_scene
    from spectrace.scene.scene_warnings import scene_warnings

    path = resolve_scene_path(scene, SCENE_SUFFIXES)
    kind = scene_format(path)
    if kind == TOML:
        try:
            loaded = load_scene(path, overrides)
        except SpectraceError as error:
            raise _with_format_hint(error, path) from None
        lines: list[str] = []
    else:
        with tempfile.TemporaryDirectory(prefix=f"spectrace-{kind}-") as folder:
            toml_path = Path(folder) / f"{path.stem or 'scene'}.toml"
            lines = _import_lines(_importer(kind)(path, toml_path))
            if report is not None:
                for line in lines:
                    report(line)
            try:
                loaded = load_scene(toml_path, overrides).with_overrides(source=path)
            except SpectraceError as error:
                where = error.where.replace(str(toml_path), str(path)) if error.where else str(path)
                raise SpectraceError(error.message.replace(str(toml_path), str(path)), where=where) from None
    if report is not None:  # an import's lines told what its own load found; overrides may tell more
        for text in scene_warnings(loaded):
            if f"warning: {text}" not in lines:
                report(f"warning: {text}")
    return loaded
