"""pbrt-v4 scene files: the tokenizer and the directives, as pbrt-v4 reads them.

The file format is pbrt-v4's ("pbrt-v4 File Format", pbrt.org/fileformat-v4): a directive is a keyword, its
positional arguments, and for most a parameter list of `"type name" value` or `"type name" [values]` entries;
`#` starts a comment. `Include` and `Import` read another file in place (relative to the including file's folder; a
`.gz` file inflated, as pbrt-v4 reads it); `Import`'s only difference in pbrt-v4, parallel parsing, changes nothing
here. A file including itself, and files whose includes multiply (each including the next several times), are
refused (spectrace.io.input_files.Inclusions). The graphics state the directives set is
spectrace.interop.pbrt.graphics_state's.

Bad input (an unterminated string, a number that is none, a directive missing its arguments, an unmatched
`AttributeEnd`) raises one SpectraceError naming file:line.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from spectrace.core import limits
from spectrace.errors import SpectraceError, one_line
from spectrace.io.compressed import file_inflater
from spectrace.io.input_files import Inclusions, regular_file

MAX_INCLUDE_DEPTH = limits.MAX_NESTING

# The parameter types pbrt-v4 knows (paramdict.cpp), and how many numbers make one value of each.
PARAMETER_TYPES = {
    "integer": 1,
    "float": 1,
    "point2": 2,
    "vector2": 2,
    "point3": 3,
    "point": 3,
    "vector3": 3,
    "vector": 3,
    "normal3": 3,
    "normal": 3,
    "rgb": 3,
    "blackbody": 1,
    "spectrum": 0,  # pairs of numbers, or a name / file (a string)
    "bool": 0,
    "string": 0,
    "texture": 0,
}

_NUMBER = re.compile(r"[+-]?(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?")
# A bracketed list without strings or comments: scanned in one step (meshes hold millions of numbers).
_PLAIN_ARRAY = re.compile(r"\[([^\]\[\"#]*)\]")
_NUMBERS = re.compile(r"(?:\s*[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?(?=\s|$))*\s*")
# Directive -> its positional arguments: "n" a number, "s" a quoted string, "m" 16 numbers in brackets; and whether
# a parameter list follows.
_DIRECTIVES: dict[str, tuple[str, bool]] = {
    "AttributeBegin": ("", False),
    "AttributeEnd": ("", False),
    "TransformBegin": ("", False),  # pbrt-v3 names pbrt-v4 still reads (with a warning)
    "TransformEnd": ("", False),
    "Identity": ("", False),
    "ReverseOrientation": ("", False),
    "WorldBegin": ("", False),
    "WorldEnd": ("", False),  # pbrt-v3
    "ObjectEnd": ("", False),
    "Translate": ("nnn", False),
    "Scale": ("nnn", False),
    "Rotate": ("nnnn", False),
    "LookAt": ("nnnnnnnnn", False),
    "Transform": ("m", False),
    "ConcatTransform": ("m", False),
    "TransformTimes": ("nn", False),
    "ActiveTransform": ("i", False),
    "CoordinateSystem": ("s", False),
    "CoordSysTransform": ("s", False),
    "ColorSpace": ("s", False),
    "Include": ("s", False),
    "Import": ("s", False),
    "NamedMaterial": ("s", False),
    "ObjectBegin": ("s", False),
    "ObjectInstance": ("s", False),
    "MediumInterface": ("s?", False),
    "Option": ("", True),
    "Attribute": ("s", True),
    "Camera": ("s", True),
    "Film": ("s", True),
    "Sampler": ("s", True),
    "Integrator": ("s", True),
    "PixelFilter": ("s", True),
    "Accelerator": ("s", True),
    "Shape": ("s", True),
    "Material": ("s", True),
    "LightSource": ("s", True),
    "AreaLightSource": ("s", True),
    "MakeNamedMaterial": ("s", True),
    "MakeNamedMedium": ("s", True),
    "Texture": ("sss", True),
}


@dataclass(frozen=True)
class Location:
    file: Path
    line: int

    def __str__(self) -> str:
        return f"{self.file}:{self.line}"


def error(location: Location, message: str) -> SpectraceError:
    """The one-line error for a problem at file:line."""
    return SpectraceError(message, where=str(location))


def shown(text: str, limit: int = 60) -> str:
    return one_line(text if len(text) <= limit else text[:limit] + "...")


@dataclass
class Token:
    text: str
    # "string" (quoted, unescaped), "number", "word" (a keyword or bare true/false), "[" or "]", or "array": the
    # text between a "[" and its "]" when it holds no strings or comments (numbers or bare words)
    kind: str
    location: Location


def tokenize(text: str, path: Path):
    """The tokens of a pbrt file, with their file:line."""
    index, line, size = 0, 1, len(text)
    while index < size:
        char = text[index]
        if char == "\n":
            line += 1
            index += 1
        elif char in " \t\r\f\v":
            index += 1
        elif char == "#":
            end = text.find("\n", index)
            index = size if end < 0 else end
        elif char == "[" and (plain := _PLAIN_ARRAY.match(text, index)) is not None:
            yield Token(plain.group(1), "array", Location(path, line))
            line += plain.group(1).count("\n")
            index = plain.end()
        elif char in "[]":
            yield Token(char, char, Location(path, line))
            index += 1
        elif char == '"':
            start_line, index, parts = line, index + 1, []
            while True:
                if index >= size:
                    raise error(Location(path, start_line), "unterminated string")
                char = text[index]
                if char == '"':
                    index += 1
                    break
                if char == "\n":
                    raise error(Location(path, start_line), "unterminated string (a string ends on its own line)")
                if char == "\\" and index + 1 < size:
                    index += 1
                    escaped = text[index]
                    parts.append({"n": "\n", "t": "\t", "b": "\b", "f": "\f", "r": "\r"}.get(escaped, escaped))
                else:
                    parts.append(char)
                index += 1
            yield Token("".join(parts), "string", Location(path, start_line))
        else:
            end = index
            while end < size and text[end] not in ' \t\r\n\f\v"[]#':
                end += 1
            word = text[index:end]
            kind = "number" if _NUMBER.fullmatch(word) else "word"
            yield Token(word, kind, Location(path, line))
            index = end


@dataclass
class Parameter:
    type: str
    name: str
    values: list  # numbers, strings or booleans
    location: Location
    used: bool = False

    def label(self) -> str:
        return f"{self.type} {self.name}"


@dataclass
class Directive:
    name: str
    arguments: list  # numbers and strings
    parameters: list[Parameter]
    location: Location


class _TokenStream:
    def __init__(self, tokens, path: Path):
        self._tokens = iter(tokens)
        self._peeked: Token | None = None
        self.path = path
        self.last = Location(path, 1)

    def peek(self) -> Token | None:
        if self._peeked is None:
            self._peeked = next(self._tokens, None)
        return self._peeked

    def next(self, what: str) -> Token:
        token = self.peek()
        if token is None:
            raise error(self.last, f"the file ends where {what} was expected")
        self._peeked = None
        self.last = token.location
        return token


def _number(token: Token, what: str) -> float:
    if token.kind != "number":
        raise error(token.location, f"expected {what}, got '{shown(token.text)}'")
    value = float(token.text)
    if not math.isfinite(value):
        raise error(token.location, f"{shown(token.text)} is not a finite number")
    return value


def _parameter(stream: _TokenStream, declaration: Token) -> Parameter:
    words = declaration.text.split()
    if len(words) != 2:
        raise error(declaration.location, f'expected a parameter "type name", got "{shown(declaration.text)}"')
    kind, name = words
    if kind not in PARAMETER_TYPES:
        raise error(
            declaration.location,
            f"unknown parameter type '{shown(kind)}' in \"{shown(declaration.text)}\" "
            f"(pbrt-v4 knows {', '.join(PARAMETER_TYPES)})",
        )
    token = stream.next(f'a value for "{shown(declaration.text)}"')
    if token.kind == "array":
        return Parameter(kind, name, _array_values(token, kind, declaration), declaration.location)
    raw: list[Token] = []
    if token.kind == "[":
        while (item := stream.next(f"']' closing the values of \"{shown(declaration.text)}\"")).kind != "]":
            if item.kind == "[":
                raise error(item.location, "'[' inside a parameter's values")
            raw.append(item)
    else:
        raw.append(token)
    values: list = []
    for item in raw:
        if kind == "bool":
            if item.text not in ("true", "false"):
                raise error(
                    item.location, f"\"{shown(declaration.text)}\" takes true or false, got '{shown(item.text)}'"
                )
            values.append(item.text == "true")
        elif kind in ("string", "texture"):
            if item.kind != "string":
                raise error(
                    item.location, f"\"{shown(declaration.text)}\" takes quoted strings, got '{shown(item.text)}'"
                )
            values.append(item.text)
        elif kind == "spectrum" and item.kind == "string":
            values.append(item.text)
        else:
            values.append(_number(item, f'a number for "{shown(declaration.text)}"'))
    size = PARAMETER_TYPES[kind]
    if not values or (size and len(values) % size):
        count = f"a multiple of {size}" if size > 1 else "at least one"
        raise error(declaration.location, f'"{shown(declaration.text)}" needs {count} values, got {len(values)}')
    return Parameter(kind, name, values, declaration.location)


def _array_values(token: Token, kind: str, declaration: Token) -> list:
    """The values of a plain bracketed list, converted at once."""
    label = shown(declaration.text)
    if kind in ("string", "texture"):
        raise error(token.location, f'"{label}" takes quoted strings')
    items = token.text.split()
    if kind == "bool":
        if any(item not in ("true", "false") for item in items):
            raise error(token.location, f'"{label}" takes true or false')
        values: list = [item == "true" for item in items]
    else:
        if not _NUMBERS.fullmatch(token.text):
            bad = next((item for item in items if not _NUMBER.fullmatch(item)), token.text)
            raise error(token.location, f"expected a number for \"{label}\", got '{shown(bad)}'")
        numbers = np.array(items, dtype=np.float64)
        if not np.all(np.isfinite(numbers)):
            raise error(token.location, f'"{label}" holds a number beyond the float range')
        values = numbers.tolist()
    size = PARAMETER_TYPES[kind]
    if not values or (size and len(values) % size):
        count = f"a multiple of {size}" if size > 1 else "at least one"
        raise error(declaration.location, f'"{label}" needs {count} values, got {len(values)}')
    return values


def _read_text(path: Path, where: str, inclusions: Inclusions) -> str:
    """A scene file's text, counted against the scene's inclusions (checked before it is read); a `.gz` file is
    inflated (as pbrt-v4 reads it) within what the inclusions have left."""
    regular_file(path, None, what="pbrt scene file")
    try:
        if path.suffix.lower() != ".gz":
            inclusions.enter(path, where)
            data = path.read_bytes()
        else:
            inclusions.enter(path, where, size=0)
            with open(path, "rb") as source:
                inflater = file_inflater(path, source, where, "pbrt scene file")
                inflater.declare(inclusions.remaining_bytes(), "left of what a scene's included files may hold")
                data = inflater.read_all()
            inclusions.charge(path, len(data), where)
    except OSError as failure:
        raise SpectraceError(f"cannot read the file ({failure.strerror or failure})", where=str(path)) from None
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as failure:
        line = data[: failure.start].count(b"\n") + 1
        raise error(Location(path, line), "is not UTF-8 text (a binary file?)") from None


def _directives(path: Path, inclusions: Inclusions, where: str | None = None):
    """The directives of one file, Include and Import followed in place."""
    text = _read_text(path, where or str(path), inclusions)
    yield from _file_directives(text, path, inclusions)
    inclusions.leave()


def _file_directives(text: str, path: Path, inclusions: Inclusions):
    stream = _TokenStream(tokenize(text, path), path)
    while (token := stream.peek()) is not None:
        stream.next("a directive")
        if token.kind != "word" or token.text not in _DIRECTIVES:
            raise error(token.location, f"unknown directive '{shown(token.text)}'")
        shape, takes_parameters = _DIRECTIVES[token.text]
        arguments: list = []
        for slot in shape:
            if slot == "n":
                arguments.append(_number(stream.next(f"a number after {token.text}"), f"a number after {token.text}"))
            elif slot == "m":
                opening = stream.peek()
                if opening is not None and opening.kind == "array":
                    stream.next("[")
                    if len(opening.text.split()) != 16 or not _NUMBERS.fullmatch(opening.text):
                        raise error(opening.location, f"{token.text} takes 16 numbers in brackets")
                    arguments.append([float(number) for number in opening.text.split()])
                    continue
                bracketed = opening is not None and opening.kind == "["
                if bracketed:
                    stream.next("[")
                matrix = [
                    _number(stream.next(f"16 numbers after {token.text}"), f"a number in {token.text}")
                    for _ in range(16)
                ]
                if bracketed and stream.next(f"']' after {token.text}'s 16 numbers").kind != "]":
                    raise error(stream.last, f"{token.text} takes exactly 16 numbers")
                arguments.append(matrix)
            elif slot == "i":
                item = stream.next(f"a word after {token.text}")
                arguments.append(item.text)
            elif slot == "?":
                following = stream.peek()
                if following is not None and following.kind == "string":
                    arguments.append(stream.next("a string").text)
            else:
                item = stream.next(f"a quoted string after {token.text}")
                if item.kind != "string":
                    raise error(item.location, f"{token.text} needs a quoted string, got '{shown(item.text)}'")
                arguments.append(item.text)
        parameters: list[Parameter] = []
        if token.text == "Option":
            declaration = stream.next("an option after Option")
            parameters.append(_parameter(stream, declaration))
        elif takes_parameters:
            while (following := stream.peek()) is not None and following.kind == "string":
                parameters.append(_parameter(stream, stream.next("a parameter")))
        if token.text in ("Include", "Import"):
            included = Path(arguments[0])
            if not included.is_absolute():
                included = path.parent / included
            # pbrt-v4 splices an Include into the token stream: parameters after it continue the included file's
            # last directive (a medium's coefficients given beside the file that holds its grid).
            trailing = []
            if token.text == "Include":
                while (following := stream.peek()) is not None and following.kind == "string":
                    trailing.append(_parameter(stream, stream.next("a parameter")))
            if not included.is_file() and inclusions.skipped is not None:
                # missing_assets="placeholder" (placeholders.py): the survey judges the rest of the scene.
                what = f" (and the {len(trailing)} parameters after it)" if trailing else ""
                inclusions.skipped.append(
                    f"{token.location}: '{shown(str(arguments[0]), 200)}' is missing: skipped{what}"
                )
                continue
            if not included.is_file():
                raise error(
                    token.location, f"{token.text} names '{shown(str(arguments[0]), 200)}', which is not a file"
                )
            if not trailing:
                yield from _directives(included, inclusions, str(token.location))
                continue
            directives = list(_directives(included, inclusions, str(token.location)))
            if not directives:
                raise error(
                    trailing[0].location,
                    f"parameters after Include, but '{shown(str(arguments[0]), 200)}' "
                    "has no directive for them to continue",
                )
            directives[-1].parameters.extend(trailing)
            yield from directives
            continue
        yield Directive(token.text, arguments, parameters, token.location)


def parse_directives(path: str | Path, skipped: list[str] | None = None) -> list[Directive]:
    """Every directive of a pbrt-v4 scene, its Include and Import files followed in place; with a list `skipped`,
    an Include or Import of a missing file is skipped and told there instead of refused."""
    inclusions = Inclusions(MAX_INCLUDE_DEPTH, "Include/Import")
    inclusions.skipped = skipped
    return list(_directives(Path(path), inclusions))
