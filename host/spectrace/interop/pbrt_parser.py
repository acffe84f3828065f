"""pbrt-v4 scene files: the tokenizer, the directives and the graphics state, as pbrt-v4 reads them.

The result is a `PbrtScene`: the camera, film, sampler and integrator entities, and every shape, light, material
and texture with its world transform and the file:line it came from; the objects of ObjectBegin/ObjectEnd with their
shapes (under the transform at their definition) and each ObjectInstance's use of one (its CTM, which places the
object's shapes as pbrt-v4 does: the instance's CTM times each shape's).
What the entities mean is left to spectrace.interop.pbrt_v4, which maps them onto a spectrace scene.

The file format is pbrt-v4's ("pbrt-v4 File Format", pbrt.org/fileformat-v4): a directive is a keyword, its
positional arguments, and for most a parameter list of `"type name" value` or `"type name" [values]` entries;
`#` starts a comment. Transforms follow pbrt-v4: each transform directive post-multiplies the current transform
matrix (CTM), `Transform`/`ConcatTransform` give the matrix column by column (translation in entries 12..14), `Rotate`
normalises its axis, `LookAt` sets the camera frame with image right = up × forward (pbrt's left-handed camera), and
the CTM at `Camera` is camera-from-world. `WorldBegin` resets the CTM; `AttributeBegin`/`AttributeEnd` save and restore
the whole graphics state. `Include` and `Import` read another file in place (relative to the including file's
folder; a `.gz` file inflated, as pbrt-v4 reads it); `Import`'s only difference in pbrt-v4, parallel parsing,
changes nothing here. A file including itself, and files whose includes multiply (each including the next several
times), are refused (spectrace.io.input_files.Inclusions).

Bad input (an unterminated string, a number that is none, a directive missing its arguments, an unmatched
`AttributeEnd`) raises one SpectraceError naming file:line.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
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
            if not included.is_file():
                raise error(
                    token.location, f"{token.text} names '{shown(str(arguments[0]), 200)}', which is not a file"
                )
            yield from _directives(included, inclusions, str(token.location))
            continue
        yield Directive(token.text, arguments, parameters, token.location)


def parse_directives(path: str | Path) -> list[Directive]:
    """Every directive of a pbrt-v4 scene, its Include and Import files followed in place."""
    return list(_directives(Path(path), Inclusions(MAX_INCLUDE_DEPTH, "Include/Import")))


# ---------------------------------------------------------------- transforms (pbrt-v4's, on column vectors)


def translate(x: float, y: float, z: float) -> np.ndarray:
    matrix = np.eye(4)
    matrix[:3, 3] = (x, y, z)
    return matrix


def scale(x: float, y: float, z: float) -> np.ndarray:
    return np.diag([x, y, z, 1.0])


def rotate(angle_degrees: float, x: float, y: float, z: float, location: Location) -> np.ndarray:
    """Rotation by the angle about the axis, which pbrt-v4 normalises (Rodrigues' formula)."""
    axis = np.array([x, y, z], dtype=np.float64)
    length = float(np.linalg.norm(axis))
    if not length > 0.0:
        raise error(location, "Rotate needs a nonzero axis")
    a = axis / length
    theta = math.radians(angle_degrees)
    cross = np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])
    matrix = np.eye(4)
    matrix[:3, :3] = math.cos(theta) * np.eye(3) + math.sin(theta) * cross + (1.0 - math.cos(theta)) * np.outer(a, a)
    return matrix


def look_at(values: list[float], location: Location) -> np.ndarray:
    """pbrt-v4's LookAt: camera-from-world for a camera at eye looking at target, image right = up × forward."""
    eye, target, up = (np.array(values[i : i + 3], dtype=np.float64) for i in (0, 3, 6))
    forward = target - eye
    if not np.linalg.norm(forward) > 0.0:
        raise error(location, "LookAt's eye and look-at point coincide")
    forward /= np.linalg.norm(forward)
    up_length = np.linalg.norm(up)
    right = np.cross(up / up_length, forward) if up_length > 0 else np.zeros(3)
    if not np.linalg.norm(right) > 1e-12:
        raise error(location, "LookAt's up vector is zero or parallel to the viewing direction")
    right /= np.linalg.norm(right)
    new_up = np.cross(forward, right)
    world_from_camera = np.eye(4)
    world_from_camera[:3, 0], world_from_camera[:3, 1], world_from_camera[:3, 2] = right, new_up, forward
    world_from_camera[:3, 3] = eye
    return np.linalg.inv(world_from_camera)


def column_major(values: list[float]) -> np.ndarray:
    """The matrix of `Transform [m00 m10 m20 m30 m01 ...]`: pbrt lists it column by column."""
    return np.array(values, dtype=np.float64).reshape(4, 4).T


# Each transform directive's CTM from the CTM before it, its arguments and its file:line.
_TRANSFORMS = {
    "Translate": lambda ctm, arguments, location: ctm @ translate(*arguments),
    "Scale": lambda ctm, arguments, location: ctm @ scale(*arguments),
    "Rotate": lambda ctm, arguments, location: (
        ctm @ rotate(arguments[0], arguments[1], arguments[2], arguments[3], location)
    ),
    "LookAt": lambda ctm, arguments, location: ctm @ look_at(arguments, location),
    "Transform": lambda ctm, arguments, location: column_major(arguments[0]),
    "ConcatTransform": lambda ctm, arguments, location: ctm @ column_major(arguments[0]),
}


# ---------------------------------------------------------------- the graphics state and the scene


@dataclass
class Entity:
    """A camera, film, sampler, integrator, material, texture, shape or light, as the file states it."""

    directive: str
    kind: str
    parameters: list[Parameter]
    location: Location
    name: str = ""  # a named material's or texture's name

    def find(self, name: str, *types: str) -> Parameter | None:
        """The parameter called `name` (of one of `types`, when given), marked as read."""
        for parameter in self.parameters:
            if parameter.name == name and (not types or parameter.type in types):
                parameter.used = True
                return parameter
        return None

    def label(self) -> str:
        return f'{self.directive} "{shown(self.kind)}"'


@dataclass
class Shape:
    entity: Entity
    world_from_object: np.ndarray
    reverse_orientation: bool
    material: Entity | str | None  # an anonymous material, a named material's name, or None: pbrt's default
    area_light: Entity | None
    inside_medium: str = ""  # a MakeNamedMedium name, or "" (none)
    outside_medium: str = ""


@dataclass
class ObjectUse:
    """An ObjectInstance: the object's name and the CTM at the directive (world from the object's space)."""

    name: str
    world_from_instance: np.ndarray
    location: Location


@dataclass
class Light:
    entity: Entity
    world_from_light: np.ndarray


@dataclass
class Texture:
    entity: Entity
    value_type: str  # "spectrum" or "float"


@dataclass
class PbrtScene:
    camera: Entity | None = None
    camera_from_world: np.ndarray = field(default_factory=lambda: np.eye(4))
    film: Entity | None = None
    pixel_filter: Entity | None = None
    sampler: Entity | None = None
    integrator: Entity | None = None
    shapes: list[Shape] = field(default_factory=list)  # outside objects
    objects: dict[str, list[Shape]] = field(default_factory=dict)  # ObjectBegin's name -> its shapes
    object_uses: list[ObjectUse] = field(default_factory=list)  # every ObjectInstance, in file order
    lights: list[Light] = field(default_factory=list)
    named_materials: dict[str, Entity] = field(default_factory=dict)
    textures: dict[tuple[str, str], Texture] = field(default_factory=dict)  # (value type, name)
    media: dict[str, Entity] = field(default_factory=dict)  # MakeNamedMedium
    camera_medium: str = ""  # the medium the camera sits in (MediumInterface's outside at Camera)
    entities: list[Entity] = field(default_factory=list)  # every entity read, for the unread-parameter report
    unsupported: list[str] = field(default_factory=list)  # "file:line: what" for directives not imported
    has_world: bool = False


@dataclass
class _State:
    ctm: np.ndarray
    reverse_orientation: bool = False
    material: Entity | str | None = None
    area_light: Entity | None = None
    kind: str = "AttributeBegin"  # the directive that pushed it: AttributeBegin, TransformBegin or ObjectBegin
    opened: Location | None = None
    inside: str = ""  # MediumInterface: the named media inside and outside what follows ("": none)
    outside: str = ""
    # `Attribute "shape" ...`: default parameters for what follows, per target (shape, light, material, texture)
    attributes: dict[str, list[Parameter]] = field(default_factory=dict)


def _saved(state: _State, directive: str, location: Location) -> _State:
    return _State(
        state.ctm.copy(),
        state.reverse_orientation,
        state.material,
        state.area_light,
        directive,
        location,
        state.inside,
        state.outside,
        {target: list(parameters) for target, parameters in state.attributes.items()},
    )


_IGNORED = {
    # Directives that change nothing spectrace imports, reported once each with what they would have changed.
    "Accelerator": "spectrace builds its own BVH",
    "TransformTimes": "motion blur is not imported",
    "ActiveTransform": "motion blur is not imported",
    "ColorSpace": "RGB values are read as linear sRGB",
    "Option": "rendering options are not imported",
}


def read_scene(path: str | Path) -> PbrtScene:
    """The scene a pbrt-v4 file describes, objects and their instances, every entity with its file:line."""
    scene = PbrtScene()
    state = _State(np.eye(4))
    stack: list[_State] = []
    named_systems: dict[str, np.ndarray] = {}
    instances: dict[str, list[Shape]] = {}
    defining: tuple[str, list[Shape]] | None = None

    def entity(directive: Directive, kind: str, name: str = "", target: str = "") -> Entity:
        parameters = list(directive.parameters)
        # Attribute defaults fill in what the entity does not state; like pbrt, unread ones are not reported.
        stated = {parameter.name for parameter in parameters}
        for default in state.attributes.get(target, []):
            if default.name not in stated:
                parameters.append(Parameter(default.type, default.name, default.values, default.location, used=True))
        made = Entity(directive.name, kind, parameters, directive.location, name)
        scene.entities.append(made)
        return made

    for directive in parse_directives(path):
        name, arguments, location = directive.name, directive.arguments, directive.location
        if name in _TRANSFORMS:
            with np.errstate(over="ignore", invalid="ignore"):  # an overflow is reported just below
                state.ctm = _TRANSFORMS[name](state.ctm, arguments, location)
            if not np.isfinite(state.ctm).all():
                raise error(location, f"{name} makes the current transform overflow (entries beyond ±1.8e308)")
        elif name == "Identity":
            state.ctm = np.eye(4)
        elif name == "CoordinateSystem":
            named_systems[arguments[0]] = state.ctm.copy()
        elif name == "CoordSysTransform":
            if arguments[0] not in named_systems:
                raise error(
                    location, f"CoordSysTransform names '{shown(arguments[0])}', which no CoordinateSystem defined"
                )
            state.ctm = named_systems[arguments[0]].copy()
        elif name == "ReverseOrientation":
            state.reverse_orientation = not state.reverse_orientation
        elif name in ("AttributeBegin", "TransformBegin"):
            stack.append(_saved(state, name, location))
        elif name in ("AttributeEnd", "TransformEnd"):
            opening = "AttributeBegin" if name == "AttributeEnd" else "TransformBegin"
            if not stack or stack[-1].kind != opening:
                raise error(location, f"{name} without a matching {opening}")
            saved = stack.pop()
            if name == "TransformEnd":
                state.ctm = saved.ctm
            else:
                state = saved
        elif name == "Camera":
            # The camera's placement is the inverse of this camera-from-world: a singular one places no camera.
            if problem := limits.linear_map_problem(state.ctm[:3, :3]):
                raise error(location, f"the current transform (camera-from-world) {problem}")
            scene.camera = entity(directive, arguments[0])
            scene.camera_from_world = state.ctm.copy()
            scene.camera_medium = state.outside
            named_systems["camera"] = np.linalg.inv(state.ctm)
        elif name in ("Film", "Sampler", "Integrator"):
            setattr(scene, name.lower(), entity(directive, arguments[0]))
        elif name == "PixelFilter":
            scene.pixel_filter = entity(directive, arguments[0])
        elif name == "WorldBegin":
            scene.has_world = True
            state.ctm = np.eye(4)
            named_systems["world"] = state.ctm.copy()
        elif name == "WorldEnd":
            continue
        elif name == "Material":
            state.material = entity(directive, arguments[0], target="material")
        elif name == "MakeNamedMaterial":
            made = entity(directive, "", arguments[0], target="material")
            if arguments[0] in scene.named_materials:
                raise error(location, f"named material '{shown(arguments[0])}' defined twice")
            scene.named_materials[arguments[0]] = made
        elif name == "NamedMaterial":
            state.material = arguments[0]
        elif name == "Texture":
            texture_name, value_type, kind = arguments
            if value_type not in ("spectrum", "float"):
                raise error(location, f'texture type \'{shown(value_type)}\' (pbrt-v4 takes "spectrum" or "float")')
            scene.textures[(value_type, texture_name)] = Texture(
                entity(directive, kind, texture_name, target="texture"), value_type
            )
        elif name == "AreaLightSource":
            state.area_light = entity(directive, arguments[0], target="light")
        elif name == "LightSource":
            scene.lights.append(Light(entity(directive, arguments[0], target="light"), state.ctm.copy()))
        elif name == "MakeNamedMedium":
            if arguments[0] in scene.media:
                raise error(location, f"medium '{shown(arguments[0])}' defined twice")
            scene.media[arguments[0]] = entity(directive, "", arguments[0], target="medium")
        elif name == "MediumInterface":
            state.inside = arguments[0]
            state.outside = arguments[1] if len(arguments) > 1 else arguments[0]
        elif name == "Attribute":
            if arguments[0] not in ("shape", "light", "material", "medium", "texture"):
                raise error(
                    location, f"Attribute target '{shown(arguments[0])}' (shape, light, material, medium or texture)"
                )
            state.attributes = {
                **state.attributes,
                arguments[0]: [*state.attributes.get(arguments[0], []), *directive.parameters],
            }
        elif name == "Shape":
            shape = Shape(
                entity(directive, arguments[0], target="shape"),
                state.ctm.copy(),
                state.reverse_orientation,
                state.material,
                state.area_light,
                state.inside,
                state.outside,
            )
            (defining[1] if defining else scene.shapes).append(shape)
        elif name == "ObjectBegin":
            if defining is not None:
                raise error(location, "ObjectBegin inside another ObjectBegin")
            if arguments[0] in instances:
                raise error(location, f"object '{shown(arguments[0])}' defined twice")
            stack.append(_saved(state, name, location))
            defining = (arguments[0], [])
        elif name == "ObjectEnd":
            if defining is None or not stack or stack[-1].kind != "ObjectBegin":
                raise error(location, "ObjectEnd without a matching ObjectBegin")
            instances[defining[0]] = defining[1]
            defining = None
            state = stack.pop()
        elif name == "ObjectInstance":
            if defining is not None:
                raise error(location, "ObjectInstance inside ObjectBegin: pbrt-v4 does not nest instances either")
            if arguments[0] not in instances:
                raise error(location, f"ObjectInstance names '{shown(arguments[0])}', which no ObjectBegin defined")
            scene.objects.setdefault(arguments[0], instances[arguments[0]])
            scene.object_uses.append(ObjectUse(arguments[0], state.ctm.copy(), location))
        elif name in _IGNORED:
            scene.unsupported.append(f"{location}: {name} not imported ({_IGNORED[name]})")
    if stack:
        closing = {"AttributeBegin": "AttributeEnd", "TransformBegin": "TransformEnd", "ObjectBegin": "ObjectEnd"}
        opened = stack[-1].opened or Location(Path(path), 1)
        raise error(opened, f"{stack[-1].kind} is never closed by {closing[stack[-1].kind]}")
    return scene
