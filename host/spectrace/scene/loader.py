"""TOML scene file -> resolved Scene. Every error names the file and the key path of the offending value."""

import dataclasses
import difflib
import tomllib
import typing
from pathlib import Path

import numpy as np
from pydantic import BaseModel, ValidationError

from spectrace import pixel_filters
from spectrace.cameras import thinlens
from spectrace.cameras.shared import clip_problem
from spectrace.core import limits
from spectrace.errors import SpectraceError
from spectrace.film.aovs import parse_aovs
from spectrace.film.response import FilmResponse, load_sensor
from spectrace.geometry import primitives
from spectrace.geometry.analytic import (
    ANALYTIC_SHAPES,
    AnalyticSurface,
    cut_parameters,
    object_tessellation,
    pbrt_uv_from_mitsuba,
    similarity_problem,
)
from spectrace.geometry.grid_volume import GridVolume, box_matrix, make_grid, read_vol
from spectrace.geometry.mesh import TriangleMesh, load_mesh, shading_normals
from spectrace.geometry.nanovdb import NanoGrid, nanovdb_grid
from spectrace.geometry.sdf_grid import make_sdf_grid, read_sdf_grid
from spectrace.geometry.transforms import apply_transform, transform_matrix
from spectrace.io.images import read_picture
from spectrace.io.input_files import regular_file
from spectrace.lights import LIGHTS
from spectrace.lights.area import emitter as area_emitter
from spectrace.lights.area import emitter_stokes, peak_radiance
from spectrace.materials import MATERIALS, surface, uv_material_textures
from spectrace.scene import schema
from spectrace.scene.curve_shapes import curve_shape
from spectrace.scene.model import (
    AreaEmitter,
    Camera,
    EmitterImage,
    Instance,
    InstancedObject,
    Light,
    Material,
    Medium,
    Scene,
    Shape,
)
from spectrace.scene.validation_messages import plain_message
from spectrace.spectral.blackbody import blackbody
from spectrace.spectral.illuminants import cie_illuminant
from spectrace.spectral.spectrum import Spectrum
from spectrace.spectral.spectrum_input import from_rgb, optical_constant, within_bounds
from spectrace.spectral.spectrum_io import library_spectrum, load_spectrum_csv, parse_inline_spectrum
from spectrace.textures import (
    INNER_TEXTURES,
    TEXTURES,
    BitmapTexture,
    check_texture_values,
    is_texture,
    texture_module,
)
from spectrace.textures.shared import Placement


def key_path(location: tuple) -> str:
    """('shapes', 2, 'material') -> 'shapes[2].material'."""
    text = ""
    for part in location:
        if isinstance(part, int):
            text += f"[{part}]"
        else:
            text += ("." if text else "") + str(part)
    return text


def _allowed_keys(model: type[BaseModel], location: tuple) -> list[str]:
    """Field names valid at `location` in the schema, for 'did you mean' hints (every member of a union)."""
    current = [model]
    name_follows = False  # the part after a dict-typed field is a user-chosen name ([materials.NAME])
    for part in location[:-1]:
        if isinstance(part, int):
            continue
        if name_follows:
            name_follows = False
            continue
        annotations = [m.model_fields[part].annotation for m in current if part in m.model_fields]
        if not annotations:
            return []
        name_follows = any(typing.get_origin(a) is dict for a in annotations)
        current = [m for a in annotations for m in _models_in(a)]
    return list(dict.fromkeys(key for m in current for key in m.model_fields))


def _models_in(annotation) -> list[type[BaseModel]]:
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return [annotation]
    return [m for arg in getattr(annotation, "__args__", ()) or () for m in _models_in(arg)]


def _location_in_data(data: object, location: tuple, missing: bool) -> tuple:
    """The parts of a pydantic error location that are keys or indices of the input: pydantic also names
    union members ('str', 'point', 'function-after[...]'), which the file does not contain."""
    kept, node = [], data
    for i, part in enumerate(location):
        if (
            isinstance(node, dict)
            and part in node
            or isinstance(node, list)
            and type(part) is int
            and 0 <= part < len(node)
        ):
            kept.append(part)
            node = node[part]
        elif missing and i == len(location) - 1:
            kept.append(part)
    return tuple(kept)


def _validation_error(path: Path, error: ValidationError, data: object = None) -> SpectraceError:
    # A misspelt key also shows up as a missing required one; the misspelling is the actionable report. Among
    # the rest, the deepest location is the most specific (a union reports every member's complaint).
    located = [(e, _location_in_data(data, e["loc"], e["type"] == "missing")) for e in error.errors()]
    first, location = min(located, key=lambda item: (item[0]["type"] != "extra_forbidden", -len(item[1])))
    message = plain_message(first)
    if first["type"] == "extra_forbidden":
        allowed = _allowed_keys(schema.SceneSpec, location)
        close = difflib.get_close_matches(str(location[-1]), allowed, n=1)
        message = f"unknown key '{location[-1]}'" + (f" (did you mean '{close[0]}'?)" if close else "")
    elif first["type"] == "missing":
        message = "required key is missing"
    elif first["type"] == "union_tag_not_found":  # e.g. a material without `type`
        discriminator = str(first.get("ctx", {}).get("discriminator", "type")).strip("'")
        location = (*location, discriminator)
        message = "required key is missing"
    elif first["type"] == "union_tag_invalid":  # e.g. a material of an unknown `type`
        context = first.get("ctx", {})
        location = (*location, str(context.get("discriminator", "type")).strip("'"))
    elif first["type"] in ("model_type", "dict_type"):  # pydantic would name a schema class
        message = f"expected a table, got {type(first['input']).__name__} {first['input']!r}"[:200]
    extra = f" ({len(error.errors()) - 1} more problem(s))" if len(error.errors()) > 1 else ""
    return SpectraceError(message + extra, where=f"{path}: {key_path(location)}" if location else str(path))


MAX_NESTING = limits.MAX_NESTING


def _too_deep(data: object) -> tuple | None:
    """The key path of a value nested beyond MAX_NESTING tables or arrays, or None (iterative: no recursion)."""
    stack: list[tuple[object, tuple]] = [(data, ())]
    while stack:
        node, location = stack.pop()
        if len(location) > MAX_NESTING:
            return location
        children = node.items() if isinstance(node, dict) else enumerate(node) if isinstance(node, list) else ()
        stack.extend((child, (*location, key)) for key, child in children)
    return None


# The top-level tables a scene file may leave out, which then hold their defaults ([sampler], [integrator]): a key
# path into one of them is there to set whether the file writes the table or not.
_DEFAULTED_TABLES = frozenset(
    name
    for name, field in schema.SceneSpec.model_fields.items()
    if not field.is_required() and isinstance(field.annotation, type) and issubclass(field.annotation, BaseModel)
)


def set_key_path(data: dict, dotted: str, value: object, where: str) -> None:
    """Replace the value at a dotted key path of parsed TOML ("materials.red.reflectance", "shapes.0.material";
    a number indexes an array of tables). The path must exist up to its last key, which may be new, except that a
    defaulted top-level table the file leaves out ("sampler.seed") is added."""
    parts = dotted.split(".")
    if len(parts) > 1 and parts[0] in _DEFAULTED_TABLES and data.get(parts[0]) is None:
        data[parts[0]] = {}
    node: object = data
    for depth, part in enumerate(parts):
        last = depth == len(parts) - 1
        if isinstance(node, list) and part.isdigit() and int(part) < len(node):
            if last:
                node[int(part)] = value
            else:
                node = node[int(part)]
        elif isinstance(node, dict) and (last or part in node):
            if last:
                node[part] = value
            else:
                node = node[part]
        else:
            raise SpectraceError(f"the scene has no {'.'.join(parts[: depth + 1])}", where=where)


def read_scene_spec(path: Path, overrides: dict[str, object] | None = None) -> schema.SceneSpec:
    data = read_scene_data(path)
    for dotted, value in (overrides or {}).items():
        set_key_path(data, dotted, value, where=f"{path}: {dotted}")
    return validate_scene_data(path, data)


def validate_scene_data(path: Path, data: dict) -> schema.SceneSpec:
    """The spec of a scene file's parsed TOML (`read_scene_data`, perhaps edited); errors name the file and key."""
    try:
        return schema.SceneSpec.model_validate(data)
    except ValidationError as exc:
        raise _validation_error(path, exc, data) from None


def read_scene_data(path: Path) -> dict:
    """A scene file's parsed TOML, not yet validated."""
    regular_file(path, what="scene file")
    try:
        # utf-8-sig: editors on Windows may start the file with a byte order mark, which TOML does not allow.
        text = path.read_text(encoding="utf-8-sig")
    except OSError as exc:
        raise SpectraceError(f"cannot read scene file ({exc.strerror})", where=str(path)) from None
    except UnicodeDecodeError as exc:
        raise SpectraceError(
            f"not a UTF-8 text file (byte 0x{exc.object[exc.start]:02x} at offset {exc.start})", where=str(path)
        ) from None
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise SpectraceError(f"TOML syntax error: {exc}", where=str(path)) from None
    except RecursionError:  # tomllib parses arrays and inline tables recursively
        raise SpectraceError(
            f"arrays or inline tables nested too deep to parse (a scene needs at most {MAX_NESTING} levels)",
            where=str(path),
        ) from None
    if (location := _too_deep(data)) is not None:
        raise SpectraceError(
            f"values nested more than {MAX_NESTING} levels deep (a scene needs only a few)",
            where=f"{path}: {key_path(location[:3])}",
        )
    return data


class _Resolver:
    """Turns a validated spec into scene objects, resolving names and files relative to the scene file."""

    def __init__(self, path: Path, spec: schema.SceneSpec):
        self.path = path
        self.folder = path.parent
        self.spec = spec
        self.named_spectra: dict[str, Spectrum] = {}
        self.named_textures: dict[str, object] = {}
        self.named_materials: dict[str, Material] = {}
        self.resolving_materials: list[str] = []  # the names being resolved: a mix naming one of them is a cycle
        self.texture_cache: dict[tuple[str, str], object] | None = None  # see texture_of
        # id(object) -> (the object, kept so that its id stays its own; its box's corners)
        self.object_corners: dict[int, tuple[InstancedObject, np.ndarray]] = {}

    def where(self, key: str) -> str:
        return f"{self.path}: {key}"

    def named_spectrum(self, name: str, key: str) -> Spectrum:
        if name in self.named_spectra:
            return self.named_spectra[name]
        entry = self.spec.spectra.get(name)
        if entry is None:
            if "/" in name or ":" in name:
                try:
                    return library_spectrum(name)
                except SpectraceError as exc:
                    raise SpectraceError(exc.message, where=self.where(key)) from None
            known = sorted(self.spec.spectra)
            close = difflib.get_close_matches(name, known, n=1)
            hint = f" (did you mean '{close[0]}'?)" if close else (f"; defined: {', '.join(known)}" if known else "")
            raise SpectraceError(f"undefined spectrum '{name}'{hint}", where=self.where(key))
        entry_key = f"spectra.{name}"
        if entry.values is not None:
            spectrum = parse_inline_spectrum(entry.values, where=self.where(f"{entry_key}.values"))
        elif entry.file is not None:
            spectrum = self.csv_spectrum(entry.file, entry.column, f"{entry_key}.file", name=name)
        else:
            assert entry.library is not None  # the schema wants exactly one of values, file, library
            try:
                spectrum = library_spectrum(entry.library)
            except SpectraceError as exc:
                raise SpectraceError(exc.message, where=self.where(f"{entry_key}.library")) from None
        self.named_spectra[name] = spectrum
        return spectrum

    def csv_spectrum(self, file: str, column: str | None, key: str, name: str | None = None) -> Spectrum:
        """A spectrum CSV; its errors (which name the CSV and its line) also name the scene key that refers to it."""
        try:
            return load_spectrum_csv(self.folder / file, column=column, name=name)
        except SpectraceError as exc:
            raise SpectraceError(str(exc), where=self.where(key)) from None

    def spectrum(self, spec: schema.SpectrumSpec, key: str, emission: bool, bounded: bool = True) -> Spectrum:
        """A spectrum table's Spectrum: an emission's or a reflectance's (an RGB triple uplifted for that role),
        refused where negative and, for a reflectance that is `bounded`, above 1 (a composite texture's operand is
        bounded by the parameter that uses the texture instead: textures.check_texture_values)."""
        if spec.display is not None:
            result = self.display_spectrum(spec, key, emission)
        elif spec.rgb is not None:
            result = from_rgb(spec.rgb, emission, self.where(f"{key}.rgb"))
        elif spec.value is not None:
            result = Spectrum.constant(spec.value, name=f"constant {spec.value}")
        elif spec.blackbody is not None:
            result = blackbody(spec.blackbody)
        elif spec.spectrum is not None:
            result = self.named_spectrum(spec.spectrum, f"{key}.spectrum")
        elif spec.values is not None:
            result = parse_inline_spectrum(spec.values, where=self.where(f"{key}.values"))
        else:
            assert spec.file is not None  # the schema wants exactly one source
            result = self.csv_spectrum(spec.file, spec.column, f"{key}.file")
        with np.errstate(over="ignore"):  # an overflow to inf is reported just below
            if problem := limits.spectrum_magnitude_problem(result.values * spec.scale):
                raise SpectraceError(problem, where=self.where(key))
        result = result * spec.scale if spec.scale != 1.0 else result
        return within_bounds(result, emission or not bounded, self.where(key))

    def spectrum_or_texture(self, spec, key: str, kind: str, inner: bool = False):
        """A textured parameter's value (kind "spectrum": a reflectance, or "float": a scalar): a Spectrum, or a
        texture whose values are checked for that use. inner: an operand of a composite (a checkerboard's side, a
        scale's or mix's operand), which takes no composite."""
        if isinstance(spec, schema.SpectrumSpec):
            return self.spectrum(spec, key, emission=False, bounded=not inner)
        if isinstance(spec, schema.TextureRefSpec):
            texture = self.named_texture(spec.texture, f"{key}.texture")
            if inner and not is_texture_image(texture):
                raise SpectraceError(
                    f"texture '{spec.texture}' is a {texture_module(texture).NAME}; a checkerboard's sides and a "
                    "scale's or mix's operands are spectra or image textures",
                    where=self.where(f"{key}.texture"),
                )
        else:
            texture = self.texture_of(spec.texture, spec, key)
        assert is_texture(texture)
        check_texture_values(texture, kind, self.where(key))
        return texture

    def number_or_texture(self, spec, key: str, parameter):
        """A textured number's value (a `roughness`): the number the schema checked, or a one-channel texture whose
        values lie in the parameter's range."""
        if isinstance(spec, (int, float)):
            return float(spec)
        texture = self.spectrum_or_texture(spec, key, "float")
        check_texture_values(texture, "float", self.where(key), upper=parameter.range.high)
        return texture

    def texture_of(self, type_name: str, spec, key: str):
        """The texture of a validated table: made from it, or, where the resolver keeps `texture_cache` (a live
        session's, whose edits resolve materials again), the one made before from the same table, so that an edit
        elsewhere neither reads its file nor stores its texels again."""
        if self.texture_cache is None:
            return TEXTURES[type_name].from_spec(spec, self, key)
        cache_key = (type_name, spec.model_dump_json())
        if cache_key not in self.texture_cache:
            self.texture_cache[cache_key] = TEXTURES[type_name].from_spec(spec, self, key)
        return self.texture_cache[cache_key]

    def named_texture(self, name: str, key: str):
        if name in self.named_textures:
            return self.named_textures[name]
        entry = self.spec.textures.get(name)
        if entry is None:
            known = sorted(self.spec.textures)
            close = difflib.get_close_matches(name, known + list(TEXTURES), n=1)
            hint = f" (did you mean '{close[0]}'?)" if close else (f"; defined: {', '.join(known)}" if known else "")
            raise SpectraceError(f"undefined texture '{name}'{hint}", where=self.where(key))
        texture = self.texture_of(entry.type, entry, f"textures.{name}")
        self.named_textures[name] = texture
        return texture

    def materials(self) -> dict[str, Material]:
        return {name: self.material_named(name, "materials") for name in self.spec.materials}

    def material_named(self, name: str, key: str) -> Material:
        """The material [materials.NAME], resolved once; a mix names others (`key`: where the name was given),
        which must be defined and must not name the mix itself, directly or through other mixes."""
        resolved, resolving = self.named_materials, self.resolving_materials
        if name in resolved:
            return resolved[name]
        if name not in self.spec.materials:
            close = difflib.get_close_matches(name, list(self.spec.materials), n=1)
            hint = f" (did you mean '{close[0]}'?)" if close else f"; defined: {', '.join(sorted(self.spec.materials))}"
            raise SpectraceError(f"undefined material '{name}'{hint}", where=self.where(key))
        if name in resolving:
            cycle = " -> ".join([*resolving[resolving.index(name) :], name])
            raise SpectraceError(f"materials mix themselves: {cycle}", where=self.where(key))
        resolving.append(name)
        try:
            resolved[name] = self.material(self.spec.materials[name], f"materials.{name}")
        finally:
            resolving.pop()
        return resolved[name]

    def material(self, spec, key: str) -> Material:
        return surface.with_detail(MATERIALS[spec.type].from_spec(spec, self, key), self.surface_detail(spec, key))

    def surface_detail(self, spec, key: str):
        """The keys every material takes besides its own (spectrace.materials.surface), resolved and checked."""
        values = {}
        for name in ("normal_map", "bump_map", "opacity"):
            value = getattr(spec, name)
            if value is None or isinstance(value, float):
                values[name] = value
            elif isinstance(value, schema.SpectrumSpec):
                takes = "a number or a texture" if name == "opacity" else "a texture"
                raise SpectraceError(f"{name} takes {takes}, not a spectrum", where=self.where(f"{key}.{name}"))
            else:
                values[name] = self.texture(value, f"{key}.{name}")
        return surface.detail(
            values["normal_map"],
            values["bump_map"],
            spec.bump_scale,
            values["opacity"],
            spec.two_sided,
            where=lambda name: self.where(f"{key}.{name}"),
            shadowing_function=spec.shadowing_function,
            normal_map_handedness=spec.normal_map_handedness,
        )

    def texture(self, spec, key: str):
        """An inline texture or a reference to a named one, unchecked: its use checks it."""
        if isinstance(spec, schema.TextureRefSpec):
            return self.named_texture(spec.texture, f"{key}.texture")
        return self.texture_of(spec.texture, spec, key)

    def optical_constant(self, spec: schema.SpectrumSpec, key: str, positive: bool) -> Spectrum:
        """η or k of a complex index of refraction: a spectrum without the reflectance bound (rgb has no meaning
        here); η must be > 0, k ≥ 0."""
        if spec.rgb is not None or spec.display is not None:
            raise SpectraceError(
                "an index of refraction needs a spectrum (value, values, spectrum or file), not a colour",
                where=self.where(key),
            )
        return optical_constant(self.spectrum(spec, key, emission=True), positive, self.where(key))

    def shapes(
        self, materials: dict[str, Material], specs: list[schema.ShapeSpec] | None = None, prefix: str = "shapes"
    ) -> list[Shape]:
        shapes = []
        for i, s in enumerate(self.spec.shapes if specs is None else specs):
            key = f"{prefix}[{i}]"
            if s.type == "curve":
                shapes.append(curve_shape(s, self.folder, self.where, key, materials, i))
                continue
            # Analytic unless asked for triangles: facets (face_normals = true) exist only on a tessellation.
            analytic = s.type in ANALYTIC_SHAPES and not (s.tessellated or s.face_normals)
            sdf_values = None
            if s.type == "sdfgrid":  # a stand-in for the range check; its tessellation follows from the placed grid
                sdf_values = self.sdf_grid_values(s, key)
                mesh = primitives.BUILTIN_SHAPES["cube"]()
            elif s.type == "mesh":
                assert s.file is not None  # the schema wants a file for a mesh
                mesh = load_mesh(self.folder / s.file, where=self.where(f"{key}.file"), shape_index=s.shape_index or 0)
            elif s.type in ANALYTIC_SHAPES and (cuts := _cuts(s)):
                mesh = AnalyticSurface(s.type, np.eye(4), pbrt_uv=s.uv_convention == "pbrt", **cuts).tessellation()
            elif s.type in ANALYTIC_SHAPES:
                mesh = object_tessellation(s.type)
                if s.uv_convention == "pbrt":
                    mesh = TriangleMesh(mesh.vertices, mesh.faces, pbrt_uv_from_mitsuba(s.type, mesh.uvs), mesh.normals)
            else:
                mesh = primitives.BUILTIN_SHAPES[s.type]()
            matrix = np.eye(4)
            placement = ([{"scale": s.radius}] if s.radius is not None else []) + (
                [{"translate": list(s.center)}] if s.center is not None else []
            )
            if s.transform or placement:
                steps = placement + [step.model_dump(exclude_none=True) for step in s.transform]
                with np.errstate(over="ignore", invalid="ignore"):  # overflows are reported just below
                    matrix = transform_matrix(steps, where=self.where(f"{key}.transform"))
                    mesh = apply_transform(mesh, matrix)
            if problem := limits.coordinates_problem(mesh.vertices):
                culprit = "transform" if s.transform else "file" if s.type == "mesh" else "type"
                raise SpectraceError(f"mesh has {problem}", where=self.where(f"{key}.{culprit}"))
            surface_of = None
            if analytic:
                if s.type == "sphere" and (problem := similarity_problem(matrix)):
                    raise SpectraceError(
                        f"{problem}; tessellated = true takes any", where=self.where(f"{key}.transform")
                    )
                surface_of = AnalyticSurface(
                    s.type, matrix, flip_normals=bool(s.flip_normals), pbrt_uv=s.uv_convention == "pbrt", **_cuts(s)
                )
                mesh = surface_of.tessellation()
            elif sdf_values is not None:
                where = self.where(f"{key}.{'file' if s.file is not None else 'grid'}")
                surface_of = make_sdf_grid(sdf_values, matrix, s.normals or "smooth", where=where)
                mesh = surface_of.tessellation()
            else:
                if s.flip_normals:
                    mesh = mesh.flipped()
                mesh = shading_normals(mesh, s.face_normals, computed=s.type == "mesh")
            if s.material is not None and s.material not in materials:
                close = difflib.get_close_matches(s.material, list(materials), n=1)
                hint = f" (did you mean '{close[0]}'?)" if close else f"; defined: {', '.join(sorted(materials))}"
                raise SpectraceError(f"undefined material '{s.material}'{hint}", where=self.where(f"{key}.material"))
            if s.material is not None and mesh.uvs is None and uv_material_textures(materials[s.material]):
                raise SpectraceError(
                    f"shape '{s.name or f'{s.type}{i}'}' has no texture coordinates, but material '{s.material}' has "
                    f"a texture ({', '.join(uv_material_textures(materials[s.material]))})",
                    where=self.where(f"{key}.material"),
                )
            emitter = None
            if s.emitter is not None:
                emitter = self.emitter(s.emitter, f"{key}.emitter")
                if emitter.image is not None and mesh.uvs is None:
                    name = s.name or f"{s.type}{i}"
                    raise SpectraceError(
                        f"shape '{name}' has no texture coordinates, but its emitter shows an image",
                        where=self.where(f"{key}.emitter.radiance"),
                    )
            interior = self.interior(s.interior, f"{key}.interior") if s.interior is not None else None
            material = materials[s.material] if s.material is not None else None
            if (problem := surface.cut_out_problem(material, emitter is not None, interior is not None)) is not None:
                raise SpectraceError(
                    f"shape '{s.name or f'{s.type}{i}'}': {problem} ('{s.material}')",
                    where=self.where(f"{key}.material"),
                )
            shapes.append(
                Shape(
                    mesh=mesh,
                    material=materials[s.material] if s.material is not None else None,
                    emitter=emitter,
                    name=s.name or f"{s.type}{i}",
                    interior=interior,
                    analytic=surface_of,
                )
            )
        return shapes

    def sdf_grid_values(self, s: schema.ShapeSpec, key: str) -> np.ndarray:
        """An sdfgrid's samples (nz, ny, nx): its volume file's or its inline grid."""
        if s.file is not None:
            return read_sdf_grid(self.folder / s.file, where=self.where(f"{key}.file"))
        where = self.where(f"{key}.grid")
        rows = {len(row) for plane in s.grid or [] for row in plane}
        if len(rows) != 1 or len({len(plane) for plane in s.grid or []}) != 1:
            raise SpectraceError(
                "an SDF grid's values must be a box of numbers: [z][y][x], rows of equal length", where=where
            )
        return np.array(s.grid, np.float64)

    def instances(self, materials: dict[str, Material]) -> list[Instance]:
        """The objects, each resolved once in its own space, and the instances that place them."""
        objects: dict[str, InstancedObject] = {}
        for name, o in self.spec.objects.items():
            key = f"objects.{name}.shapes"
            for i, s in enumerate(o.shapes):
                if s.emitter is not None:
                    raise SpectraceError(
                        "emitters cannot be instanced: place the emitting shape in `shapes`",
                        where=self.where(f"{key}[{i}].emitter"),
                    )
            objects[name] = InstancedObject(shapes=self.shapes(materials, o.shapes, key), name=name)
        instances = []
        for i, spec in enumerate(self.spec.instances):
            key = f"instances[{i}]"
            if spec.object not in objects:
                close = difflib.get_close_matches(spec.object, list(objects), n=1)
                hint = (
                    f" (did you mean '{close[0]}'?)" if close else f"; defined: {', '.join(sorted(objects)) or 'none'}"
                )
                raise SpectraceError(f"undefined object '{spec.object}'{hint}", where=self.where(f"{key}.object"))
            obj = objects[spec.object]
            matrix = self.instance_matrix(spec, key, obj)
            instances.append(Instance(object=obj, to_world=matrix, name=spec.name or f"{spec.object}{i}"))
        return instances

    def instance_matrix(self, spec: schema.InstanceSpec, key: str, obj: InstancedObject) -> np.ndarray:
        """The map of the instance `spec` of `obj`, refused where it places the object out of a scene's range."""
        matrix = np.eye(4)
        if spec.transform:
            steps = [step.model_dump(exclude_none=True) for step in spec.transform]
            with np.errstate(over="ignore", invalid="ignore"):
                matrix = transform_matrix(steps, where=self.where(f"{key}.transform"))
        if id(obj) not in self.object_corners:  # the object's box corners: an affine map keeps the rest within them
            points = np.concatenate([sh.mesh.vertices for sh in obj.shapes])
            lo, hi = points.min(axis=0), points.max(axis=0)
            self.object_corners[id(obj)] = (
                obj,
                np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])]),
            )
        corners = self.object_corners[id(obj)][1]
        with np.errstate(over="ignore", invalid="ignore"):
            placed = corners @ matrix[:3, :3].T + matrix[:3, 3]
        if problem := limits.coordinates_problem(placed):
            raise SpectraceError(f"the placed object has {problem}", where=self.where(f"{key}.transform"))
        return matrix

    def interior(self, spec: schema.InteriorSpec, key: str) -> Medium:
        """σa, σs in 1/scene unit: a preset's 1/mm table or the given spectra (no upper bound), times scale."""
        from spectrace.spectral.media_presets import preset_coefficients

        if spec.preset is not None:
            sigma_a, sigma_s = preset_coefficients(spec.preset, spec.scale, spec.g, where=self.where(f"{key}.preset"))
        else:
            sigma_a, sigma_s = (
                self.coefficient(given, f"{key}.{name}", spec.scale)
                for name, given in (("sigma_a", spec.sigma_a), ("sigma_s", spec.sigma_s))
            )
        for name, spectrum in (("sigma_a", sigma_a), ("sigma_s", sigma_s)):
            if problem := limits.spectrum_magnitude_problem(spectrum.values):
                raise SpectraceError(problem, where=self.where(f"{key}.{name}"))
        density = self.density_grid(spec.density, f"{key}.density") if spec.density is not None else None
        emission = self.spectrum(spec.emission, f"{key}.emission", emission=True) if spec.emission else None
        if (
            emission is None
            and density is not None
            and (density.emission is not None or density.temperature is not None)
        ):
            emission = Spectrum.constant(1.0)  # the grids' glow as they give it
        return Medium(
            sigma_a=sigma_a, sigma_s=sigma_s, g=spec.g, name=spec.preset or "", density=density, emission=emission
        )

    def density_grid(self, spec: schema.DensityGridSpec, key: str) -> GridVolume:
        """A grid medium's density (and albedo) from a .vol file (one channel, or three: a colour) or inline
        values."""

        def values(file: str | None, inline: list[float] | None, name: str) -> np.ndarray:
            """The grid's values; 3 channels (a file's or 3 inline values a voxel) give an RGB grid shaped
            (nz, ny, nx, 3); a file's other channel counts, its first channel."""
            if file is not None:
                grid = read_vol(self.folder / file, where=self.where(f"{key}.{name}file"))[0]
                return grid if grid.shape[3] == 3 else grid[..., 0]
            nx, ny, nz = spec.resolution or (0, 0, 0)
            count = nx * ny * nz
            if count >= 1 and len(inline or ()) == 3 * count:
                return np.asarray(inline, np.float32).reshape(nz, ny, nx, 3)
            if min(nx, ny, nz) < 1 or len(inline or ()) != count:
                need = f"{max(count, 0)} or {3 * max(count, 0)} for a colour"
                raise SpectraceError(
                    f"{len(inline or ())} values for resolution {nx}×{ny}×{nz} (need {need})",
                    where=self.where(f"{key}.{name}values"),
                )
            return np.asarray(inline, np.float32).reshape(nz, ny, nx)

        albedo = None
        if spec.albedo_file is not None or spec.albedo_values is not None:
            albedo = values(spec.albedo_file, spec.albedo_values, "albedo_")
        nano = None
        if spec.file is not None and _is_nanovdb(spec.file):
            if "box" in spec.model_fields_set:
                raise SpectraceError(
                    "a NanoVDB grid is placed by its own index-to-world map, not by box (move it with transform)",
                    where=self.where(f"{key}.box"),
                )
            nano = nanovdb_grid(self.folder / spec.file, spec.grid or "density", where=self.where(f"{key}.file"))
            density, matrix = nano.dense_grid()
        elif spec.grid is not None:
            raise SpectraceError("grid names a grid of a NanoVDB file (.nvdb)", where=self.where(f"{key}.grid"))
        elif spec.file is None and spec.values is None and albedo is not None:
            density = np.ones(albedo.shape[:3], np.float32)  # an albedo grid over a homogeneous medium
            matrix = box_matrix(*spec.box)
        else:
            density = values(spec.file, spec.values, "")
            matrix = box_matrix(*spec.box)
        if spec.transform:
            steps = [step.model_dump(exclude_none=True) for step in spec.transform]
            matrix = transform_matrix(steps, where=self.where(f"{key}.transform")) @ matrix
        scalars = {}
        for name in ("emission", "temperature"):
            file, inline = getattr(spec, f"{name}_file"), getattr(spec, f"{name}_values")
            if file is not None and _is_nanovdb(file):
                scalars[name] = self.nanovdb_companion(file, name, nano, f"{key}.{name}_file")
            elif file is not None or inline is not None:
                grid = values(file, inline, f"{name}_")
                if grid.ndim != 3:
                    raise SpectraceError(
                        f"the {name} grid takes one value a voxel", where=self.where(f"{key}.{name}_values")
                    )
                scalars[name] = grid
        if "temperature" in scalars and (spec.temperature_offset != 0.0 or spec.temperature_scale != 1.0):
            scalars["temperature"] = (scalars["temperature"] - spec.temperature_offset) * spec.temperature_scale
        return make_grid(density, matrix, albedo, where=self.where(key), outside=spec.outside, **scalars)

    def nanovdb_companion(self, file: str, name: str, density: NanoGrid | None, key: str) -> np.ndarray:
        """A NanoVDB file's grid named `name` over the voxels of the density read from a NanoVDB file (the same
        index-to-world map)."""
        if density is None:
            raise SpectraceError(f"a NanoVDB {name} grid needs the density from a NanoVDB file", where=self.where(key))
        grid = nanovdb_grid(self.folder / file, name, where=self.where(key))
        if not np.allclose(grid.index_to_world, density.index_to_world):
            raise SpectraceError(
                f"the NanoVDB {name} grid's index-to-world map differs from the density's", where=self.where(key)
            )
        return grid.dense(np.array(density.index_min) - 1, np.array(density.index_max) + 1)

    def coefficient(self, spec: schema.SpectrumSpec | None, key: str, scale: float) -> Spectrum:
        """A medium coefficient, 1/scene unit: like an emission it has no upper bound (rgb: a smooth spectrum
        reproducing the triple, see media_presets.coefficient_spectrum)."""
        from spectrace.spectral.media_presets import coefficient_spectrum

        if spec is None:
            return Spectrum.zeros()
        if spec.display is not None or spec.blackbody is not None:
            raise SpectraceError(
                "a medium coefficient takes rgb, value, spectrum, values or file", where=self.where(key)
            )
        if spec.rgb is not None:
            result = coefficient_spectrum(spec.rgb, where=self.where(f"{key}.rgb")).scaled(spec.scale)
        else:
            result = self.spectrum(spec, key, emission=True)
        return result.scaled(scale) if scale != 1.0 else result

    def display_spectrum(self, spec: schema.SpectrumSpec, key: str, emission: bool) -> Spectrum:
        """r·R(λ) + g·G(λ) + b·B(λ) of a display's primaries for the triple it shows (decoded by `encoding`). A
        display keeps its measured radiance unless white_luminance rescales it; relative displays need one."""

        if not emission:
            raise SpectraceError("a display spectrum is an emission, not a reflectance", where=self.where(key))
        if spec.image is not None:
            raise SpectraceError(
                "a display showing an image is only possible as an area emitter's radiance",
                where=self.where(f"{key}.image"),
            )
        display = self.display(spec, key)
        try:
            return display.emission(spec.rgb)
        except SpectraceError as exc:
            raise SpectraceError(exc.message, where=self.where(f"{key}.rgb")) from None

    def display(self, spec: schema.SpectrumSpec, key: str):
        from spectrace.spectral.display_catalog import load_display
        from spectrace.spectral.display_transfer import parse_encoding

        assert spec.display is not None  # asked only for a spectrum that names a display
        name = str(self.folder / spec.display) if spec.display.lower().endswith(".csv") else spec.display
        try:
            display = load_display(name, where=self.where(f"{key}.display"))
        except SpectraceError as exc:
            if exc.where == self.where(f"{key}.display"):
                raise
            # A display CSV's own error names the CSV (and its line); the scene key says who asked for it.
            raise SpectraceError(str(exc), where=self.where(f"{key}.display")) from None
        if spec.white_luminance is not None:
            display = display.scaled_to_white_luminance(spec.white_luminance)
        elif not display.absolute:
            raise SpectraceError(
                f"display '{display.name}' has relative data: give white_luminance (cd/m²)",
                where=self.where(f"{key}.white_luminance"),
            )
        return display.with_transfer(parse_encoding(spec.encoding, where=self.where(f"{key}.encoding")))

    def emitter(self, spec, key: str) -> AreaEmitter:
        """A shape's emitter: a radiance spectrum, a display's picture, or an emission texture, times scale; the
        radiance is checked once more with the scale applied, which alone may carry it past 32-bit range."""
        emitter = self._emitter(spec, key)
        if spec.polarization is not None:
            radiance = spec.radiance
            named = isinstance(radiance, schema.SpectrumSpec) and radiance.display is not None
            display = self.display(radiance, f"{key}.radiance") if named else None
            stokes = emitter_stokes(spec.polarization, display, self.where(f"{key}.polarization"))
            emitter = dataclasses.replace(emitter, stokes=stokes)
        if problem := limits.spectrum_magnitude_problem(np.array([peak_radiance(emitter)])):
            raise SpectraceError(problem, where=self.where(f"{key}.scale" if spec.scale != 1.0 else f"{key}.radiance"))
        return emitter

    def _emitter(self, spec, key: str) -> AreaEmitter:
        radiance = spec.radiance
        if isinstance(radiance, schema.SpectrumSpec) and radiance.image is not None:
            drive, primaries = self.emitter_image(radiance, f"{key}.radiance")
            mean_drive = drive.reshape(-1, 3).mean(axis=0)
            mean = Spectrum(sum(d * p.values for d, p in zip(mean_drive, primaries)), name="image mean")
            # The picture is an emission texture of the display's primaries, each texel the one containing the point.
            texture = BitmapTexture(_float32(drive), Placement(filter="nearest"), source=radiance.image)
            image = EmitterImage(texture, primaries, spec.scale)
            return AreaEmitter(
                radiance=mean.scaled(spec.scale) if spec.scale != 1.0 else mean, two_sided=spec.two_sided, image=image
            )
        if isinstance(radiance, schema.SpectrumSpec):
            return area_emitter(self.spectrum(radiance, f"{key}.radiance", emission=True), spec.two_sided, spec.scale)
        texture = self.spectrum_or_texture(radiance, f"{key}.radiance", "emission")
        return area_emitter(texture, spec.two_sided, spec.scale)

    def emitter_image(self, spec: schema.SpectrumSpec, key: str) -> tuple[np.ndarray, tuple]:
        """The picture a display shows: its encoded values decoded to linear drive by the display's encoding, and
        the display's primaries (times the spectrum's scale)."""
        from spectrace.spectral.display_transfer import decode_to_drive

        assert spec.image is not None  # asked only for a radiance that names an image
        display = self.display(spec, key)
        encoded = read_picture(self.folder / spec.image, self.where(f"{key}.image"))
        drive = np.clip(decode_to_drive(encoded, display.transfer), 0.0, 1.0)
        primaries = tuple(p * spec.scale for p in display.primaries)
        return drive, primaries

    def lights(self) -> list[Light]:
        return [LIGHTS[spec.type].from_spec(spec, self, f"lights[{i}]") for i, spec in enumerate(self.spec.lights)]


def _float32(values: np.ndarray) -> np.ndarray:
    array = np.ascontiguousarray(values, np.float32)
    array.setflags(write=False)
    return array


def is_texture_image(texture) -> bool:
    return isinstance(texture, INNER_TEXTURES)


TEXTURE_TYPE_NAMES = tuple(TEXTURES)


def load_scene(path: str | Path, overrides: dict[str, object] | None = None) -> Scene:
    """Read, validate and resolve a TOML scene file; raises SpectraceError naming the file and key path.
    `overrides`: values replacing the file's at dotted key paths ("film.width", "materials.red.reflectance"),
    before validation, as if the file said so (a sweep's grid, spectrace.sweep)."""
    path = Path(path)
    scene = scene_from_spec(path, read_scene_spec(path, overrides))
    if overrides:  # what the file does not say, for whoever reads the file again (a live session)
        scene.notes["overrides"] = dict(overrides)
    return scene


def scene_from_spec(path: Path, spec: schema.SceneSpec) -> Scene:
    """The scene of a validated spec of the file at `path` (whose folder its files are named relative to)."""
    resolver = _Resolver(path, spec)
    for name in spec.textures:
        if name in TEXTURE_TYPE_NAMES:
            raise SpectraceError(
                f"a texture may not be named after a texture type ({', '.join(TEXTURE_TYPE_NAMES)}): "
                '{ texture = "NAME" } would be ambiguous',
                where=f"{path}: textures.{name}",
            )
    materials = resolver.materials()
    shapes = resolver.shapes(materials)
    instances = resolver.instances(materials)
    lights = resolver.lights()
    for name in spec.spectra:
        resolver.named_spectrum(name, f"spectra.{name}")
    for name in spec.textures:
        resolver.named_texture(name, f"textures.{name}")
    camera = camera_from_spec(spec.camera, resolver.folder, resolver.where)
    _check_camera(camera, path)
    film_response = _film_response(spec.film, resolver)
    try:  # the rules between a filter's keys; the schema checked each key alone
        pixel_filter = pixel_filters.from_spec(spec.film.filter)
    except SpectraceError as exc:
        raise SpectraceError(exc.message, where=resolver.where(f"film.{exc.where}")) from None
    return Scene(
        camera=camera,
        width=spec.film.width,
        height=spec.film.height,
        shapes=shapes,
        lights=lights,
        integrator=spec.integrator.type,
        max_depth=spec.integrator.max_depth,
        exposure=spec.film.exposure,
        aovs=parse_aovs(spec.film.aovs),
        pixel_filter=pixel_filter,
        film_response=film_response,
        rr_depth=spec.integrator.rr_depth,
        hide_environment=spec.integrator.hide_environment,
        hide_emitters=spec.integrator.hide_emitters,
        count_thin_passes=spec.integrator.count_thin_passes,
        polarized=spec.integrator.polarized,
        pixels_per_light_path=spec.integrator.pixels_per_light_path,
        spp=spec.sampler.spp,
        seed=spec.sampler.seed,
        sampler=spec.sampler.type,
        source=path,
        instances=instances,
    )


def camera_from_spec(spec, folder: Path = Path("."), where=lambda key: key) -> Camera:
    """The model camera of a `[camera]` table (any type: spectrace.cameras); `folder` the scene file's, which
    files it names are relative to; `where(key path)` names a key in errors."""
    keys = spec.model_dump()
    fields: dict = {"origin": spec.origin, "target": spec.target, "up": spec.up, "near_clip": spec.near_clip}
    fields["far_clip"] = spec.far_clip
    fields["polarizer_angle"] = spec.polarizer_angle
    fields["type"] = spec.type
    if "fov" in keys:
        fields["fov_degrees"], fields["fov_axis"] = spec.fov, spec.fov_axis
    if spec.type == "thinlens":
        fields["aperture_radius"] = thinlens.aperture_radius(spec.aperture_radius, spec.f_number, spec.focal_length)
        distance = float(np.linalg.norm(np.subtract(spec.target, spec.origin)))
        fields["focus_distance"] = spec.focus_distance if spec.focus_distance is not None else distance
    if spec.type == "orthographic":
        fields["view_width"] = spec.view_width
    if spec.type == "realistic":
        fields["lens_system"] = _lens_system(spec, folder, where)
    return Camera(**fields)


def _lens_system(spec, folder: Path, where):
    from spectrace.cameras import realistic

    path = realistic.lens_file_path(spec.lens_file, folder)
    rows = realistic.read_lens_file(path, where("camera.lens_file"))
    try:
        return realistic.lens_system(rows, spec.aperture_diameter, spec.focus_distance, spec.film_diagonal)
    except SpectraceError as exc:
        raise SpectraceError(exc.message, where=where("camera.focus_distance")) from None


def _film_response(film: schema.FilmSpec, resolver: _Resolver) -> FilmResponse:
    """The film's observers and sensor (spectrace.film.response); errors name the film's keys."""
    sensor = None
    if film.sensor is not None:
        try:
            sensor = load_sensor(resolver.folder / film.sensor)
        except SpectraceError as exc:
            raise SpectraceError(str(exc), where=resolver.where("film.sensor")) from None
    if film.sensor_white is not None:
        if sensor is None or len(sensor.channel_names) != 3:
            raise SpectraceError(
                "sensor_white (white balance and colour correction) needs a 3-channel film.sensor",
                where=resolver.where("film.sensor_white"),
            )
        try:
            cie_illuminant(film.sensor_white)
        except SpectraceError as exc:
            raise SpectraceError(exc.message, where=resolver.where("film.sensor_white")) from None
    try:
        return FilmResponse(
            observer=film.observer,
            observers=tuple(film.observers),
            sensor=sensor,
            sensor_white=film.sensor_white,
            wavelengths=(float(film.wavelengths[0]), float(film.wavelengths[1])),
            extend_rgb=film.extend_rgb,
        )
    except SpectraceError as exc:
        if exc.where == "film.wavelengths":
            raise SpectraceError(exc.message, where=resolver.where(exc.where)) from None
        raise SpectraceError(str(exc), where=resolver.where("film")) from None


def _check_camera(camera: Camera, path: Path) -> None:
    for name in ("origin", "target", "up"):
        if problem := limits.coordinates_problem(getattr(camera, name)):
            raise SpectraceError(f"camera {name} has {problem}", where=f"{path}: camera.{name}")
    forward = np.subtract(camera.target, camera.origin)
    if np.linalg.norm(forward) == 0:
        raise SpectraceError("camera target equals origin", where=f"{path}: camera.target")
    # Written as not (>) so that an up vector too small to survive the cross product counts as parallel.
    if not np.linalg.norm(np.cross(forward, camera.up)) > 1e-9 * np.linalg.norm(forward) * np.linalg.norm(camera.up):
        raise SpectraceError("camera up is parallel to the viewing direction (or zero)", where=f"{path}: camera.up")
    if problem := clip_problem(camera):
        raise SpectraceError(problem, where=f"{path}: camera.far_clip")


def _cuts(spec: schema.ShapeSpec) -> dict:
    """A sphere's, disk's or cylinder's partial-shape keywords (the schema has checked them)."""
    if spec.type not in ANALYTIC_SHAPES:
        return {}
    keys = (spec.phi_max, spec.z_min, spec.z_max, spec.inner_radius)
    return cut_parameters(spec.type, *keys, radius=spec.radius or 1.0)


def _is_nanovdb(file: str) -> bool:
    return file.lower().endswith(".nvdb")
