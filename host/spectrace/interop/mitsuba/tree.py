"""A Mitsuba 3 XML file as Mitsuba's own parser reads it, before any plugin is looked at: the element tree with each
element's file, line and path, `$name` parameters substituted in every attribute, `<default>` values, `<include>`d
files spliced in, `<path>` folders collected, and files of Mitsuba 0.x (`version` below 2.0.0) upgraded.

Learnt from Mitsuba 3's parser (src/core/parser.cpp: `substitute_parameters`, the `Include`, `Default` and
`Resource` tags, `upgrade_from_v1`; and the `upgrade_tree` of its earlier src/core/xml.cpp):

- Substitution runs over every attribute of every element in document order, parameters sorted longest name first,
  each `$name` replaced wherever it occurs; `\\$` stays a literal `$`; any other `$` left is an undefined parameter.
  A `<default name value>` defines a parameter unless `-D` (or an earlier default) did; later elements see it.
- `<include filename>` reads the file relative to the including file's folder (then the `<path>` folders and the
  scene's folder); an included `<scene>` contributes its children, any other root element itself. Mitsuba stops at
  15 levels of inclusion; a file that includes itself is named as such.
- `<path value>` (a child of the root only) adds a folder where relative file names are looked up, before the
  scene's own folder.
- Version < 2.0.0 (per file, so an old file included by a new one is upgraded alone): every `name` but a
  `<default>`'s turned from camelCase to snake_case (toWorld -> to_world, intIOR -> int_ior), `<lookAt>` ->
  `<lookat>` (Mitsuba 3 before 3.7 did this; its newer parser refuses `<lookAt>`), a `diffuse` bsdf's
  `diffuse_reflectance` -> `reflectance`, and `uoffset`/`voffset`/`uscale`/`vscale` -> a `to_uv` transform that
  translates, then scales.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path
from xml.parsers import expat

from spectrace.core import limits
from spectrace.errors import SpectraceError, one_line
from spectrace.io.input_files import Inclusions, regular_file

MAX_NESTING = limits.MAX_NESTING
MAX_INCLUDE_DEPTH = 15  # Mitsuba 3's ParserConfig.max_include_depth
UPGRADED_BELOW = (2, 0, 0)  # files of an older version are upgraded


@dataclass
class Element:
    tag: str
    attributes: dict[str, str]
    line: int
    children: list[Element] = field(default_factory=list)
    path: str = ""  # e.g. "shape[2]/transform/translate", for messages
    file: Path | None = None  # the file it was read from (an <include>d one, or the scene)

    def get(self, key: str, default: str | None = None) -> str | None:
        return self.attributes.get(key, default)

    def label(self) -> str:
        kind = self.get("type")
        return f"{self.tag} '{shown(kind)}'" if kind else shown(self.tag)


@dataclass
class SceneTree:
    """The scene's root element (includes spliced in) and the folders relative file names are looked up in."""

    root: Element
    search_folders: list[Path]  # <path> folders, the latest first, then the scene's folder
    unused_parameters: list[str]  # -D parameters no attribute used


def shown(text: str, limit: int = 60) -> str:
    """Text from the file as it may appear in a one-line message: shortened, line breaks and other unprintable
    characters escaped."""
    return one_line(text if len(text) <= limit else text[:limit] + "...")


def read_input_file(path: Path, where: str) -> bytes:
    """The bytes of the scene or of a file it refers to: every input file is read here, so that what may be read
    is decided in one place."""
    # A FIFO or a device would block or never end: only regular files are read.
    regular_file(
        path, None if where == str(path) else where, what="Mitsuba scene file" if where == str(path) else "file"
    )
    try:
        return path.read_bytes()
    except OSError as error:
        raise SpectraceError(
            f"cannot read '{shown(str(path), 200)}' ({error.strerror or error})", where=where
        ) from None


def parse_file(path: Path, where: str | None = None) -> Element:
    """One XML file's element tree with each element's file, line number and path (for messages)."""
    data = read_input_file(path, where or str(path))
    parser = expat.ParserCreate()
    stack: list[Element] = []
    root: list[Element] = []

    def start(tag: str, attributes: dict[str, str]) -> None:
        if len(stack) >= MAX_NESTING:
            raise SpectraceError(
                f"elements nested more than {MAX_NESTING} deep (line {parser.CurrentLineNumber}); "
                "Mitsuba scenes need a handful of levels",
                where=str(path),
            )
        element = Element(tag, dict(attributes), parser.CurrentLineNumber, file=path)
        (stack[-1].children if stack else root).append(element)
        stack.append(element)

    parser.StartElementHandler = start
    parser.EndElementHandler = lambda tag: stack.pop()
    try:
        parser.Parse(data, True)
    except expat.ExpatError as error:
        raise SpectraceError(
            f"XML syntax error: {expat.ErrorString(error.code)} (line {error.lineno}, column {error.offset + 1})",
            where=str(path),
        ) from None
    if not root:
        raise SpectraceError("not a Mitsuba scene: the file has no element", where=str(path))
    name_paths(root[0])
    return root[0]


def name_paths(root: Element) -> None:
    """Each element's path below the root: tags joined by '/', with the index among siblings of the same tag
    (from 0, as spectrace's own key paths count) where there are several."""
    root.path = root.tag
    pending = [(root, "")]
    while pending:
        parent, prefix = pending.pop()
        counts: dict[str, int] = {}
        for child in parent.children:
            counts[child.tag] = counts.get(child.tag, 0) + 1
        seen: dict[str, int] = {}
        for child in parent.children:
            index = seen.get(child.tag, 0)
            seen[child.tag] = index + 1
            child.path = prefix + (f"{child.tag}[{index}]" if counts[child.tag] > 1 else child.tag)
            pending.append((child, child.path + "/"))


def element_error(element: Element, message: str, attribute: str | None = None) -> SpectraceError:
    """The one-line error for a problem at an element (or one of its attributes), naming its file and path."""
    place = f"{element.path}@{shown(attribute)}" if attribute else element.path
    return SpectraceError(f"{message} (line {element.line})", where=f"{element.file}: {place}")


def camel_to_snake(name: str) -> str:
    """Mitsuba's upgrade of a 0.x property name: an underscore before each capital that follows a lower-case letter,
    and that capital and the capitals right after it lower-cased (toWorld -> to_world, intIOR -> int_ior,
    sampleCount -> sample_count; already snake_case names and 'ID' stay)."""
    out: list[str] = []
    i = 0
    while i < len(name):
        c = name[i]
        if i > 0 and name[i - 1].islower() and c.isupper():
            out.append("_" + c.lower())
            while i + 1 < len(name) and name[i + 1].isupper():
                i += 1
                out.append(name[i].lower())
        else:
            out.append(c)
        i += 1
    return "".join(out)


def parse_version(root: Element) -> tuple[int, int, int] | None:
    """The root's `version` (major, minor, patch), or None where it has none (read as the current format)."""
    text = root.get("version")
    if text is None:
        return None
    parts = text.strip().split(".")
    if not (1 <= len(parts) <= 3 and all(part.isdigit() for part in parts)):
        raise element_error(root, f"invalid version number '{shown(text)}' (expected e.g. 3.0.0)", "version")
    numbers = [int(part) for part in parts] + [0] * (3 - len(parts))
    return numbers[0], numbers[1], numbers[2]


class _Reader:
    """One scene's reading: the parameters (from -D, then <default>s as they come), the <path> folders, the files
    being included (to refuse a loop, and to bound what all of them may hold)."""

    def __init__(self, scene_path: Path, parameters: dict[str, str]):
        self.scene_path = scene_path
        self.parameters = dict(parameters)
        self.from_command_line = set(parameters)
        self.used: set[str] = set()
        self.folders: list[Path] = []
        self.inclusions = Inclusions(MAX_INCLUDE_DEPTH, "<include>")

    # -------------------------------------------------- $parameters

    def substitute(self, element: Element) -> None:
        for key, value in list(element.attributes.items()):
            if "$" in value:
                element.attributes[key] = self.substituted(value, element, key)

    def substituted(self, value: str, element: Element, key: str) -> str:
        # Longest names first, so $resx is not read as $res followed by x (Mitsuba's order).
        for name in sorted(self.parameters, key=len, reverse=True):
            token = "$" + name
            position = 0
            while (position := value.find(token, position)) != -1:
                if position > 0 and value[position - 1] == "\\":
                    position += len(token)
                    continue
                replacement = self.parameters[name]
                value = value[:position] + replacement + value[position + len(token) :]
                self.used.add(name)
                position += len(replacement)
        for match in re.finditer(r"\$([A-Za-z0-9_]*)", value):
            if match.start() > 0 and value[match.start() - 1] == "\\":
                continue
            name = match.group(1)
            raise element_error(
                element,
                f'undefined parameter ${shown(name)} (add <default name="{shown(name)}" value="..."/> or '
                f"-D {shown(name)}=...)",
                key,
            )
        return value.replace("\\$", "$")

    # -------------------------------------------------- the walk

    def read(self, path: Path, where: str | None, depth: int) -> tuple[Element, tuple[int, int, int] | None]:
        """A file's root element, substituted, its includes spliced in, upgraded where its version is old."""
        # Refuses a loop, and scenes whose files (counted each time they are included) would take too long or
        # too much memory to read.
        self.inclusions.enter(path, where or str(path))
        try:
            root = parse_file(path, where)
            self.substitute(root)
            version = parse_version(root)
            old = version is not None and version < UPGRADED_BELOW
            self.walk(root, old, depth, 0)
        finally:
            self.inclusions.leave()
        return root, version

    def walk(self, element: Element, old: bool, depth: int, level: int) -> None:
        if level >= MAX_NESTING:
            raise element_error(element, f"elements nested more than {MAX_NESTING} deep (through <include>)")
        children: list[Element] = []
        for child in element.children:
            self.substitute(child)
            if old:
                upgrade_element(child)
            if child.tag == "default":
                self.define(child)
            elif child.tag == "include":
                children += self.include(child, depth)
                continue
            elif child.tag == "path":
                self.add_folder(child, element)
                continue
            self.walk(child, old, depth, level + 1)
            children.append(child)
        element.children = children
        if old:
            upgrade_properties(element)

    def define(self, element: Element) -> None:
        name, value = element.get("name"), element.get("value")
        if name is None or value is None:
            missing = "name" if name is None else "value"
            raise element_error(element, f"<default> needs the attribute '{missing}'", missing)
        if not name:
            raise element_error(element, "<default> needs a non-empty name", "name")
        self.parameters.setdefault(name, value)

    def include(self, element: Element, depth: int) -> list[Element]:
        name = element.get("filename")
        if name is None:
            raise element_error(element, "<include> needs the attribute 'filename'", "filename")
        if depth + 1 >= MAX_INCLUDE_DEPTH:
            raise element_error(element, f"<include> nested more than {MAX_INCLUDE_DEPTH} files deep", "filename")
        assert element.file is not None
        path = self.find(name, element.file.parent)
        if path is None:
            raise element_error(element, f"included file '{shown(name, 200)}' not found", "filename")
        root, _ = self.read(path, f"{element.file}: {element.path}@filename (line {element.line})", depth + 1)
        if root.tag == "scene":
            return root.children
        if element.get("name") is not None:
            root.attributes["name"] = element.attributes["name"]
        return [root]

    def add_folder(self, element: Element, parent: Element) -> None:
        value = element.get("value")
        if value is None:
            raise element_error(element, "<path> needs the attribute 'value'", "value")
        if parent.tag != "scene" or parent.path != "scene":
            raise element_error(element, "<path> may only be a child of the root <scene>")
        assert element.file is not None
        folder = element.file.parent / value
        if not folder.is_dir():
            found = self.find(value, element.file.parent)
            if found is None or not found.is_dir():
                raise element_error(element, f"<path>: folder '{shown(str(folder), 200)}' not found", "value")
            folder = found
        self.folders.insert(0, folder)

    def find(self, name: str, first: Path) -> Path | None:
        """A relative file name looked up as Mitsuba's file resolver does: `first`, the <path> folders, the scene's."""
        for folder in (first, *self.folders, self.scene_path.parent):
            candidate = folder / name
            try:
                if candidate.exists():
                    return candidate
            except (OSError, ValueError):  # e.g. a name too long for the file system
                return None
        return None


def upgrade_element(element: Element) -> None:
    """The element's own part of Mitsuba's 0.x upgrade: its property name in snake_case, <lookAt> as <lookat>."""
    if element.tag != "default" and (name := element.get("name")) is not None:
        element.attributes["name"] = camel_to_snake(name)
    if element.tag == "lookAt":
        element.tag = "lookat"


def upgrade_properties(element: Element) -> None:
    """The upgrades of a 0.x object's properties: diffuse's diffuse_reflectance, uoffset/voffset/uscale/vscale."""
    if element.tag == "bsdf" and element.get("type") == "diffuse":
        for child in element.children:
            if child.get("name") == "diffuse_reflectance":
                child.attributes["name"] = "reflectance"
    placement = {
        child.get("name"): child
        for child in element.children
        if child.tag == "float" and child.get("name") in ("uoffset", "voffset", "uscale", "vscale")
    }
    if not placement:
        return

    def value(name: str, default: str) -> str:
        return placement[name].get("value", default) if name in placement else default  # type: ignore[return-value]

    first = min(placement.values(), key=lambda child: element.children.index(child))
    transform = Element("transform", {"name": "to_uv"}, first.line, path=first.path, file=first.file)
    transform.children = [
        Element("translate", {"x": value("uoffset", "0"), "y": value("voffset", "0")}, first.line, file=first.file),
        Element("scale", {"x": value("uscale", "1"), "y": value("vscale", "1")}, first.line, file=first.file),
    ]
    for step in transform.children:
        step.path = f"{transform.path}/{step.tag}"
    element.children = [child for child in element.children if child not in placement.values()] + [transform]


def read_scene(path: Path, parameters: dict[str, str]) -> SceneTree:
    """The scene as Mitsuba's parser reads it (module docstring)."""
    reader = _Reader(path, parameters)
    root, _ = reader.read(path, None, 0)
    if root.tag != "scene":
        raise SpectraceError("not a Mitsuba scene: the root element must be <scene>", where=str(path))
    unused = sorted(name for name in reader.from_command_line if name not in reader.used)
    return SceneTree(root, [*reader.folders, path.parent], unused)
