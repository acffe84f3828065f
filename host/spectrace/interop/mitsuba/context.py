"""One import's state and the helpers every plugin's mapping shares: property values and references, the one-line
error naming the file and element path, and the records of what is not imported (unsupported plugins, notes,
warnings). The kinds' modules (shapes, materials, textures, ...) are functions of this context; the plugin modules'
`from_mitsuba` receive the importer (spectrace.interop.mitsuba.importer), this context with the kinds' helpers a
mapping calls (spectrum, roughness, ior, material, ...) as methods."""

from __future__ import annotations

import os
import re
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import overload

import numpy as np

from spectrace.core import limits
from spectrace.errors import SpectraceError
from spectrace.interop.mitsuba.plugins import OBJECT_TAGS, PROPERTY_TAGS, importable
from spectrace.interop.mitsuba.tree import Element, element_error, shown
from spectrace.number_text import DECIMAL, INTEGER

MAX_NESTING = limits.MAX_NESTING
FLOAT32_MAX = float(np.finfo(np.float32).max)
INTEGER_LIMIT = 2**63  # TOML's integers are 64-bit


class Properties(dict):
    """An object's named children, which remember the keys the importer asked about (`in`, `[]`, `get`, or walking
    the keys, which a plugin does to judge each one): every other one is reported as not imported."""

    def __init__(self, owner: Element, items: dict[str, Element]):
        super().__init__(items)
        self.owner = owner
        self.read: set[str] = set()

    def __getitem__(self, key: str) -> Element:
        self.read.add(key)
        return super().__getitem__(key)

    def get(self, key, default=None):
        self.read.add(key)
        return super().get(key, default)

    def __contains__(self, key: object) -> bool:
        if isinstance(key, str):
            self.read.add(key)
        return super().__contains__(key)

    def __iter__(self):
        self.read.update(dict.keys(self))
        return super().__iter__()

    def understood(self, *keys: str) -> None:
        """Keys the importer takes as read although it looks them up another way (or, as storage, not at all)."""
        self.read.update(keys)

    def unread(self) -> list[str]:
        return [key for key in dict.keys(self) if key not in self.read]


class ImportContext:
    """One import of an XML scene: what has been imported so far (materials, textures, where each TOML key came
    from) and what is not (unsupported plugins, notes, warnings), with the helpers every mapping uses: property
    values (`number`, `integer`, `vector`, `text`, `boolean`, `choice`, `properties`, `child`, `nested`, `resolve`),
    `fail(element, message, attribute)` for the one-line error naming the file and element path,
    `unsupported_plugin(element, detail)` for what spectrace cannot represent (mappings return None then), and
    `notes` for what it represents differently."""

    def __init__(self, xml_path: Path, toml_folder: Path, parameters: dict[str, str]):
        self.xml_path = xml_path
        self.toml_folder = toml_folder
        self.parameters = dict(parameters)
        # Files the scene needs beside its TOML (a specfilm's response curves as a sensor CSV): name -> text.
        self.side_files: dict[str, str | bytes] = {}
        self.side_stem = xml_path.stem  # their names start with it (import_mitsuba: the TOML's stem)
        self.ids: dict[str, Element] = {}
        self.unsupported: dict[str, list] = {}  # "plugin detail" -> [count, first element]
        self.notes: list[str] = []
        self.warnings: list[str] = []  # properties and unknown tags not imported: `--strict` makes them an error
        self.unknown_tags = 0  # of the warnings
        self.film_aovs: list[str] = []  # from an aov integrator
        self.property_tables: dict[int, Properties] = {}  # element -> its Properties, read by every mapping
        self.object_names: dict[int, str] = {}  # shapegroup element -> its spectrace object's name
        self.search_folders: list[Path] = [xml_path.parent]  # <path> folders, then the scene's
        self.materials: dict[str, dict] = {}
        self.material_of_element: dict[tuple[int, bool], str] = {}
        self.textures: dict[str, dict] = {}
        self.texture_of_element: dict[tuple[int, bool], str] = {}
        self.texture_elements: dict[str, Element] = {}
        # Whether the material being converted is for a shape whose v runs up (shapes.V_UP_SHAPES): its textures'
        # v are flipped.
        self.flip_v = False
        self.used_texture = False  # a texture was converted or reused since this was last reset
        self.resolving: list[int] = []  # elements being converted, to stop reference cycles
        self.origins: dict[str, Element] = {}  # TOML key path -> the element it was imported from

    # -------------------------------------------------- helpers

    def fail(self, element: Element, message: str, attribute: str | None = None) -> SpectraceError:
        """The error for a problem at an element (or one of its attributes): where names the file and the path."""
        return element_error(element, message, attribute)

    def where(self, element: Element) -> str:
        return f"{element.file or self.xml_path}: {element.path}"

    @overload
    def attribute(self, element: Element, key: str, default: str) -> str: ...

    @overload
    def attribute(self, element: Element, key: str, default: None = None) -> str | None: ...

    def attribute(self, element: Element, key: str, default: str | None = None) -> str | None:
        """An attribute ($parameters were substituted when the file was read: spectrace.interop.mitsuba.tree)."""
        return element.get(key, default)

    def required(self, element: Element, key: str) -> str:
        value = self.attribute(element, key)
        if value is None:
            raise self.fail(element, f"<{shown(element.tag)}> needs the attribute '{key}'", key)
        return value

    def kind(self, element: Element) -> str:
        """The plugin type of an object element (shape, bsdf, emitter, ...), which Mitsuba requires."""
        return self.required(element, "type")

    def child(self, properties: dict[str, Element], key: str, owner: Element) -> Element:
        if key not in properties:
            raise self.fail(owner, f"{owner.label()} needs a property named '{key}'")
        return properties[key]

    def unsupported_plugin(self, element: Element, detail: str = "") -> None:
        """Record what spectrace cannot represent; the error names each once, with its count and first line."""
        entry = self.unsupported.setdefault(f"{element.label()}{detail}", [0, element])
        entry[0] += 1

    def unsupported_object(self, element: Element, detail: str = "") -> None:
        """A plugin spectrace does not import at all, and the plugins nested in it (or referenced from it) that it
        would not import either, so that one error names all of them."""
        self.unsupported_plugin(element, detail)
        seen = {id(element)}
        pending = list(element.children)
        while pending:
            child = pending.pop(0)
            if child.tag == "ref":
                identifier = child.get("id")
                if identifier is None or identifier not in self.ids:
                    continue
                child = self.ids[identifier]
            if id(child) in seen:
                continue
            seen.add(id(child))
            kind = child.get("type")
            if child.tag in OBJECT_TAGS and kind is not None and not importable(child.tag, kind):
                self.unsupported_plugin(child)
            pending += child.children

    def at(self, element: Element) -> str:
        """'line N' of an element, or 'line N of other.xml' for one from an <include>d file (notes, messages)."""
        return f"line {element.line}" + (
            f" of {shown(element.file.name, 100)}" if element.file not in (None, self.xml_path) else ""
        )

    def unsupported_text(self) -> str:
        parts = []
        for text, (count, element) in self.unsupported.items():
            place = self.at(element)
            parts.append(f"{text} ({place})" if count == 1 else f"{text} ({count} times, first at {place})")
        return ", ".join(parts)

    def nested(self, properties: Properties, tag: str) -> list[Element]:
        """The children (nested or referenced) of one kind, e.g. a shape's bsdf, read."""
        keys = [key for key, child in properties.items() if self.resolve(child).tag == tag]
        properties.understood(*keys)
        return [self.resolve(properties[key]) for key in keys]

    def parse_number(self, text: str, element: Element, key: str) -> float:
        """A finite number that float32 (Mitsuba's and the renderer's precision) holds."""
        text = text.strip()
        if not DECIMAL.fullmatch(text):
            raise self.fail(element, f"expected a finite number, got '{shown(text)}'", key)
        value = float(text)
        if not abs(value) <= FLOAT32_MAX:
            raise self.fail(element, f"{shown(text)} is beyond the float32 range (±3.4e38)", key)
        return value

    def numbers(self, element: Element, key: str = "value", default: str | None = None) -> list[float]:
        text = self.attribute(element, key, default)
        if text is None:
            raise self.fail(element, f"<{shown(element.tag)}> needs the attribute '{key}'", key)
        parts = [part for part in re.split(r"[,\s]+", text.strip()) if part]
        if not parts:
            raise self.fail(element, "expected numbers, got an empty value", key)
        return [self.parse_number(part, element, key) for part in parts]

    def number(self, element: Element, key: str = "value") -> float:
        values = self.numbers(self.resolve(element), key)
        if len(values) != 1:
            raise self.fail(
                element,
                f'<{shown(element.tag)} name="{shown(element.get("name") or "")}"> needs one number, got {len(values)}',
                key,
            )
        return values[0]

    def integer(self, element: Element, low: int | None = None) -> int:
        """An integer property (<integer>, or an integral <float>) within TOML's 64-bit range."""
        element = self.resolve(element)
        text = self.required(element, "value").strip()
        if INTEGER.fullmatch(text):
            value = int(text)
        else:
            number = self.number(element)
            if number != int(number):
                raise self.fail(element, f"expected an integer, got '{shown(text)}'", "value")
            value = int(number)
        if not -INTEGER_LIMIT < value < INTEGER_LIMIT:
            raise self.fail(element, f"integer {shown(text)} is out of range", "value")
        if low is not None and value < low:
            raise self.fail(
                element,
                f'<{element.tag} name="{shown(element.get("name") or "")}"> must be at least {low}, got {value}',
                "value",
            )
        return value

    def vector(self, element: Element, default: float = 0.0) -> list[float]:
        """<point>/<vector> (x, y, z attributes or value="x, y, z")."""
        if element.get("value") is not None:
            values = self.numbers(element, "value")
            if len(values) == 1:
                values *= 3
            if len(values) != 3:
                raise self.fail(element, f"<{shown(element.tag)}> needs 3 numbers, got {len(values)}", "value")
            return values
        return [self.parse_number(self.attribute(element, axis, repr(default)), element, axis) for axis in "xyz"]

    def resolve(self, element: Element) -> Element:
        if element.tag != "ref":
            return element
        identifier = self.required(element, "id")
        if identifier not in self.ids:
            raise self.fail(element, f"reference to undefined id '{shown(identifier)}'", "id")
        return self.ids[identifier]

    @contextmanager
    def converting(self, element: Element) -> Iterator[None]:
        """While an element is converted: references may nest, but not loop or run deeper than elements may."""
        if id(element) in self.resolving:
            raise self.fail(element, f"{element.label()} refers to itself (through <ref>)")
        if len(self.resolving) >= MAX_NESTING:
            raise self.fail(element, f"references nested more than {MAX_NESTING} deep")
        self.resolving.append(id(element))
        try:
            yield
        finally:
            self.resolving.pop()

    def properties(self, element: Element) -> Properties:
        """Named children (property elements, references, nested objects); unnamed nested objects by tag. The same
        object each time for one element, so that what was read of it adds up."""
        if id(element) in self.property_tables:
            return self.property_tables[id(element)]
        found: dict[str, Element] = {}
        for index, child in enumerate(element.children):
            name = child.get("name")
            if name is None and child.tag in PROPERTY_TAGS:
                raise self.fail(child, f"<{child.tag}> needs the attribute 'name' (the property it sets)", "name")
            if name is None and child.tag in OBJECT_TAGS:
                name = child.tag if child.tag not in found else f"{child.tag}#{index}"
            found[name or f"#{index}"] = child
        properties = self.property_tables[id(element)] = Properties(element, found)
        return properties

    def text(self, element: Element) -> str:
        return self.attribute(self.resolve(element), "value") or ""

    def boolean(self, element: Element) -> bool:
        """A boolean as Mitsuba 3's parser reads one: "true" or "false" in any case ("True", "FALSE"), nothing
        else (no spaces around, no 1 or yes). Its lower-casing is ASCII-only (std::tolower)."""
        value = self.text(element)
        folded = value.lower() if value.isascii() else value
        if folded not in ("true", "false"):
            raise self.fail(element, f"expected true or false, got '{shown(value)}'", "value")
        return folded == "true"

    def input_file(self, element: Element, what: str = "file") -> str:
        """A file named by a property's value, relative to the XML: checked to exist, and written relative to the
        TOML."""
        path = self.find_file(element, self.required(element, "value"))
        try:
            found = path.is_file()
        except (OSError, ValueError):  # e.g. a name too long for the file system
            found = False
        if not found:
            raise self.fail(element, f"{what} '{shown(str(path), 200)}' does not exist or is not a file", "value")
        return relative_path(path, self.toml_folder)

    def find_file(self, element: Element, name: str) -> Path:
        """A file named in the scene, looked up as Mitsuba's file resolver does: the <path> folders, then the scene's
        folder (and, for an element of an <include>d file, that file's folder first). Where none holds it, the path
        in the scene's folder, for the message."""
        first = [element.file.parent] if element.file is not None and element.file != self.xml_path else []
        for folder in (*first, *self.search_folders):
            candidate = folder / name
            try:
                if candidate.exists():
                    return candidate
            except (OSError, ValueError):
                break
        return self.xml_path.parent / name

    def choice(self, element: Element, options: tuple[str, ...]) -> str:
        """A string property that must be one of `options`."""
        value = self.text(element)
        if value not in options:
            raise self.fail(
                element,
                f"unknown {shown(element.get('name') or element.tag)} '{shown(value)}' ({', '.join(options)})",
                "value",
            )
        return value

    def non_negative(self, values: list[float], element: Element, key: str) -> None:
        """Reflectances, emission and optical constants are never negative."""
        if any(value < 0.0 for value in values):
            raise self.fail(element, f"negative value {min(values):g}; spectra must be >= 0", key)

    def imported_error(self, error: SpectraceError, toml_path: Path) -> SpectraceError:
        """A loader's complaint about the imported TOML, told at the XML element the value came from."""
        where = error.where or ""
        key = where[len(str(toml_path)) + 2 :] if where.startswith(f"{toml_path}: ") else ""
        matches = [
            prefix
            for prefix in self.origins
            if key == prefix or key.startswith(prefix + ".") or key.startswith(prefix + "[")
        ]
        element = self.origins[max(matches, key=len)] if matches else None
        detail = f" (imported as {key})" if key else ""
        if element is None:
            return SpectraceError(
                f"the imported scene does not load: {error.message}{detail}", where=str(self.xml_path)
            )
        return self.fail(element, f"{error.message}{detail}")


def unique_name(base: str, taken: dict) -> str:
    """A TOML name from an id: what a bare key cannot hold becomes '_', and a number follows a name taken."""
    name = re.sub(r"[^A-Za-z0-9_-]", "_", base) or "material"
    candidate, number = name, 2
    while candidate in taken:
        candidate, number = f"{name}_{number}", number + 1
    return candidate


def relative_path(path: Path, folder: Path) -> str:
    """A file as the TOML names it: relative to the TOML's folder (absolute where no relative path leads there)."""
    try:
        return Path(os.path.relpath(path.resolve(), folder.resolve())).as_posix()
    except ValueError:  # another drive on Windows
        return path.resolve().as_posix()
