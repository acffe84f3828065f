"""Mitsuba 3 XML scenes -> spectrace scene TOML, for the subset spectrace represents exactly.

This module is the machinery every plugin shares: the XML with each element's path, property values, spectra,
transforms, references, errors and notes, and the plugins that are no material or light (shapes, twosided, the
sensor, film, sampler and integrator). Each BSDF and emitter is mapped by its spectrace module, which names the
Mitsuba plugins it imports (MITSUBA_PLUGINS) and converts them (`from_mitsuba`): spectrace.materials.<name> for
BSDFs, spectrace.lights.<name> for emitters (lights.area for a shape's), spectrace.textures.<name> for textures
(bitmap, checkerboard). The plugin -> module tables are built from the registries (MATERIALS, LIGHTS, TEXTURES).

A <texture> (by id or inline) becomes a [textures] table wherever a spectrum may be; it is kept exactly where the
material's or light's parameter table marks the parameter `textured` (`checked_textures`), so a parameter that
becomes textured there imports textures without a change here. Mitsuba's rectangle and PLY texture coordinates run
v up where spectrace's run down: textures on those shapes are imported with v flipped, as a material of their own.

Imported here: shapes obj, ply, serialized (shape_index), rectangle, cube, and the analytic sphere (center, radius),
disk and cylinder (p0, p1, radius) (face_normals on obj, ply, serialized and sphere); twosided around one BSDF (a
reflecting BSDF outside it is one-sided, black from the back, as in Mitsuba: its material takes two_sided = false);
the perspective sensor (fov with any fov_axis, or focal_length; to_world with lookat/translate/rotate/scale/matrix);
hdrfilm width/height; specfilm (its responses as the film's sensor, a CSV beside the TOML); the sampler's
sample_count and seed; integrators path (max_depth, rr_depth), direct (as path with max_depth 2), volpath/volpathmis
(as path, which renders media) and ptracer (as the light tracer, `light`); a shape's interior homogeneous medium
with constant sigma_t and scale, a constant or rgb albedo and an hg or isotropic phase (a null bsdf: the
index-matched boundary).
Spectra: rgb (uplifted exactly as Mitsuba does: Jakob & Hanika 2019, emission D65-based), float, spectrum given as
a value, "λ:v" pairs, wavelengths/values or an .spd file, and the spectrum plugins uniform, regular, irregular,
blackbody, d65 and srgb.
`$name` parameters and <default> are substituted as Mitsuba does.

Bad values are reported as one SpectraceError naming the file and the element path
(`scene.xml: shape[2]/transform/translate@x`, docs/mitsuba.md "Bad input"). Anything else (another plugin type,
a texture where spectrace takes none, other media) is reported in one error naming each unsupported plugin and
its line; choices spectrace makes differently (the reconstruction filter, the sampler) are returned as notes.
Parameters are documented in Mitsuba 3's plugin reference (mitsuba.readthedocs.io, "Plugin reference").
Mitsuba 0.6's bdpt integrator (Mitsuba 3 has none) imports as spectrace's bidirectional path tracer, `bdpt`; its
sppm and photonmapper integrators as spectrace's stochastic progressive photon mapping, `sppm`.
"""

from __future__ import annotations

import math
import os
import re
import tempfile
from functools import partial
from pathlib import Path
from typing import overload

import numpy as np

from spectrace.cameras import CAMERAS
from spectrace.core import limits
from spectrace.core.parameters import DISTRIBUTIONS, ROUGHNESS_RANGE
from spectrace.engine.bdpt import BDPT_MAX_SEGMENTS
from spectrace.errors import SpectraceError
from spectrace.geometry.transforms import transform_matrix
from spectrace.interop.mitsuba_tree import (
    Element,
    SceneTree,
    camel_to_snake,
    element_error,
    read_input_file,
    read_scene,
)
from spectrace.interop.mitsuba_tree import shown as _shown
from spectrace.io.output_files import check_output_file
from spectrace.lights import LIGHTS, area
from spectrace.materials import MATERIALS
from spectrace.number_text import DECIMAL, INTEGER
from spectrace.pixel_filters import PixelFilter
from spectrace.spectral.grid import GRID_MAX_NM, GRID_MIN_NM
from spectrace.textures import TEXTURES


def _modules_by_plugin(modules) -> dict:
    """Mitsuba plugin name -> the material or light module that imports it (its MITSUBA_PLUGINS)."""
    return {plugin: module for module in modules for plugin in module.MITSUBA_PLUGINS}


BSDF_MODULES = _modules_by_plugin(MATERIALS.values())
EMITTER_MODULES = _modules_by_plugin(LIGHTS.values())  # emitters of their own, <emitter> children of <scene>
SHAPE_EMITTER_MODULES = _modules_by_plugin((area,))  # emitters on a shape
TEXTURE_MODULES = _modules_by_plugin(TEXTURES.values())
# `twosided` wraps one BSDF: without it, a reflecting material imports with two_sided = false. The surface-detail
# adapters wrap one BSDF too, and become keys of its material (spectrace.materials.surface): normal_map, bump_map,
# opacity.
SURFACE_DETAIL_WRAPPERS = ("normalmap", "bumpmap", "mask")
BSDF_WRAPPERS = ("twosided", *SURFACE_DETAIL_WRAPPERS)
# Mitsuba sensor plugin → spectrace camera type, from the cameras' modules (spectrace.cameras).
CAMERA_PLUGINS = {plugin: name for name, module in CAMERAS.items() for plugin in module.MITSUBA_PLUGINS}
_SENSOR_PLUGINS = tuple(CAMERA_PLUGINS)
SUPPORTED = {
    "shape": ("obj", "ply", "serialized", "rectangle", "cube", "sphere", "disk", "cylinder", "shapegroup", "instance"),
    "bsdf": (*BSDF_MODULES, *BSDF_WRAPPERS),
    "emitter": (*SHAPE_EMITTER_MODULES, *EMITTER_MODULES),
    "texture": tuple(TEXTURE_MODULES),
    "sensor": tuple(CAMERA_PLUGINS),
    "film": ("hdrfilm", "specfilm"),
    "integrator": (
        "path",
        "direct",
        "volpath",
        "volpathmis",
        "moment",
        "aov",
        "ptracer",
        "bdpt",
        "sppm",
        "photonmapper",
    ),
    "medium": ("homogeneous",),
    "phase": ("hg", "isotropic"),
}


def _importable(tag: str, kind: str) -> bool:
    """Whether a nested object of this tag and type is one the importer reads (the rest, under a plugin it does not
    import, is named with it)."""
    if tag in ("sampler", "rfilter"):  # replaced by spectrace's own, with a note
        return True
    if tag in ("texture", "spectrum") and kind in _SPECTRUM_PLUGINS:
        return True
    return kind in SUPPORTED.get(tag, ())


def supported_text() -> str:
    """The plugins spectrace imports, per element: "shape obj, ply, ...; bsdf diffuse, ...; ..." (the modules'
    MITSUBA_PLUGINS through the registries, and what the importer itself reads)."""
    return "; ".join(f"{tag} {', '.join(kinds)}" for tag, kinds in SUPPORTED.items())


# Mitsuba's aov integrator's AOV types -> spectrace's film AOVs of the same definition (kernels/aov.cl).
_MITSUBA_AOVS = {"albedo": "albedo", "depth": "depth", "position": "position", "sh_normal": "normal"}
# Mitsuba BSDFs whose spectrace counterparts are being written; until then they are reported as unsupported.
_PLANNED_BSDFS: tuple[str, ...] = ()
# Mitsuba 3's named indices of refraction (its documentation's table, at about 589 nm), for int_ior / ext_ior.
_NAMED_IOR = {
    "vacuum": 1.0,
    "helium": 1.000036,
    "hydrogen": 1.000132,
    "air": 1.000277,
    "carbon dioxide": 1.00045,
    "water": 1.333,
    "acetone": 1.36,
    "ethanol": 1.361,
    "carbon tetrachloride": 1.461,
    "glycerol": 1.4729,
    "benzene": 1.501,
    "silicone oil": 1.52045,
    "bromine": 1.661,
    "water ice": 1.31,
    "fused quartz": 1.458,
    "pyrex": 1.470,
    "acrylic glass": 1.49,
    "polypropylene": 1.49,
    "bk7": 1.5046,
    "sodium chloride": 1.544,
    "amber": 1.55,
    "pet": 1.575,
    "diamond": 2.419,
}
_OBJECT_TAGS = (
    "scene",
    "shape",
    "bsdf",
    "emitter",
    "sensor",
    "film",
    "sampler",
    "integrator",
    "rfilter",
    "texture",
    "medium",
    "phase",
    "volume",
    "spectrum",
)
# Elements that set a named property of the object holding them.
# hdrfilm properties about the file Mitsuba writes, not the image: nothing to import.
_FILM_STORAGE = ("pixel_format", "component_format", "file_format", "banner")
_PROPERTY_TAGS = ("float", "integer", "string", "boolean", "rgb", "point", "vector", "transform")
# Every tag Mitsuba 3's parser knows (src/core/parser.cpp): the objects, the properties, a transform's steps, and
# the parser's own (<include> and <path> are gone once the file is read: spectrace.interop.mitsuba_tree). Any other
# tag is a misspelling or another program's; Mitsuba refuses it, the import reports it (--strict: an error).
_TRANSFORM_STEPS = ("translate", "rotate", "scale", "matrix", "lookat")
_KNOWN_TAGS = frozenset(
    (*_OBJECT_TAGS, *_PROPERTY_TAGS, *_TRANSFORM_STEPS, "ref", "alias", "default", "include", "path")
)
_FILM_DIAGONAL_MM = math.hypot(36.0, 24.0)  # Mitsuba's focal_length is in 35 mm film equivalent (36 x 24 mm)
MITSUBA_DEFAULT_FILM = (768, 576)  # hdrfilm's default width and height
MITSUBA_DEFAULT_FOCAL_LENGTH_MM = 50.0  # the perspective sensor's, when neither fov nor focal_length is given
MAX_NESTING = limits.MAX_NESTING
# The spectrum plugins imported as spectra (spectrum_element), also when written as <texture type="...">.
_SPECTRUM_PLUGINS = ("uniform", "irregular", "regular", "blackbody", "d65", "srgb")
# Shapes whose Mitsuba texture coordinates run v up the image where spectrace's (for the same surface) run down:
# Mitsuba's rectangle has v = 0 at y = -1, spectrace's at y = +1; Mitsuba reads a PLY's v as stored, spectrace
# flips it (as both do an OBJ's vt). Textures on them are imported with v flipped.
_V_UP_SHAPES = ("rectangle", "ply", "serialized")


# ---------------------------------------------------------------- values

_FLOAT32_MAX = float(np.finfo(np.float32).max)
_INTEGER_LIMIT = 2**63  # TOML's integers are 64-bit


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


class MitsubaImporter:
    """One import of an XML scene. The material and light modules' `from_mitsuba` functions get it, and use its
    helpers: property values (`spectrum`, `number`, `integer`, `vector`, `text`, `properties`, `child`, `resolve`),
    the rough BSDFs' shared `roughness` and `ior`, `fail(element, message, attribute)` for the one-line error naming
    the file and element path, `unsupported_plugin(element, detail)` for what spectrace cannot represent (they return
    None then), and `notes` for what it represents differently."""

    # Mitsuba 3's named indices of refraction, for int_ior / ext_ior and their defaults.
    NAMED_IOR = _NAMED_IOR

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
        self._properties: dict[int, Properties] = {}
        self._object_names: dict[int, str] = {}  # shapegroup element -> its spectrace object's name
        self.search_folders: list[Path] = [xml_path.parent]  # <path> folders, then the scene's
        self.materials: dict[str, dict] = {}
        self._material_of_element: dict[tuple[int, bool], str] = {}
        self.textures: dict[str, dict] = {}
        self._texture_of_element: dict[tuple[int, bool], str] = {}
        self._texture_elements: dict[str, Element] = {}
        self._flip_v = False  # textures being converted for a shape whose v runs up (_V_UP_SHAPES)
        self._used_texture = False  # a texture was converted or reused since this was last reset
        self._resolving: list[int] = []  # elements being converted, to stop reference cycles
        self.origins: dict[str, Element] = {}  # TOML key path -> the element it was imported from

    @property
    def flip_v(self) -> bool:
        """Whether the material being converted is for a shape whose v runs up (its textures' v flipped)."""
        return self._flip_v

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
        """An attribute ($parameters were substituted when the file was read: spectrace.interop.mitsuba_tree)."""
        return element.get(key, default)

    def required(self, element: Element, key: str) -> str:
        value = self.attribute(element, key)
        if value is None:
            raise self.fail(element, f"<{_shown(element.tag)}> needs the attribute '{key}'", key)
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
            if child.tag in _OBJECT_TAGS and kind is not None and not _importable(child.tag, kind):
                self.unsupported_plugin(child)
            pending += child.children

    def at(self, element: Element) -> str:
        """'line N' of an element, or 'line N of other.xml' for one from an <include>d file (notes, messages)."""
        return f"line {element.line}" + (
            f" of {_shown(element.file.name, 100)}" if element.file not in (None, self.xml_path) else ""
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
            raise self.fail(element, f"expected a finite number, got '{_shown(text)}'", key)
        value = float(text)
        if not abs(value) <= _FLOAT32_MAX:
            raise self.fail(element, f"{_shown(text)} is beyond the float32 range (±3.4e38)", key)
        return value

    def numbers(self, element: Element, key: str = "value", default: str | None = None) -> list[float]:
        text = self.attribute(element, key, default)
        if text is None:
            raise self.fail(element, f"<{_shown(element.tag)}> needs the attribute '{key}'", key)
        parts = [part for part in re.split(r"[,\s]+", text.strip()) if part]
        if not parts:
            raise self.fail(element, "expected numbers, got an empty value", key)
        return [self.parse_number(part, element, key) for part in parts]

    def number(self, element: Element, key: str = "value") -> float:
        values = self.numbers(self.resolve(element), key)
        if len(values) != 1:
            raise self.fail(
                element,
                f'<{_shown(element.tag)} name="{_shown(element.get("name") or "")}"> needs one '
                f"number, got {len(values)}",
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
                raise self.fail(element, f"expected an integer, got '{_shown(text)}'", "value")
            value = int(number)
        if not -_INTEGER_LIMIT < value < _INTEGER_LIMIT:
            raise self.fail(element, f"integer {_shown(text)} is out of range", "value")
        if low is not None and value < low:
            raise self.fail(
                element,
                f'<{element.tag} name="{_shown(element.get("name") or "")}"> must be at least {low}, got {value}',
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
                raise self.fail(element, f"<{_shown(element.tag)}> needs 3 numbers, got {len(values)}", "value")
            return values
        return [self.parse_number(self.attribute(element, axis, repr(default)), element, axis) for axis in "xyz"]

    def resolve(self, element: Element) -> Element:
        if element.tag != "ref":
            return element
        identifier = self.required(element, "id")
        if identifier not in self.ids:
            raise self.fail(element, f"reference to undefined id '{_shown(identifier)}'", "id")
        return self.ids[identifier]

    def enter(self, element: Element) -> None:
        """Mark an element being converted: references may nest, but not loop or run deeper than elements may."""
        if id(element) in self._resolving:
            raise self.fail(element, f"{element.label()} refers to itself (through <ref>)")
        if len(self._resolving) >= MAX_NESTING:
            raise self.fail(element, f"references nested more than {MAX_NESTING} deep")
        self._resolving.append(id(element))

    def leave(self) -> None:
        self._resolving.pop()

    def properties(self, element: Element) -> Properties:
        """Named children (property elements, references, nested objects); unnamed nested objects by tag. The same
        object each time for one element, so that what was read of it adds up."""
        if id(element) in self._properties:
            return self._properties[id(element)]
        found: dict[str, Element] = {}
        for index, child in enumerate(element.children):
            name = child.get("name")
            if name is None and child.tag in _PROPERTY_TAGS:
                raise self.fail(child, f"<{child.tag}> needs the attribute 'name' (the property it sets)", "name")
            if name is None and child.tag in _OBJECT_TAGS:
                name = child.tag if child.tag not in found else f"{child.tag}#{index}"
            found[name or f"#{index}"] = child
        properties = self._properties[id(element)] = Properties(element, found)
        return properties

    # -------------------------------------------------- transforms

    def transform_steps(self, element: Element) -> list[dict]:
        """A <transform> as spectrace transform steps, first step first (Mitsuba applies them in file order)."""
        steps: list[dict] = []
        for step in element.children:
            if step.tag == "translate":
                steps.append({"translate": self.vector(step)})
            elif step.tag == "scale":
                if step.get("value") is not None:
                    values = self.numbers(step, "value")
                    if len(values) not in (1, 3):
                        raise self.fail(step, f"scale needs 1 or 3 numbers, got {len(values)}", "value")
                    factors = values * 3 if len(values) == 1 else values
                    steps.append({"scale": values[0] if len(values) == 1 else values})
                else:
                    factors = self.vector(step, default=1.0)
                    steps.append({"scale": factors})
                if 0.0 in factors:
                    raise self.fail(step, "scale factors must be non-zero (a zero scale flattens the shape)")
            elif step.tag == "rotate":
                angle = self.parse_number(self.attribute(step, "angle", "0"), step, "angle")
                axis = self.vector(step)
                if not any(axis):
                    raise self.fail(step, "the rotation axis (x, y, z) must not be zero")
                if abs(float(np.linalg.norm(axis)) - 1.0) <= 1e-7:
                    steps.append({"rotate": {"axis": axis, "angle": angle}})
                else:
                    # Mitsuba does not normalise the axis: its Rodrigues matrix with a longer axis also stretches.
                    steps.append({"matrix": _unnormalised_rotation(axis, angle).tolist()})
                    self.notes.append(
                        f"{self.at(step)}: rotate axis {tuple(axis)} is not a unit vector; Mitsuba does not "
                        "normalise it (the step also scales), and neither does the import"
                    )
            elif step.tag == "matrix":
                values = self.numbers(step, "value")
                if len(values) == 9:
                    values = values[0:3] + [0.0] + values[3:6] + [0.0] + values[6:9] + [0.0, 0.0, 0.0, 0.0, 1.0]
                if len(values) != 16:
                    raise self.fail(step, f"a matrix needs 16 (or 9) numbers, got {len(values)}", "value")
                steps.append({"matrix": [values[i : i + 4] for i in range(0, 16, 4)]})
            elif step.tag == "lookat":
                steps.append({"matrix": self.look_at(step).tolist()})
            elif step.tag in _KNOWN_TAGS:
                self.unsupported_plugin(step, " transform step")
            # an unknown tag (a misspelt step) is reported by report_unknown_tags
        return steps

    def look_at(self, element: Element) -> np.ndarray:
        """Mitsuba's look_at: columns left = up × dir, up' = dir × left, dir, and the origin."""
        vectors = {}
        for key, default in (("origin", None), ("target", None), ("up", "0, 1, 0")):
            vectors[key] = np.array(self.numbers(element, key, default))
            if len(vectors[key]) != 3:
                raise self.fail(element, f"{key} needs 3 numbers, got {len(vectors[key])}", key)
        origin, target, up = vectors["origin"], vectors["target"], vectors["up"]
        direction = target - origin
        left = np.cross(up, direction)
        if not (np.linalg.norm(direction) > 0 and np.linalg.norm(left) > 0):
            raise self.fail(element, "lookat needs target != origin and up not parallel to the view")
        direction /= np.linalg.norm(direction)
        left /= np.linalg.norm(left)
        matrix = np.eye(4)
        matrix[:3, 0], matrix[:3, 1], matrix[:3, 2], matrix[:3, 3] = left, np.cross(direction, left), direction, origin
        return matrix

    def to_world(self, properties: dict[str, Element], key: str = "to_world") -> np.ndarray:
        element = properties.get(key)
        if element is None:
            return np.eye(4)
        element = self.resolve(element)
        steps = self.transform_steps(element)
        try:
            with np.errstate(over="ignore", invalid="ignore"):  # an overflow is reported just below
                matrix = transform_matrix(steps, where="")
        except SpectraceError as error:
            raise self.fail(element, error.message) from None
        if not np.isfinite(matrix).all():
            raise self.fail(element, "the transform overflows (its product is not finite)")
        return matrix

    # -------------------------------------------------- spectra

    def spectrum(self, element: Element, key: str) -> dict | None:
        """A spectrace spectrum table for a Mitsuba colour/spectrum property, or None (unsupported, recorded)."""
        element = self.resolve(element)
        self.enter(element)
        try:
            return self._spectrum(element, key)
        finally:
            self.leave()

    def _spectrum(self, element: Element, key: str) -> dict | None:
        if element.tag == "rgb":
            values = self.numbers(element, "value")
            if len(values) not in (1, 3):
                raise self.fail(element, f"an rgb colour needs 3 numbers (or 1), got {len(values)}", "value")
            self.non_negative(values, element, "value")
            return {"rgb": values * 3 if len(values) == 1 else values}
        if element.tag == "float":
            value = self.number(element)
            self.non_negative([value], element, "value")
            return {"value": value}
        if element.tag == "spectrum":
            return self.spectrum_element(element)
        if element.tag == "texture":
            return self.texture(element, key)
        raise self.fail(element, f"'{key}' must be a colour or spectrum, got <{_shown(element.tag)}>")

    # -------------------------------------------------- textures

    def texture(self, element: Element, key: str) -> dict | None:
        """A <texture> where a spectrum may be: a reference to its [textures] table, converted by its module on
        first use (once more, v flipped, for shapes whose v runs up). Whether the parameter takes a texture is
        decided by the material's or light's parameter table (`checked_textures`), not here."""
        if self.kind(element) in _SPECTRUM_PLUGINS:  # Mitsuba 3's spectra are textures; its serialiser says so
            return self.spectrum_element(element)
        self._used_texture = True
        cache = (id(element), self._flip_v)
        if cache in self._texture_of_element:
            return {"texture": self._texture_of_element[cache]}
        module = TEXTURE_MODULES.get(self.kind(element))
        if module is None:
            self.unsupported_object(element, f" as {key}")
            return None
        table = module.from_mitsuba(self, element, self.properties(element))
        if table is None:
            return None
        base = (self.attribute(element, "id") or f"{key}_texture") + ("_flipped_v" if self._flip_v else "")
        name = _unique_name(base, {**self.textures, **TEXTURES})  # a texture named after a type is ambiguous
        self.textures[name] = table
        self._texture_of_element[cache] = name
        self._texture_elements[name] = element
        self.origins[f"textures.{name}"] = element
        return {"texture": name}

    def scalar_texture(self, element: Element, key: str) -> dict | None:
        """A texture where Mitsuba reads one number per point (a bump map's height, an opacity, an α): an RGB bitmap
        there gives its luminance in Mitsuba, so it is imported as a texture of its own with luminance = true (a
        grey one as it is)."""
        known = set(self.textures)
        reference = self.texture(element, key)
        if reference is None or list(reference) != ["texture"]:
            return reference
        name = reference["texture"]
        table = self.textures[name]
        if table["type"] != "bitmap" or table.get("luminance"):
            return reference
        from spectrace.io.images import read_texture_image

        values, _ = read_texture_image(self.toml_folder / table["file"], f"{self.xml_path}: {key}")
        if values.shape[-1] == 1:
            return reference
        if name not in known:  # made for this use: it becomes the luminance, and a colour use makes its own
            table["luminance"] = True
            self._texture_of_element = {k: v for k, v in self._texture_of_element.items() if v != name}
            return reference
        grey = f"{name}_luminance"
        if grey not in self.textures:
            self.textures[grey] = table | {"luminance": True}
            self._texture_elements[grey] = self._texture_elements[name]
            self.origins[f"textures.{grey}"] = self._texture_elements[name]
        return {"texture": grey}

    def texture_type(self, name: str) -> str:
        return self.textures[name]["type"]

    def checked_textures(self, table: dict, module) -> bool:
        """False, recording each, where a texture was given to a parameter that `module`'s parameter table does not
        mark `textured`: marking one there is all it takes for the import to pass textures on to it."""
        textured = {parameter.name for parameter in module.PARAMETERS if parameter.textured}
        fine = True
        for key, value in table.items():
            if isinstance(value, dict) and list(value) == ["texture"] and key not in textured:
                self.unsupported_plugin(
                    self._texture_elements[value["texture"]],
                    f" as {key} of {module.NAME} (spectrace's {module.NAME} takes no texture there)",
                )
                fine = False
        return fine

    def uv_placement(self, texture: Element, properties: dict[str, Element], squares: float = 1.0) -> dict | None:
        """uv_scale and uv_offset for a texture's `to_uv`, which spectrace represents when it scales and translates
        (st = uv · uv_scale + uv_offset); `squares` multiplies both (a checkerboard's squares per unit of Mitsuba's
        uv'). Only what differs from the default (squares, 0) is written."""
        scale, offset = [1.0, 1.0], [0.0, 0.0]
        if "to_uv" in properties:
            element = self.resolve(properties["to_uv"])
            if element.tag != "transform":
                raise self.fail(element, f"to_uv must be a <transform>, got <{_shown(element.tag)}>")
            matrix = self.to_world(properties, "to_uv")
            # Mitsuba keeps the 2D affine part of the 4 x 4 matrix (x and y rows and columns, and the translation).
            if matrix[0, 1] != 0.0 or matrix[1, 0] != 0.0:
                self.unsupported_plugin(
                    texture, " with a to_uv that rotates or shears (spectrace's textures take uv_scale and uv_offset)"
                )
                return None
            scale, offset = [matrix[0, 0], matrix[1, 1]], [matrix[0, 3], matrix[1, 3]]
        if self._flip_v:  # the lookup at (u, 1 - v): st_v = -scale_v · v + scale_v + offset_v
            scale, offset = [scale[0], -scale[1]], [offset[0], scale[1] + offset[1]]
        table = {}
        if scale != [1.0, 1.0]:
            table["uv_scale"] = [float(squares * value) for value in scale]
        if offset != [0.0, 0.0]:
            table["uv_offset"] = [float(squares * value) for value in offset]
        return table

    def input_file(self, element: Element, what: str = "file") -> str:
        """A file named by a property's value, relative to the XML: checked to exist, and written relative to the
        TOML."""
        path = self.find_file(element, self.required(element, "value"))
        try:
            found = path.is_file()
        except (OSError, ValueError):  # e.g. a name too long for the file system
            found = False
        if not found:
            raise self.fail(element, f"{what} '{_shown(str(path), 200)}' does not exist or is not a file", "value")
        return _relative_path(path, self.toml_folder)

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
                f"unknown {_shown(element.get('name') or element.tag)} '{_shown(value)}' ({', '.join(options)})",
                "value",
            )
        return value

    def default_emission(self) -> dict:
        """What an emitter emits when its spectrum is not given: Mitsuba's d65 of unit luminance."""
        return {"rgb": [1.0, 1.0, 1.0]}

    def emission(self, properties: dict, key: str) -> dict | None:
        """An emitter's spectrum `key`, or the default emission where it is not given."""
        return self.spectrum(properties[key], key) if key in properties else self.default_emission()

    def non_negative(self, values: list[float], element: Element, key: str) -> None:
        """Reflectances, emission and optical constants are never negative."""
        if any(value < 0.0 for value in values):
            raise self.fail(element, f"negative value {min(values):g}; spectra must be >= 0", key)

    def spectrum_element(self, element: Element) -> dict | None:
        kind = element.get("type")
        if kind is None:
            if element.get("filename") is not None:
                return {"values": self.spd_file(element)}
            if element.get("wavelengths") is not None:
                wavelengths = self.numbers(element, "wavelengths")
                values = self.numbers(element, "values")
                return {"values": self.pairs(element, wavelengths, values, "values")}
            text = self.required(element, "value")
            if ":" in text:
                wavelengths, values = [], []
                for entry in (entry.strip() for entry in text.split(",")):
                    parts = entry.split(":")
                    if len(parts) != 2:
                        raise self.fail(
                            element,
                            f"expected 'wavelength:value' pairs separated by commas, got '{_shown(entry)}'",
                            "value",
                        )
                    wavelengths.append(self.parse_number(parts[0], element, "value"))
                    values.append(self.parse_number(parts[1], element, "value"))
                return {"values": self.pairs(element, wavelengths, values, "value")}
            value = self.number(element)
            self.non_negative([value], element, "value")
            return {"value": value}
        properties = self.properties(element)
        if kind == "uniform":
            if "value" not in properties:
                return {"value": 1.0}
            value = self.number(properties["value"])
            self.non_negative([value], properties["value"], "value")
            return {"value": value}
        if kind == "irregular":
            wavelengths_element = self.child(properties, "wavelengths", element)
            values_element = self.child(properties, "values", element)
            wavelengths = self.numbers(wavelengths_element, "value")
            values = self.numbers(values_element, "value")
            return {"values": self.pairs(values_element, wavelengths, values, "value")}
        if kind == "regular":
            low = self.number(self.child(properties, "wavelength_min", element))
            high = self.number(self.child(properties, "wavelength_max", element))
            values_element = self.child(properties, "values", element)
            values = self.numbers(values_element, "value")
            if not 0.0 < low < high:
                raise self.fail(element, f"needs 0 < wavelength_min < wavelength_max, got {low:g} and {high:g}")
            wavelengths = [float(w) for w in np.linspace(low, high, len(values))] if len(values) > 1 else [low]
            return {"values": self.pairs(values_element, wavelengths, values, "value")}
        if kind == "blackbody":
            from spectrace.spectral.blackbody import WIEN_DISPLACEMENT, planck_radiance

            temperature_element = self.child(properties, "temperature", element)
            temperature = self.number(temperature_element)
            if not temperature > 0.0:
                raise self.fail(
                    temperature_element, f"a black body's temperature must be > 0 K, got {temperature:g}", "value"
                )
            # Mitsuba's black body is Planck's law in W/(m² sr nm); spectrace's is normalised to a peak of 1.
            with np.errstate(all="ignore"):
                peak = float(planck_radiance(np.array([WIEN_DISPLACEMENT / temperature * 1e9]), temperature)[0])
            if not (math.isfinite(peak) and peak > 0.0):
                raise self.fail(
                    temperature_element, f"a black body of {temperature:g} K has no finite radiance", "value"
                )
            return {"blackbody": temperature, "scale": peak}
        if kind == "d65":
            from spectrace.spectral.colorimetry import spectrum_to_xyz
            from spectrace.spectral.illuminants import cie_illuminant

            scale = self.number(properties["scale"]) if "scale" in properties else 1.0
            if "scale" in properties:
                self.non_negative([scale], properties["scale"], "value")
            if "color" in properties:
                self.unsupported_plugin(element, " with a color")
                return None
            # Mitsuba's d65 has unit luminance, i.e. film Y = 1 in spectrace's convention.
            return {"spectrum": "cie:D65", "scale": scale / float(spectrum_to_xyz(cie_illuminant("D65"))[1])}
        if kind == "srgb" and "color" in properties:
            return self.spectrum(properties["color"], "color")
        self.unsupported_plugin(element)
        return None

    def pairs(self, element: Element, wavelengths: list[float], values: list[float], key: str) -> list[list[float]]:
        """(wavelength, value) pairs, checked: as many wavelengths as values, wavelengths positive and increasing,
        values not negative."""
        if len(wavelengths) != len(values):
            raise self.fail(element, f"{len(wavelengths)} wavelengths but {len(values)} values", key)
        if wavelengths[0] <= 0.0:
            raise self.fail(element, f"wavelengths must be > 0 nm, got {wavelengths[0]:g}", key)
        for before, after in zip(wavelengths, wavelengths[1:]):
            if not after > before:
                raise self.fail(element, f"wavelengths must increase, got {before:g} then {after:g}", key)
        self.non_negative(values, element, key)
        return [[w, v] for w, v in zip(wavelengths, values)]

    def spd_file(self, element: Element) -> list[list[float]]:
        """An .spd file: lines 'wavelength value' (nm), '#' comments."""
        name = self.required(element, "filename")
        path = self.find_file(element, name)
        where = f"{self.where(element)}@filename"
        data = read_input_file(path, where)
        try:
            lines = data.decode("utf-8").splitlines()
        except UnicodeDecodeError as error:
            raise self.fail(
                element, f"spectrum file '{_shown(name)}' is not UTF-8 text (byte {error.start})", "filename"
            ) from None
        wavelengths, values = [], []
        for number, line in enumerate(lines, start=1):
            text = line.split("#", 1)[0].strip()
            if not text:
                continue
            parts = text.split()
            if len(parts) != 2 or not all(DECIMAL.fullmatch(part) for part in parts):
                raise self.fail(
                    element,
                    f"line {number} of '{_shown(name)}': expected 'wavelength value', got '{_shown(text)}'",
                    "filename",
                )
            pair = [float(part) for part in parts]
            if not all(abs(value) <= _FLOAT32_MAX for value in pair):
                raise self.fail(
                    element, f"line {number} of '{_shown(name)}': beyond the float32 range (±3.4e38)", "filename"
                )
            wavelengths.append(pair[0])
            values.append(pair[1])
        if not wavelengths:
            raise self.fail(element, f"spectrum file '{_shown(name)}' holds no 'wavelength value' lines", "filename")
        return self.pairs(element, wavelengths, values, "filename")

    # -------------------------------------------------- materials

    def material(self, element: Element | None, owner: str, flip_v: bool = False, emits: bool = False) -> str | None:
        """The name of the spectrace material for a (possibly referenced) bsdf, defining it on first use. flip_v:
        for a shape whose v runs up (_V_UP_SHAPES); a textured bsdf then becomes a material of its own, with its
        textures' v flipped. Without a bsdf, Mitsuba's default: diffuse 0.5, one-sided as its plain diffuse is,
        and black on a shape that emits (measured: Mitsuba 3's emitter without a bsdf reflects nothing)."""
        if element is None:
            name, reflectance = ("default_emitter", 0.0) if emits else ("default", 0.5)
            if name not in self.materials:
                self.materials[name] = {"type": "diffuse", "reflectance": {"value": reflectance}}
                if not emits:
                    self.materials[name]["two_sided"] = False
            return name
        bsdf = self.resolve(element)
        if (id(bsdf), flip_v) in self._material_of_element:
            return self._material_of_element[(id(bsdf), flip_v)]
        base = self.attribute(bsdf, "id") or f"{owner}_bsdf"
        name = _unique_name(base, self.materials)
        saved = self._flip_v, self._used_texture
        self._flip_v, self._used_texture = flip_v, False
        try:
            table = self.material_table(bsdf)
            textured = self._used_texture
        finally:
            self._flip_v, self._used_texture = saved[0], saved[1] or self._used_texture
        if table is None:
            return None
        if textured and flip_v:
            name = _unique_name(f"{base}_flipped_v", self.materials)
            self.notes.append(
                f"{self.at(bsdf)}: {bsdf.label()} on a rectangle or PLY shape: their texture coordinates run v up "
                f"in Mitsuba and down in spectrace, so it is imported as material '{name}' with its textures' v "
                "flipped"
            )
        self.materials[name] = table
        self._material_of_element[(id(bsdf), flip_v)] = name
        if not textured:  # the same material whichever way v runs
            self._material_of_element[(id(bsdf), not flip_v)] = name
        self.origins[f"materials.{name}"] = bsdf
        for key, value in table.items():
            # What the loader says of a texture a key takes (a normal map read as colours) is told at the texture.
            if isinstance(value, dict) and list(value) == ["texture"]:
                self.origins[f"materials.{name}.{key}"] = self._texture_elements[value["texture"]]
        return name

    def material_table(self, bsdf: Element, two_sided: bool = False) -> dict | None:
        """two_sided: the bsdf is inside a `twosided` wrapper. Outside one, Mitsuba's reflecting BSDFs are black
        from the back of the surface, so their materials take two_sided = false; those that transmit have two
        sides by nature."""
        self.enter(bsdf)
        try:
            return self._material_table(bsdf, two_sided)
        finally:
            self.leave()

    def _material_table(self, bsdf: Element, two_sided: bool) -> dict | None:
        kind = self.kind(bsdf) if bsdf.tag == "bsdf" else None
        properties = self.properties(bsdf)
        if kind == "twosided":
            nested = self.nested(properties, "bsdf")
            if len(nested) != 1:
                self.unsupported_plugin(bsdf, " with two different sides")
                return None
            return self.material_table(nested[0], two_sided=True)
        if kind in SURFACE_DETAIL_WRAPPERS:
            return self.surface_detail(bsdf, kind, properties, two_sided)
        if kind in BSDF_MODULES:
            table = BSDF_MODULES[kind].from_mitsuba(self, bsdf, properties)
            # A module may import a plugin as another material (conductor "none" as mirror): that one's table counts.
            if table is None or not self.checked_textures(table, MATERIALS[table["type"]]):
                return None
            if not two_sided and not MATERIALS[table["type"]].MODEL.has_transmission:
                table["two_sided"] = False
            return table
        self.unsupported_object(bsdf, " (not yet in spectrace)" if kind in _PLANNED_BSDFS else "")
        return None

    def surface_detail(self, bsdf: Element, kind: str, properties: Properties, two_sided: bool) -> dict | None:
        """The material of the one bsdf that a normalmap, bumpmap or mask adapter wraps, with the adapter's key
        added: normal_map (its `normalmap` texture), bump_map and bump_scale (its one texture, `scale`), opacity
        (`opacity`, Mitsuba's default 0.5). Mitsuba's bumpmap displaces by scale · h along the normal (its tangents
        are dp/du + scale · ∂h/∂u · n), which is spectrace's bump_scale. A normal or bump map's
        `use_shadowing_function` (Mitsuba's default true) is spectrace's shadowing_function."""
        nested = self.nested(properties, "bsdf")
        properties.understood(*properties.keys())  # each key is judged below
        if len(nested) != 1:
            raise self.fail(bsdf, f"{bsdf.label()} needs exactly one nested bsdf, got {len(nested)}")
        expected = {"normalmap": "normalmap", "bumpmap": "scale", "mask": "opacity"}[kind]
        textures = [key for key, child in properties.items() if self.resolve(child).tag == "texture"]
        shadowing = kind != "mask"
        for key, child in properties.items():
            if shadowing and key == "use_shadowing_function":
                continue
            # A bumpmap's texture may have any name.
            if key != expected and self.resolve(child).tag != "bsdf" and not (kind == "bumpmap" and key in textures):
                self.unsupported_plugin(bsdf, f" with {_shown(key)}")
                return None
        detail: dict = {}
        if kind == "normalmap":
            texture = self.resolve(self.child(properties, "normalmap", bsdf))
            if texture.tag == "texture" and self.kind(texture) == "rawconstant":
                constant = self.constant_normal_map(texture)
                if constant is None:
                    return None
                if constant:  # the unturned normal (0, 0, 1) needs no map
                    detail["normal_map"] = constant
            elif texture.tag != "texture" or self.kind(texture) != "bitmap":
                self.unsupported_plugin(texture, " as normalmap (spectrace's normal maps are bitmaps or rawconstant)")
                return None
            else:
                detail["normal_map"] = self.texture(texture, "normal_map")
        elif kind == "bumpmap":
            if len(textures) != 1:
                raise self.fail(bsdf, f"{bsdf.label()} needs exactly one nested texture, got {len(textures)}")
            texture = self.resolve(properties[textures[0]])
            if self.kind(texture) in _SPECTRUM_PLUGINS:  # a constant height: no gradient, nothing to import
                self.unsupported_plugin(texture, " as a bump map (spectrace's bump maps are bitmaps or checkerboards)")
                return None
            detail["bump_map"] = self.scalar_texture(texture, "bump_map")
            if "scale" in properties:
                detail["bump_scale"] = self.number(properties["scale"])
        else:
            detail["opacity"] = self.opacity(properties["opacity"]) if "opacity" in properties else 0.5
        if any(value is None for value in detail.values()):
            return None
        if shadowing and detail:
            switch = properties.get("use_shadowing_function")
            detail["shadowing_function"] = True if switch is None else self.boolean(switch)
        table = self.material_table(nested[0], two_sided)
        if table is None:
            return None
        one_of = ("opacity",) if "opacity" in detail else ("normal_map", "bump_map")
        taken = [key for key in one_of if key in table]
        if taken:
            self.unsupported_plugin(
                bsdf,
                f" around a bsdf with a {taken[0].replace('_', ' ')} already (a spectrace material takes one "
                f"{'opacity' if one_of == ('opacity',) else 'normal map or bump map'})",
            )
            return None
        return table | detail

    def constant_normal_map(self, texture: Element) -> dict | None:
        """A `rawconstant` texture as a normal map: one tangent-space normal 2 c − 1 everywhere. The unturned normal
        (c = (0.5, 0.5, 1)) is an empty dict (no map); any other is a 1 x 1 float OpenEXR of c written beside the
        TOML, read raw. None when it is no normal (recorded)."""
        properties = self.properties(texture)
        value = self.resolve(self.child(properties, "value", texture))
        if value.tag not in ("vector", "rgb", "float"):
            self.unsupported_plugin(texture, " as normalmap (its value is a vector, an rgb or a float)")
            return None
        numbers = self.vector(value) if value.tag == "vector" else self.numbers(value)
        if len(numbers) not in (1, 3):
            raise self.fail(value, f"a rawconstant normal map needs 1 or 3 numbers, got {len(numbers)}", "value")
        c = np.resize(np.asarray(numbers, np.float64), 3)
        if not np.linalg.norm(2.0 * c - 1.0) > 0.0:
            raise self.fail(value, "a rawconstant normal map of value 0.5, 0.5, 0.5 holds no direction", "value")
        if np.allclose(c, (0.5, 0.5, 1.0), rtol=0.0, atol=1e-6):
            return {}
        from spectrace.io.exr import write_exr

        with tempfile.TemporaryDirectory(prefix="spectrace-normal-") as folder:
            path = Path(folder) / "normal.exr"
            write_exr(path, np.tile(c, (1, 1, 1)), None, {})
            data = path.read_bytes()
        name = f"{self.side_stem}.normal_map_{sum(key.endswith('.exr') for key in self.side_files) + 1}.exr"
        self.side_files[name] = data
        texture_name = _unique_name(self.attribute(texture, "id") or "normal_map_constant", self.textures)
        self.textures[texture_name] = {"type": "bitmap", "file": name, "raw": True}
        self._texture_elements[texture_name] = texture
        self.origins[f"textures.{texture_name}"] = texture
        self.notes.append(
            f"{self.at(texture)}: the rawconstant normal map is a 1 x 1 image written to {name} beside the scene"
        )
        return {"texture": texture_name}

    def opacity(self, element: Element) -> float | dict | None:
        """A mask's opacity: a number in [0, 1] or a texture."""
        resolved = self.resolve(element)
        if resolved.tag == "texture":
            return self.scalar_texture(resolved, "opacity")
        if resolved.tag != "float":
            self.unsupported_plugin(resolved, " as opacity (spectrace's opacity is a number or a texture)")
            return None
        value = self.number(resolved)
        if not 0.0 <= value <= 1.0:
            raise self.fail(resolved, f"opacity must lie in [0, 1], got {value:g}", "value")
        return value

    def text(self, element: Element) -> str:
        return self.attribute(self.resolve(element), "value") or ""

    def boolean(self, element: Element) -> bool:
        value = self.text(element)
        if value not in ("true", "false"):
            raise self.fail(element, f"expected true or false, got '{_shown(value)}'", "value")
        return value == "true"

    def roughness(self, bsdf: Element, properties: dict[str, Element]) -> float | dict | None:
        """Microfacet α of a rough Mitsuba BSDF (its default 0.1), or a texture reference for a textured `alpha`; None
        when spectrace cannot represent it (recorded)."""
        alpha: float | dict | None
        if "alpha_u" in properties or "alpha_v" in properties:
            u_element = properties.get("alpha_u", properties.get("alpha_v"))
            v_element = properties.get("alpha_v", properties.get("alpha_u"))
            assert u_element is not None and v_element is not None  # one of them is given, standing for both
            if "texture" in (self.resolve(u_element).tag, self.resolve(v_element).tag):
                self.unsupported_plugin(bsdf, " with a textured alpha_u or alpha_v (anisotropic roughness)")
                return None
            alpha_u = self.number(self.resolve(u_element))
            alpha_v = self.number(self.resolve(v_element))
            alpha = alpha_u
            if alpha_u != alpha_v:
                # spectrace's microfacet lobes are isotropic: the geometric mean keeps the distribution's peak
                # D(0) = 1 / (π αu αv), so the highlight's height, and loses its stretch.
                alpha = math.sqrt(alpha_u * alpha_v)
                self.warnings.append(
                    f"{_shown(str(bsdf.file or self.xml_path), 200)}:{bsdf.line}: {bsdf.label()}: anisotropic "
                    f"roughness alpha_u = {alpha_u:g}, alpha_v = {alpha_v:g} approximated by the isotropic "
                    f"alpha = sqrt(alpha_u alpha_v) = {alpha:.4g} (spectrace's microfacet lobes are isotropic)"
                )
        elif "alpha" in properties:
            element = self.resolve(properties["alpha"])
            # A texture's α is checked against the range when the scene loads, as any roughness texture is.
            alpha = self.scalar_texture(element, "roughness") if element.tag == "texture" else self.number(element)
            if alpha is None:
                return None
            if isinstance(alpha, dict) and list(alpha) == ["value"]:  # a spectrum plugin standing for a number
                alpha = float(alpha["value"])
        else:
            alpha = 0.1
        if isinstance(alpha, float) and not ROUGHNESS_RANGE.contains(alpha):
            raise self.fail(bsdf, f"alpha must lie in {ROUGHNESS_RANGE} for spectrace, got {alpha:g}")
        return alpha

    def distribution(self, bsdf: Element, properties: dict[str, Element]) -> str:
        """The microfacet distribution of a rough Mitsuba BSDF (its default: beckmann)."""
        if "distribution" not in properties:
            return "beckmann"
        element = self.resolve(properties["distribution"])
        value = self.text(element)
        if value not in DISTRIBUTIONS:
            raise self.fail(element, f"unknown distribution '{_shown(value)}' (Mitsuba's: ggx, beckmann)", "value")
        return value

    def ior(self, bsdf: Element, properties: dict[str, Element], key: str, default: float) -> float:
        """An index of refraction property (int_ior, ext_ior): a number or one of Mitsuba's names."""
        if key not in properties:
            return default
        element = self.resolve(properties[key])
        if element.tag == "string":
            name = self.text(element)
            if name.lower() not in _NAMED_IOR:
                raise self.fail(
                    element, f"unknown {key} '{_shown(name)}' (Mitsuba names: {', '.join(_NAMED_IOR)})", "value"
                )
            return _NAMED_IOR[name.lower()]
        value = self.number(element)
        if not value > 0.0:
            raise self.fail(element, f"{key} must be > 0, got {value:g}", "value")
        return value

    # -------------------------------------------------- scene parts

    def shape(self, element: Element, index: int) -> dict | None:
        kind = self.kind(element)
        if kind not in SUPPORTED["shape"]:
            self.unsupported_object(element)
            return None
        properties = self.properties(element)
        name = element.get("id") or element.get("name") or f"{kind}{index}"
        table: dict = {"name": name}
        steps: list[dict] = []
        if kind in ("obj", "ply", "serialized"):
            filename = self.child(properties, "filename", element)
            table |= {"type": "mesh", "file": self.input_file(filename, "mesh file")}
            if kind == "serialized" and "shape_index" in properties:
                table["shape_index"] = self.integer(properties["shape_index"], low=0)
        else:
            table["type"] = kind
        if kind == "sphere":
            radius = self.number(properties["radius"]) if "radius" in properties else 1.0
            if not radius > 0.0:
                raise self.fail(properties["radius"], f"a sphere's radius must be > 0, got {radius:g}", "value")
            centre = self.vector(properties["center"]) if "center" in properties else [0.0, 0.0, 0.0]
            steps += [{"scale": radius}, {"translate": centre}]
        if kind == "cylinder":
            steps += self.cylinder_steps(properties)
        if "to_world" in properties:
            steps += self.transform_steps(properties["to_world"])
        flip = "flip_normals" in properties and self.text(properties["flip_normals"]) == "true"
        if flip and kind in ("sphere", "disk", "cylinder"):
            table["flip_normals"] = True
        elif flip:
            if kind != "rectangle":
                self.unsupported_plugin(element, " with flip_normals")
            steps.insert(0, {"scale": [1.0, 1.0, -1.0]})  # mirroring the flat square turns its face over
        if steps:
            table["transform"] = steps
        if kind in ("obj", "ply", "serialized", "sphere"):
            face_normals = self.boolean(properties["face_normals"]) if "face_normals" in properties else False
            # Mitsuba 3 shades its meshes smoothly, computing vertex normals when the file has none, unless
            # face_normals is set; spectrace makes none up unless asked (face_normals = false) and shades the sphere
            # smoothly by default.
            if face_normals or kind != "sphere":
                table["face_normals"] = face_normals
        bsdf = next(iter(self.nested(properties, "bsdf")), None)
        emitter = next(iter(self.nested(properties, "emitter")), None)
        interior = self.interior_medium(properties)
        if interior is not None:
            table["interior"] = interior
        if interior is not None and bsdf is not None and self.kind(self.resolve(bsdf)) == "null":
            table["material"] = None  # Mitsuba's null bsdf: the index-matched boundary of spectrace's media
        else:
            table["material"] = self.material(bsdf, name, flip_v=kind in _V_UP_SHAPES, emits=emitter is not None)
        if emitter is not None:
            module = SHAPE_EMITTER_MODULES.get(self.kind(emitter))
            if module is None:
                self.unsupported_plugin(emitter, " on a shape")
            elif (
                emitter_table := module.from_mitsuba(self, emitter, self.properties(emitter))
            ) is not None and self.checked_textures(emitter_table, module):
                table["emitter"] = emitter_table
        if table["material"] is None and "interior" in table:
            del table["material"]
            return table
        return table if table["material"] is not None else None

    def instance(self, element: Element, objects: dict[str, dict]) -> dict | None:
        """A Mitsuba `instance`: its shapegroup (imported once, as a spectrace object) placed by its to_world."""
        properties = self.properties(element)
        groups = self.nested(properties, "shape")
        if len(groups) != 1 or self.kind(groups[0]) != "shapegroup":
            raise self.fail(element, 'an instance places exactly one shapegroup (<ref id="..."/>)')
        (group,) = groups
        if id(group) not in self._object_names:
            self._object_names[id(group)] = self.shapegroup(group, objects)
        name = self._object_names[id(group)]
        if not objects[name]["shapes"]:
            return None
        table: dict = {"object": name}
        if "to_world" in properties:
            steps = self.transform_steps(self.resolve(properties["to_world"]))
            self.to_world(properties)  # the same steps, checked as for shapes: non-zero scales, a finite product
            if steps:
                table["transform"] = steps
        return table

    def shapegroup(self, group: Element, objects: dict[str, dict]) -> str:
        """A Mitsuba `shapegroup` as a spectrace object (its shapes in their own space, stored once); its name in
        `objects`. Mitsuba 3 refuses emitters ("Instancing of emitters is not supported") and nested instancing in a
        shapegroup; so does the import. Spheres, disks and cylinders stay exact, as in Mitsuba's instances."""
        name = _unique_name(group.get("id") or "shapegroup", objects)
        tables: list[dict] = []
        for index, child in enumerate(self.nested(self.properties(group), "shape")):
            kind = self.kind(child)
            if kind in ("shapegroup", "instance"):
                raise self.fail(child, f"a {kind} inside a shapegroup: nested instancing is not supported")
            emitters = [c for c in self.properties(child).values() if self.resolve(c).tag == "emitter"]
            if emitters:
                raise self.fail(
                    emitters[0], "emitters cannot be instanced: a shapegroup's shapes do not emit (nor in Mitsuba 3)"
                )
            if (table := self.shape(child, index)) is None:
                continue
            self.origins[f"objects.{name}.shapes[{len(tables)}]"] = child
            tables.append(table)
        objects[name] = {"shapes": tables}
        return name

    def interior_medium(self, properties: Properties) -> dict | None:
        """A shape's `interior` homogeneous medium as spectrace's interior: σs = scale·albedo·σt and
        σa = scale·(1 − albedo)·σt (Mitsuba 3's homogeneous: albedo default 0.75, sigma_t default 1), with its
        Henyey–Greenstein phase (Mitsuba's hg: g default 0.8; isotropic: 0). A constant or rgb sigma_t and a
        constant or rgb albedo are mapped; other coloured coefficients are reported."""
        self.nested(properties, "medium")  # read here, whatever their names
        if "exterior" in properties:
            self.unsupported_plugin(self.resolve(properties["exterior"]), " as an exterior medium")
        if "interior" not in properties:
            return None
        medium = self.resolve(properties["interior"])
        if self.kind(medium) != "homogeneous":
            self.unsupported_object(medium)
            return None
        items = self.properties(medium)
        items.understood("sample_emitters")  # how Mitsuba samples, not what it renders
        given: dict = {}
        for key, default in (("sigma_t", 1.0), ("albedo", 0.75)):
            value: dict | None = self.spectrum(items[key], key) if key in items else {"value": default}
            # An rgb albedo or sigma_t is uplifted as Mitsuba's spectral variants uplift a reflectance (they refuse
            # an rgb sigma_t outside [0, 1], and so does spectrace); `scale` then multiplies sigma_t.
            if value is None or set(value) not in ({"value"}, {"rgb"}):
                self.unsupported_plugin(medium, f" with a coloured {key}")
                return None
            if "rgb" in value and not all(0.0 <= c <= 1.0 for c in value["rgb"]):
                raise self.fail(
                    items[key],
                    f"a medium's rgb {key} must lie in [0, 1] (as Mitsuba's spectral variants "
                    f"require), got {value['rgb']}",
                    "value",
                )
            given[key] = value
        albedo = given["albedo"].get("value", 0.0)
        if albedo > 1.0:
            raise self.fail(items["albedo"], f"a medium's albedo must not exceed 1, got {albedo:g}", "value")
        scale = self.number(items["scale"]) if "scale" in items else 1.0
        if not scale > 0.0:
            raise self.fail(items["scale"], f"a medium's scale must be > 0, got {scale:g}", "value")
        g = 0.0
        phase = next(iter(self.nested(items, "phase")), None)
        if phase is not None and self.kind(phase) == "hg":
            phase_items = self.properties(phase)
            g = self.number(phase_items["g"]) if "g" in phase_items else 0.8
        elif phase is not None and self.kind(phase) != "isotropic":
            self.unsupported_object(phase)
            return None
        if "rgb" in given["albedo"] or "rgb" in given["sigma_t"]:
            return {**self._coloured_coefficients(given["sigma_t"], given["albedo"], scale, medium), "g": g}
        sigma_t = float(given["sigma_t"]["value"]) * scale
        return {"sigma_a": {"value": sigma_t * (1.0 - albedo)}, "sigma_s": {"value": sigma_t * albedo}, "g": g}

    def _coloured_coefficients(self, sigma_t: dict, albedo: dict, scale: float, medium: Element) -> dict:
        """σs = σt(λ)·a(λ), σa = σt(λ)·(1 − a(λ)) with σt = scale · sigma_t, each of sigma_t and the albedo a number
        or an rgb in [0, 1] uplifted as Mitsuba uplifts a reflectance (Jakob & Hanika 2019; measured: Mitsuba 3's
        homogeneous medium gives the same σt(λ) and σs(λ) within 0.1 %), tabulated every 5 nm (smooth curves)."""
        from spectrace.spectral.grid import GRID_MAX_NM, GRID_MIN_NM
        from spectrace.spectral.uplift import uplift_reflectance

        wavelengths = np.arange(GRID_MIN_NM, GRID_MAX_NM + 0.5, 5.0)

        def tabulated(value: dict) -> np.ndarray:
            if "value" in value:
                return np.full(len(wavelengths), float(value["value"]))
            spectrum = uplift_reflectance(value["rgb"], where=self.where(medium))[0]
            return np.array([float(spectrum.evaluate(w)) for w in wavelengths])

        extinction, albedo_values = scale * tabulated(sigma_t), tabulated(albedo)
        return {
            "sigma_a": {
                "values": [[float(w), t * (1.0 - a)] for w, t, a in zip(wavelengths, extinction, albedo_values)]
            },
            "sigma_s": {"values": [[float(w), t * a] for w, t, a in zip(wavelengths, extinction, albedo_values)]},
        }

    def cylinder_steps(self, properties: dict[str, Element]) -> list[dict]:
        """Mitsuba's cylinder from p0 to p1 of `radius`: the unit cylinder scaled by (r, r, |p1 − p0|), turned by the
        frame Mitsuba builds around the axis (its coordinate_system, Duff et al. 2017, which sets where u = 0 is),
        moved to p0."""
        radius = self.number(properties["radius"]) if "radius" in properties else 1.0
        if not radius > 0.0:
            raise self.fail(properties["radius"], f"a cylinder's radius must be > 0, got {radius:g}", "value")
        p0 = np.array(self.vector(properties["p0"]) if "p0" in properties else [0.0, 0.0, 0.0])
        p1 = np.array(self.vector(properties["p1"]) if "p1" in properties else [0.0, 0.0, 1.0])
        length = float(np.linalg.norm(p1 - p0))
        if not length > 0.0:
            raise self.fail(properties.get("p1") or properties["p0"], "a cylinder's p0 and p1 must differ", "x")
        n = (p1 - p0) / length
        sign = math.copysign(1.0, n[2])
        a = -1.0 / (sign + n[2])
        b = n[0] * n[1] * a
        s = [1.0 + sign * n[0] * n[0] * a, sign * b, -sign * n[0]]
        t = [b, sign + n[1] * n[1] * a, -n[1]]
        frame = np.eye(4)
        frame[:3, 0], frame[:3, 1], frame[:3, 2], frame[:3, 3] = s, t, n, p0
        return [{"scale": [radius, radius, length]}, {"matrix": frame.tolist()}]

    def light(self, element: Element) -> dict | None:
        kind = self.kind(element)
        properties = self.properties(element)
        matrix = self.to_world(properties)
        if kind in EMITTER_MODULES:
            table = EMITTER_MODULES[kind].from_mitsuba(self, element, properties, matrix)
            return table if table is None or self.checked_textures(table, LIGHTS[table["type"]]) else None
        self.unsupported_object(element, " (not on a shape)" if kind in SHAPE_EMITTER_MODULES else "")
        return None

    def sensor(self, element: Element, data: dict) -> None:
        kind = self.kind(element)
        if kind not in _SENSOR_PLUGINS:
            self.unsupported_object(element)
            return
        properties = self.properties(element)
        for key, child in properties.items():
            if key.startswith("principal_point_offset"):
                properties.understood(key)
                if self.number(child) != 0.0:
                    self.unsupported_plugin(element, f" with {_shown(key)}")
        # Nested or referenced (a scene may declare its film or sampler at the top and refer to it by id).
        film = next(iter(self.nested(properties, "film")), None)
        width, height = MITSUBA_DEFAULT_FILM
        self.origins["film"] = element
        if film is not None:
            self.origins["film"] = film
            if self.kind(film) not in SUPPORTED["film"]:
                self.unsupported_plugin(film)
            film_properties = self.properties(film)
            film_properties.understood(*_FILM_STORAGE)
            width = self.integer(film_properties["width"], low=1) if "width" in film_properties else width
            height = self.integer(film_properties["height"], low=1) if "height" in film_properties else height
            for key in list(film_properties.keys()):
                if key.startswith("crop_"):
                    film_properties.understood(key)
                    self.unsupported_plugin(film, f" with {_shown(key)}")
            rfilter = next(iter(self.nested(film_properties, "rfilter")), None)
            sensor = self.specfilm_sensor(film, film_properties) if self.kind(film) == "specfilm" else {}
        else:
            rfilter = None
            sensor = {}
        data["film"] = {"width": width, "height": height, "filter": self.pixel_filter(rfilter), **(sensor or {})}
        matrix = self.to_world(properties)
        linear = matrix[:3, :3]
        if not np.linalg.det(linear) > 0:
            self.unsupported_plugin(element, " with a mirroring or singular to_world")
            return
        origin = matrix[:3, 3]
        forward = linear @ [0.0, 0.0, 1.0]
        up = linear @ [0.0, 1.0, 0.0]
        data["camera"] = {
            "type": CAMERA_PLUGINS[kind],
            "origin": origin.tolist(),
            "target": (origin + forward / np.linalg.norm(forward)).tolist(),
            "up": (up / np.linalg.norm(up)).tolist(),
        }
        if kind == "orthographic":
            # Mitsuba's view spans [-1, 1] along camera x and [-1/aspect, 1/aspect] along y, then to_world scales it.
            half_x, half_y = np.linalg.norm(linear @ [1.0, 0.0, 0.0]), np.linalg.norm(up)
            if not math.isclose(half_x, half_y, rel_tol=1e-6):
                self.unsupported_plugin(element, " whose to_world scales x and y differently")
                return
            data["camera"]["view_width"] = 2.0 * float(half_x)
        else:
            data["camera"]["fov"] = self.fov_x(properties, width / height, element)
            data["camera"]["fov_axis"] = "x"
        if kind == "thinlens":
            if "aperture_radius" not in properties:
                raise self.fail(element, "thinlens needs aperture_radius (Mitsuba 3 requires it too)", "type")
            aperture = self.number(properties["aperture_radius"])
            # Mitsuba's default focus is 10 000 scene units away: as good as infinity for a scene of metres.
            focus = self.number(properties["focus_distance"]) if "focus_distance" in properties else 1e4
            if not aperture >= 0.0 or not focus > 0.0:
                raise self.fail(element, "thinlens needs aperture_radius >= 0 and focus_distance > 0", "type")
            data["camera"] |= {"aperture_radius": aperture, "focus_distance": focus}
        if "near_clip" in properties:
            data["camera"]["near_clip"] = self.number(properties["near_clip"])
            if not data["camera"]["near_clip"] >= 0.0:
                raise self.fail(properties["near_clip"], "near_clip must be 0 or more", "value")
        if "far_clip" in properties:
            # Mitsuba's default is 10 000 scene units; spectrace's none, the same for scenes of any usual size.
            far = self.number(properties["far_clip"])
            if not far > data["camera"].get("near_clip", 0.0):
                raise self.fail(properties["far_clip"], "far_clip must be more than near_clip", "value")
            data["camera"]["far_clip"] = far
        self.origins["camera"] = element
        sampler = next(iter(self.nested(properties, "sampler")), None)
        # A pinhole has no focus: Mitsuba's perspective sensor takes focus_distance and does nothing with it.
        properties.understood("focus_distance")
        if sampler is not None:
            sampler_properties = self.properties(sampler)
            data["sampler"] = {}
            self.origins["sampler"] = sampler
            if "sample_count" in sampler_properties:
                data["sampler"]["spp"] = self.integer(sampler_properties["sample_count"], low=1)
            if "seed" in sampler_properties:
                data["sampler"]["seed"] = self.integer(sampler_properties["seed"], low=0)
            if self.kind(sampler) != "independent":
                self.notes.append(
                    f"{self.at(sampler)}: sampler '{_shown(sampler.get('type') or '')}' not imported: "
                    "spectrace uses its own sampler (same sample count)"
                )

    def specfilm_sensor(self, film: Element, properties: Properties) -> dict | None:
        """A specfilm's response curves (its named spectra) as the film's sensor: a CSV beside the TOML
        (`side_files`) with one channel per curve, in the file's order (as Mitsuba's film holds them; its EXR
        sorts them by name, as spectrace's does), on a 1 nm grid over their
        wavelengths, each zero outside its own (as Mitsuba evaluates a tabulated spectrum). Both films record
        ∫ L(λ) s(λ) dλ per channel. Curves beyond 360-830 nm widen the film's range there, with the RGB uplifts
        continued (film.extend_rgb), as Mitsuba evaluates its RGB spectra at any wavelength."""
        curves: dict[str, np.ndarray] = {}
        for key in list(dict.keys(properties)):
            child = self.resolve(dict.__getitem__(properties, key))
            if child.tag not in ("spectrum", "texture") or (
                child.tag == "texture" and self.kind(child) not in _SPECTRUM_PLUGINS
            ):
                continue
            properties.understood(key)
            table = self.spectrum_element(child)
            if table is None:
                return None
            if "values" in table:
                curves[key] = np.asarray(table["values"], np.float64).reshape(-1, 2)
            elif "value" in table:  # Mitsuba's uniform spectrum spans the visible
                curves[key] = np.array([[GRID_MIN_NM, table["value"]], [GRID_MAX_NM, table["value"]]])
            else:
                self.unsupported_plugin(film, f" with the response '{_shown(key)}' (a {_shown(self.kind(child))})")
                return None
            if not re.fullmatch(r"[A-Za-z0-9_.\-]+", key):
                raise self.fail(child, f"response name '{_shown(key)}' must be letters, digits, '_', '.' or '-'")
        if not curves:
            raise self.fail(film, "a specfilm needs at least one response spectrum (Mitsuba requires one)")
        lo = math.floor(min(curve[0, 0] for curve in curves.values()))
        hi = math.ceil(max(curve[-1, 0] for curve in curves.values()))
        if lo < 200 or hi > 2500:
            raise self.fail(film, f"its responses span {lo}-{hi} nm; spectrace's film reaches 200-2500 nm")
        grid = np.arange(lo, hi + 1, dtype=np.float64)
        columns = [np.interp(grid, c[:, 0], c[:, 1], left=0.0, right=0.0) for c in curves.values()]
        lines = ["# The response curves of a Mitsuba 3 specfilm, on a 1 nm grid", f"wavelength_nm,{','.join(curves)}"]
        lines += [f"{w:g}," + ",".join(f"{column[i]:.9g}" for column in columns) for i, w in enumerate(grid)]
        name = f"{self.side_stem}.sensor.csv"
        self.side_files[name] = "\n".join(lines) + "\n"
        sensor: dict = {"sensor": name}
        if lo < GRID_MIN_NM or hi > GRID_MAX_NM:
            sensor |= {"wavelengths": [min(lo, int(GRID_MIN_NM)), max(hi, int(GRID_MAX_NM))], "extend_rgb": True}
            self.notes.append(
                f"the specfilm's responses reach {lo}-{hi} nm: the film's range is widened to take them, with RGB "
                "colours continued beyond the visible as Mitsuba does"
            )
        self.notes.append(f"the specfilm's responses are the film's sensor, written to {name} beside the scene")
        return sensor

    def pixel_filter(self, rfilter: Element | None) -> dict:
        """The film's filter: Mitsuba 3's own default, its Gaussian of σ = 0.5, when the file names none."""
        if rfilter is None:
            return {"type": "gaussian", "stddev": 0.5}
        kind = rfilter.get("type") or ""
        properties = self.properties(rfilter)
        if kind == "box":
            return {"type": "box"}
        if kind == "tent":
            return {"type": "tent"}  # radius 1 in Mitsuba, fixed
        if kind == "gaussian":
            stddev = self.number(properties["stddev"]) if "stddev" in properties else 0.5
            try:  # the filters' own range (spectrace.pixel_filters)
                PixelFilter("gaussian", stddev=stddev)
            except SpectraceError as exc:
                raise self.fail(rfilter, exc.message, "type") from None
            return {"type": "gaussian", "stddev": stddev}
        if kind == "mitchell":
            table: dict[str, object] = {"type": "mitchell", "radius": 2.0}
            for key in ("B", "C"):
                if key in properties:
                    value = self.number(properties[key])
                    if not 0.0 <= value <= 1.0:
                        raise self.fail(rfilter, f"{key} must lie in [0, 1], got {value:g}", "type")
                    table[key.lower()] = value
            return table
        self.notes.append(
            f"{self.at(rfilter)}: reconstruction filter '{_shown(kind)}' not imported: spectrace has box, tent, "
            "gaussian and mitchell; a box filter used"
        )
        return {"type": "box"}

    def fov_x(self, properties: dict[str, Element], aspect: float, element: Element) -> float:
        """Horizontal field of view in degrees, as Mitsuba derives it from fov + fov_axis or focal_length."""
        if "fov" in properties:
            fov = self.number(properties["fov"])
            if not 0.0 < fov < 180.0:
                raise self.fail(properties["fov"], f"fov must lie in (0, 180) degrees, got {fov:g}", "value")
            axis = self.text(properties["fov_axis"]) if "fov_axis" in properties else "x"
        else:
            focal = MITSUBA_DEFAULT_FOCAL_LENGTH_MM
            if "focal_length" in properties:
                focal_element = self.resolve(properties["focal_length"])
                text = self.required(focal_element, "value").strip().removesuffix("mm")
                focal = self.parse_number(text, focal_element, "value")
                if not focal > 0.0:
                    raise self.fail(focal_element, f"focal_length must be > 0 mm, got {focal:g}", "value")
            fov, axis = math.degrees(2.0 * math.atan(_FILM_DIAGONAL_MM / (2.0 * focal))), "diagonal"
        tan_half = math.tan(math.radians(fov) / 2.0)
        if axis == "smaller":
            axis = "y" if aspect > 1.0 else "x"
        elif axis == "larger":
            axis = "x" if aspect > 1.0 else "y"
        if axis == "y":
            tan_half *= aspect
        elif axis == "diagonal":
            tan_half *= aspect / math.hypot(aspect, 1.0)
        elif axis != "x":
            raise self.fail(
                properties["fov_axis"],
                f"unknown fov_axis '{_shown(axis)}' (x, y, diagonal, smaller or larger)",
                "value",
            )
        return math.degrees(2.0 * math.atan(tan_half))

    def integrator(self, element: Element, data: dict) -> None:
        kind = self.kind(element)
        if kind not in SUPPORTED["integrator"]:
            self.unsupported_object(element)
            return
        properties = self.properties(element)
        settings = {"type": "path", "max_depth": -1}  # Mitsuba's path tracers default to unbounded depth
        if "max_depth" in properties:
            settings["max_depth"] = self.integer(properties["max_depth"])
        if "rr_depth" in properties:
            settings["rr_depth"] = self.integer(properties["rr_depth"])
        if "hide_emitters" in properties and self.boolean(properties["hide_emitters"]):
            # Mitsuba's camera rays then see no environment and pass through area lights (measured: behind a
            # hidden area light they see the lit wall it hides, with its path and direct integrators alike).
            settings["hide_emitters"] = True
        if kind == "direct":
            settings["max_depth"] = 2
            self.notes.append(
                f"{self.at(element)}: integrator 'direct' imported as path tracing with max_depth 2 "
                "(emitters seen directly and direct light)"
            )
            # Mitsuba's direct integrator's sample counts per technique change the noise, not the mean.
            properties.understood("emitter_samples", "bsdf_samples", "shading_samples")
        elif kind == "ptracer":
            # Mitsuba's particle tracer is spectrace's light tracer, with the same max_depth and rr_depth meaning;
            # how many light paths one of its passes runs changes the scheduling, not the image.
            settings["type"] = "light"
            properties.understood("samples_per_pass")
        elif kind == "bdpt":
            # Mitsuba 0.6's bidirectional path tracer (Mitsuba 3 has none): spectrace's bdpt, max_depth and rr_depth
            # meaning the same; its per-strategy options change the noise, not the mean.
            settings["type"] = "bdpt"
            depth = settings["max_depth"]
            if not (isinstance(depth, int) and 0 <= depth <= BDPT_MAX_SEGMENTS):
                # Unbounded (Mitsuba's default, -1) or deeper than the kernel's subpath arrays: the longest paths
                # spectrace's bdpt keeps, so the import renders; the paths left out carry what Russian roulette
                # lets through beyond that many bounces.
                self.notes.append(
                    f"{self.at(element)}: integrator 'bdpt' with max_depth {depth} imported with "
                    f"max_depth {BDPT_MAX_SEGMENTS}, the longest paths spectrace's bdpt keeps"
                )
                settings["max_depth"] = BDPT_MAX_SEGMENTS
            properties.understood(*_with_snake_case("lightImage", "sampleDirect", "samples_per_pass"))
        elif kind in ("sppm", "photonmapper"):
            # Mitsuba 0.6's photon mappers: spectrace's sppm, which converges to the same image; the photon counts,
            # radii and lookup sizes are its own (spectrace.engine.sppm), so they are noted, not followed.
            settings["type"] = "sppm"
            own = _with_snake_case(  # a 0.x file's names arrive upgraded to snake_case
                "photonCount", "initialRadius", "alpha", "granularity", "maxPasses", "directSamples",
                "glossySamples", "globalPhotons", "causticPhotons", "volumePhotons", "globalLookupRadius",
                "causticLookupRadius", "lookupSize",
            )  # fmt: skip
            if any(name in properties for name in own):
                self.notes.append(
                    f"{self.at(element)}: integrator '{kind}' imported as 'sppm'; its photon counts and radii are "
                    "spectrace's own choice"
                )
            properties.understood(*own)
        elif kind.startswith("volpath"):
            self.notes.append(f"{self.at(element)}: integrator '{kind}' imported as 'path', which renders media")
            # volpath counts no null interaction toward max_depth, and Mitsuba's thindielectric transmits by a
            # null lobe: a pass straight through a thin sheet is no segment there (path counts it).
            settings["count_thin_passes"] = False
        elif kind == "moment":
            # Mitsuba's moment integrator renders its nested integrator's image with the second moment as extra
            # channels: the image is the nested one's.
            nested = self.nested(properties, "integrator")
            if len(nested) != 1:
                raise self.fail(element, f"integrator 'moment' needs exactly one nested integrator, got {len(nested)}")
            self.notes.append(
                f"{self.at(element)}: integrator 'moment' imported as the integrator it holds (spectrace's image "
                "has no moment channels)"
            )
            self.integrator(nested[0], data)
            return
        elif kind == "aov":
            self.aov_integrator(element, properties, data)
            return
        data["integrator"] = settings
        self.origins["integrator"] = element

    def aov_integrator(self, element: Element, properties: Properties, data: dict) -> None:
        """Mitsuba's `aov` integrator: its nested integrator's image, and the AOVs its `aovs` list names
        ("name:type, ..."). The types spectrace's film keeps (the same definitions: spectrace.film.aovs) become the
        film's aovs; each other type is a warning naming it, and so is an aov integrator without a nested one
        (Mitsuba's image then holds the AOVs alone; spectrace renders the path tracer's image beside them)."""
        nested = self.nested(properties, "integrator")
        if len(nested) > 1:
            raise self.fail(element, f"integrator 'aov' with {len(nested)} nested integrators (spectrace renders one)")
        where = f"{_shown(str(element.file or self.xml_path), 200)}:{element.line}: integrator 'aov'"
        kept: list[str] = []
        text = self.text(properties["aovs"]) if "aovs" in properties else ""
        for entry in filter(None, (part.strip() for part in text.split(","))):
            kind = entry.split(":", 1)[-1].strip()
            if kind in _MITSUBA_AOVS and _MITSUBA_AOVS[kind] not in kept:
                kept.append(_MITSUBA_AOVS[kind])
            elif kind not in _MITSUBA_AOVS:
                self.warnings.append(
                    f"{where}: AOV '{_shown(entry)}' is not imported (spectrace's film keeps the types "
                    f"{', '.join(sorted(_MITSUBA_AOVS))})"
                )
        if kept:
            self.film_aovs = kept
        if nested:
            self.integrator(nested[0], data)
        else:
            self.warnings.append(f"{where}: it holds no integrator; its image is spectrace's path tracer's")
            data["integrator"] = {"type": "path", "max_depth": -1}
            self.origins["integrator"] = element

    # -------------------------------------------------- the scene

    def report_unknown_tags(self, root: Element) -> None:
        """A warning (--strict: an error) for every element, at any depth, whose tag Mitsuba does not know: it and
        what it holds are not imported. Misspellings (<emiter>, <shpe>) would otherwise vanish unseen where nothing
        looks for them (the scene's top level, a declaration never used, a property's or a transform's children)."""
        pending = list(reversed(root.children))  # depth first, in document order
        while pending:
            element = pending.pop()
            if element.tag in _KNOWN_TAGS:
                pending += reversed(element.children)
                continue
            self.unknown_tags += 1
            self.warnings.append(
                f"{_shown(str(element.file or self.xml_path), 200)}:{element.line}: {element.path}: unknown tag "
                f"<{_shown(element.tag)}> is not imported (Mitsuba 3 has no such element)"
            )

    def run(self, tree: SceneTree) -> dict:
        root = tree.root
        self.search_folders = tree.search_folders
        self.report_unknown_tags(root)
        if tree.unused_parameters:
            self.notes.append(
                "parameters the scene does not use: " + ", ".join(_shown(name) for name in tree.unused_parameters)
            )
        self._collect_ids(root)
        referenced = self._referenced_ids(root)
        data: dict = {"integrator": {"type": "path", "max_depth": -1}}
        shapes: list[dict] = []
        lights: list[dict] = []
        sensors = [c for c in root.children if c.tag == "sensor"]
        if not sensors:
            # Mitsuba 3 makes no default camera (its scene dropped the one it made before 3.0.0): it loads such a
            # file, usually a fragment for <include>, and refuses to render it ("No sensor specified").
            raise SpectraceError(
                "the scene has no <sensor>, and a camera is needed: Mitsuba 3 loads such a file but renders nothing "
                "from it either (it makes no default camera); add a <sensor>, or import the scene that includes "
                "this file",
                where=str(self.xml_path),
            )
        if len(sensors) > 1:
            self.notes.append(f"{self.at(sensors[1])}: only the first of {len(sensors)} sensors is imported")
        self.sensor(sensors[0], data)
        objects: dict[str, dict] = {}
        instances: list[dict] = []
        for index, child in enumerate(root.children):
            if child.tag == "shape" and child.get("type") == "shapegroup":
                continue  # a declaration: imported where an instance places it
            if child.tag == "shape" and child.get("type") == "instance":
                if (table := self.instance(child, objects)) is not None:
                    self.origins[f"instances[{len(instances)}]"] = child
                    instances.append(table)
            elif child.tag == "shape":
                if (table := self.shape(child, index)) is not None:
                    self.origins[f"shapes[{len(shapes)}]"] = child
                    shapes.append(table)
            elif child.tag == "emitter":
                if child.get("type") == "area" and child.get("id") in referenced:
                    continue  # an area light declared here and given to shapes by reference
                if (table := self.light(child)) is not None:
                    self.origins[f"lights[{len(lights)}]"] = child
                    lights.append(table)
            elif child.tag == "integrator":
                self.integrator(child, data)
            elif child.tag in ("bsdf", "texture", "spectrum", "rgb", "default", "sensor", "alias"):
                continue  # declarations: imported where they are used
            elif child.tag in ("film", "sampler", "rfilter", "medium", "phase") and child.get("id") in referenced:
                continue  # the same, for what a sensor or a shape (its interior) refers to
            elif child.tag in _OBJECT_TAGS:
                self.unsupported_object(child)
        if self.unsupported:
            raise SpectraceError(
                f"unsupported Mitsuba 3 plugins: {self.unsupported_text()} (spectrace imports {supported_text()})",
                where=str(self.xml_path),
            )
        environments = [
            self.origins[f"lights[{i}]"]
            for i, light in enumerate(lights)
            if getattr(LIGHTS[light["type"]], "IS_ENVIRONMENT", False)
        ]
        if len(environments) > 1:
            raise self.fail(environments[1], "a second environment emitter; spectrace takes one environment light")
        if self.unsupported:
            raise SpectraceError(
                f"unsupported Mitsuba 3 plugins: {self.unsupported_text()} (spectrace imports {supported_text()})",
                where=str(self.xml_path),
            )
        self.report_unread_properties()
        if self.textures:
            data["textures"] = self.textures
        data["materials"] = self.materials
        data["shapes"] = shapes
        data["lights"] = lights
        data["objects"] = {name: table for name, table in objects.items() if table["shapes"]}
        data["instances"] = instances
        if self.film_aovs and "film" in data:
            data["film"]["aovs"] = self.film_aovs
        self.whole_pixel_filter(data)
        order = ("camera", "film", "integrator", "sampler", "textures", "materials", "shapes", "lights")
        # materials stays even when empty (the scene format asks for the table); objects only when some are placed.
        kept = {key: data[key] for key in order if key in data and data[key] != []}
        return kept | {key: data[key] for key in ("objects", "instances") if data[key]}

    def whole_pixel_filter(self, data: dict) -> None:
        """spectrace's bdpt and sppm estimate whole pixels (spectrace.engine.light_tracer, .sppm): a film filter
        other than the box (Mitsuba's default is a Gaussian) becomes the box with a note, so the import renders."""
        film, integrator = data.get("film"), data.get("integrator", {})
        if film is None or integrator.get("type") not in ("bdpt", "sppm") or film["filter"]["type"] == "box":
            return
        self.notes.append(
            f"{self.at(self.origins['film'])}: integrator '{integrator['type']}' estimates whole pixels: the film's "
            f"{film['filter']['type']} filter is imported as the box filter"
        )
        film["filter"] = {"type": "box"}

    def report_unread_properties(self) -> None:
        """A warning for each property of an imported object that nothing read: spectrace does not know it."""
        for properties in self._properties.values():
            owner = properties.owner
            for key in properties.unread():
                child = dict.__getitem__(properties, key)
                if child.tag not in _KNOWN_TAGS:
                    continue  # reported as an unknown tag
                name = child.label() if key.startswith("#") or "#" in key else f"'{_shown(key)}'"
                self.warnings.append(
                    f"{_shown(str(child.file or self.xml_path), 200)}:{child.line}: {owner.label()}: property "
                    f"{name} is not imported (spectrace does not know it)"
                )

    def _referenced_ids(self, root: Element) -> set[str]:
        found: set[str] = set()
        pending = [root]
        while pending:
            element = pending.pop()
            if element.tag == "ref" and (identifier := element.get("id")) is not None:
                found.add(identifier)
            pending += element.children
        return found

    def _collect_ids(self, root: Element) -> None:
        aliases: list[Element] = []
        pending = [root]
        while pending:
            element = pending.pop()
            for child in element.children:
                identifier = child.get("id") if child.tag not in ("ref", "alias") else None
                # Mitsuba refuses a scene whose objects share an id: a <ref> could not tell them apart.
                if identifier is not None and (other := self.ids.setdefault(identifier, child)) is not child:
                    first, second = sorted((other, child), key=lambda e: (e.file != self.xml_path, e.line))
                    raise self.fail(second, f"duplicate id '{_shown(identifier)}' (also at {self.at(first)})", "id")
                if child.tag == "alias":
                    aliases.append(child)
                pending.append(child)
        for alias in sorted(aliases, key=lambda e: e.line):  # <alias id="a" as="b"/>: b names a's object too
            source, target = self.required(alias, "id"), self.required(alias, "as")
            if source not in self.ids:
                raise self.fail(alias, f"alias of an undefined id '{_shown(source)}'", "id")
            if target in self.ids:
                raise self.fail(alias, f"alias '{_shown(target)}' names an id already taken", "as")
            self.ids[target] = self.ids[source]

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


def _unnormalised_rotation(axis: list[float], degrees: float) -> np.ndarray:
    """Mitsuba's rotate step as it builds it, axis a as given: cos θ I + sin θ [a]× + (1 − cos θ) a aᵀ (a rotation only
    for a unit axis)."""
    a = np.asarray(axis, np.float64)
    cos, sin = math.cos(math.radians(degrees)), math.sin(math.radians(degrees))
    cross = np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])
    matrix = np.eye(4)
    matrix[:3, :3] = cos * np.eye(3) + sin * cross + (1.0 - cos) * np.outer(a, a)
    return matrix


def _with_snake_case(*names: str) -> tuple[str, ...]:
    """Mitsuba 0.6 property names as a 3.x file spells them and as a 0.x file's upgrade turns them (snake_case)."""
    return tuple(dict.fromkeys([*names, *(camel_to_snake(name) for name in names)]))


def _unique_name(base: str, taken: dict) -> str:
    name = re.sub(r"[^A-Za-z0-9_-]", "_", base) or "material"
    candidate, number = name, 2
    while candidate in taken:
        candidate, number = f"{name}_{number}", number + 1
    return candidate


def _relative_path(path: Path, folder: Path) -> str:
    try:
        return Path(os.path.relpath(path.resolve(), folder.resolve())).as_posix()
    except ValueError:  # another drive on Windows
        return path.resolve().as_posix()


def check_output_path(toml_path: Path, xml_path: Path | None = None, option: str = "the TOML file") -> None:
    """Refuse, before any work, an output that could not be written or would destroy the input: what every output
    is refused for (spectrace.io.output_files), and the XML itself. Missing folders are created when the TOML is
    written."""
    where = str(toml_path)
    check_output_file(toml_path, option, create_folders=True)
    if xml_path is not None and toml_path.exists() and xml_path.exists() and toml_path.samefile(xml_path):
        raise SpectraceError("is the Mitsuba scene being imported; writing it would destroy the input", where=where)


# ---------------------------------------------------------------- public API


WARNING_PREFIX = "warning: "


def _imported(importer: MitsubaImporter, strict: bool) -> dict:
    """The scene data; the properties nothing read are warnings among the notes, or with `strict` one error."""
    data = importer.run(read_scene(importer.xml_path, importer.parameters))
    if importer.warnings and strict:
        properties, tags = len(importer.warnings) - importer.unknown_tags, importer.unknown_tags
        counts = [f"{properties} {'property' if properties == 1 else 'properties'}"] if properties else []
        counts += [f"{tags} unknown {'tag' if tags == 1 else 'tags'}"] if tags else []
        raise SpectraceError(
            f"{' and '.join(counts)} not imported (--strict): {'; '.join(importer.warnings)}",
            where=str(importer.xml_path),
        )
    importer.notes += [WARNING_PREFIX + warning for warning in importer.warnings]
    return data


def mitsuba_scene_data(
    xml_path: str | Path,
    toml_folder: str | Path | None = None,
    parameters: dict[str, str] | None = None,
    strict: bool = False,
) -> tuple[dict, list[str]]:
    """(scene data in the TOML format's structure, notes) for a Mitsuba 3 XML scene. Mesh paths are written relative
    to `toml_folder` (default: the XML's folder). `parameters` set `$name` values, as `mitsuba -D name=value`.
    Raises SpectraceError naming every unsupported plugin. Properties spectrace does not know are notes starting
    with "warning: ", or with `strict` an error naming each."""
    xml_path = Path(xml_path)
    importer = MitsubaImporter(xml_path, Path(toml_folder) if toml_folder else xml_path.parent, parameters or {})
    return _imported(importer, strict), importer.notes


def import_mitsuba(
    xml_path: str | Path,
    toml_path: str | Path,
    parameters: dict[str, str] | None = None,
    strict: bool = False,
    option: str = "the TOML file",
) -> list[str]:
    """Write the spectrace TOML scene for a Mitsuba 3 XML scene and check that it loads; returns the notes.
    option: what errors about the output call it (the command line's --output).

    The output is checked first (a folder, a read-only place) and locked (spectrace.io.output_lock: a second import
    writing it is refused); the TOML and the files beside it that it refers to (`side_files`) are replaced
    together, and only by a complete import whose TOML loads: a failed import leaves an earlier one as it was."""
    from spectrace.interop.toml_writer import lock_import

    xml_path, toml_path = Path(xml_path), Path(toml_path)
    check_output_path(toml_path, xml_path, option)
    with lock_import(toml_path, option, "spectrace import-mitsuba"):
        return _import_mitsuba(xml_path, toml_path, parameters, strict, option)


def _import_mitsuba(
    xml_path: Path, toml_path: Path, parameters: dict[str, str] | None, strict: bool, option: str
) -> list[str]:
    from spectrace.interop.toml_writer import non_finite_key, write_scene
    from spectrace.scene import load_scene

    importer = MitsubaImporter(xml_path, toml_path.parent, parameters or {})
    importer.side_stem = toml_path.stem
    data = _imported(importer, strict)
    header = "\n".join(
        [
            f"Imported from the Mitsuba 3 scene {_shown(xml_path.name, 200)} by `spectrace import-mitsuba`.",
            *(note if note.startswith(WARNING_PREFIX) else f"note: {note}" for note in importer.notes),
        ]
    )
    if (key := non_finite_key(data)) is not None:
        failure = SpectraceError(
            "is NaN or infinite: a number of the file overflows or divides by zero", f"{toml_path}: {key}"
        )
        raise importer.imported_error(failure, toml_path)

    def check(temp: Path) -> None:
        try:
            load_scene(temp)  # from the output's folder, where its relative mesh paths lead
        except SpectraceError as error:
            raise importer.imported_error(error, temp) from None

    files = {name: partial(_write_side, content=content) for name, content in importer.side_files.items()}
    try:
        write_scene(toml_path, data, header, files, check, option, "spectrace import-mitsuba")
    except OSError as error:
        raise SpectraceError(
            f"cannot write the TOML or its files ({error.strerror or error})", where=str(toml_path)
        ) from None
    return importer.notes


def _write_side(path: Path, content: str | bytes) -> None:
    if isinstance(content, bytes):
        path.write_bytes(content)
    else:
        path.write_text(content, encoding="utf-8")


def load_mitsuba_scene(xml_path: str | Path, parameters: dict[str, str] | None = None, strict: bool = False):
    """A `Scene` from a Mitsuba 3 XML file (through a temporary TOML file)."""
    from spectrace.scene import load_scene

    with tempfile.TemporaryDirectory(prefix="spectrace-mitsuba-") as folder:
        toml_path = Path(folder) / (Path(xml_path).stem + ".toml")
        import_mitsuba(xml_path, toml_path, parameters, strict)
        return load_scene(toml_path).with_overrides(source=Path(xml_path))
