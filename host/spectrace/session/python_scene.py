"""The editable parameters of a scene built in Python, by key path, and the scene with some of them changed.

A scene file names its materials and lights; a scene built in Python has objects. They are named here by their
place, as a scene file's keys would name them: a material by the first shape that uses it (`materials.floor`; by
its position in the order the build meets the materials, `materials.2`, where shapes share a name), a light by its
index (`lights.0`), a shape's emitter and medium through the shape (`shapes.lamp.emitter`, `shapes.cloud.interior`).
An object's parameters are the arguments its API constructor was given (spectrace.core.api_calls), under the scene
file's names (a point light's `power`, the API's `power_w`); an argument that is itself made by a constructor (a
texture, a mix's materials) is walked into: `materials.panel.reflectance.uv_scale`, `materials.blend.materials.0.
roughness`. An edit makes the object again through its constructor with the new argument (the API's checks, one
error naming the key), then every object holding it, so that an object shared by several shapes or materials
changes everywhere it is used.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import replace
from typing import TYPE_CHECKING, Any

from spectrace.core.api_calls import call_of
from spectrace.errors import SpectraceError

if TYPE_CHECKING:
    from spectrace.scene.model import Scene


def _shapes_in_order(scene: Scene) -> list:
    from spectrace.engine.scene_edits import _shapes_in_order as in_order

    return in_order(scene)


def materials_by_label(scene: Scene) -> dict[str, Any]:
    """The scene's materials by their labels, in the order the build meets them."""
    firsts: list[tuple[Any, str]] = []
    seen: set[int] = set()
    for shape in _shapes_in_order(scene):
        if shape.material is not None and id(shape.material) not in seen:
            seen.add(id(shape.material))
            firsts.append((shape.material, shape.name))
    names = [name for _, name in firsts]
    return {
        name if name and names.count(name) == 1 and not name.isdigit() else str(i): material
        for i, (material, name) in enumerate(firsts)
    }


def shape_label(shapes: list, index: int) -> str:
    """How a key names shape `index`: its name where no other shape has it, else its index."""
    name = shapes[index].name
    return name if name and sum(s.name == name for s in shapes) == 1 and not name.isdigit() else str(index)


def roots(scene: Scene) -> dict[str, Any]:
    """Each editable object of the scene under the key that names it (shapes by their index)."""
    found = {f"materials.{label}": material for label, material in materials_by_label(scene).items()}
    found |= {f"lights.{i}": light for i, light in enumerate(scene.lights)}
    for i, shape in enumerate(scene.shapes):
        for part in ("emitter", "interior"):
            if getattr(shape, part) is not None:
                found[f"shapes.{i}.{part}"] = getattr(shape, part)
    return found


def parameters(scene: Scene) -> dict[str, object]:
    """The parameters of the scene's objects made by the API, by key path (shapes by their labels)."""
    found: dict[str, object] = {}
    for key, made in roots(scene).items():
        parts = key.split(".")
        if parts[0] == "shapes":
            key = ".".join(["shapes", shape_label(list(scene.shapes), int(parts[1])), *parts[2:]])
        _flatten(key, made, found)
    return found


def _flatten(prefix: str, made: object, found: dict[str, object]) -> None:
    call = call_of(made)
    if call is None:
        return
    names = {api: name for name, api in call.aliases().items()}
    for argument, value in call.arguments.items():
        key = f"{prefix}.{names.get(argument, argument)}"
        if call_of(value) is not None:
            _flatten(key, value, found)
        elif isinstance(value, (list, tuple)) and any(call_of(item) is not None for item in value):
            for i, item in enumerate(value):
                if call_of(item) is not None:
                    _flatten(f"{key}.{i}", item, found)
                else:
                    found[f"{key}.{i}"] = item
        else:
            found[key] = list(value) if isinstance(value, tuple) else value  # as TOML and update() give it


class ModelEdits:
    """Edits of a scene built in Python, gathered by `stage` (each checked for its key) and carried out by `apply`."""

    def __init__(self, scene: Scene) -> None:
        self.roots = roots(scene)
        self.pending: dict[int, dict[str, object]] = {}  # id(object) -> its arguments changed
        self.where: dict[int, str] = {}  # id(object) -> the key (as given) that changed it
        self.kinds: dict[str, list[str]] = {}  # materials, lights, media -> the keys (as given) that edit them

    def stage(self, key: str, value: object, given: str) -> None:
        """Stage `key` = `value` (key with shapes by their index; `given` the key as the caller wrote it)."""
        prefixes = [p for p in self.roots if key.startswith(p + ".")]
        if not prefixes:
            raise SpectraceError(
                "names no material, light, emitter or medium of the scene (session.parameters() lists the keys)",
                where=given,
            )
        prefix = max(prefixes, key=len)
        kind = {"materials": "materials", "lights": "lights"}.get(prefix.split(".")[0])
        kind = kind or ("lights" if prefix.endswith(".emitter") else "media")
        made = self.roots[prefix]
        parts = key[len(prefix) + 1 :].split(".")
        i = 0
        while True:
            call = call_of(made)
            if call is None:
                raise SpectraceError(
                    "was not made by one of spectrace's constructors (spectrace.diffuse, spectrace.point_light, "
                    "spectrace.medium, ...), so its parameters have no names to edit",
                    where=given,
                )
            argument = call.aliases().get(parts[i], parts[i])
            if argument not in call.arguments:
                names = {api: name for name, api in call.aliases().items()}
                takes = ", ".join(names.get(a, a) for a in call.arguments)
                raise SpectraceError(f"has no parameter '{parts[i]}' (it takes {takes})", where=given)
            if i == len(parts) - 1:
                self.pending.setdefault(id(made), {})[argument] = value
                self.where.setdefault(id(made), given)
                self.kinds.setdefault(kind, []).append(given)
                return
            inner = call.arguments[argument]
            if isinstance(inner, (list, tuple)) and parts[i + 1].isdigit() and int(parts[i + 1]) < len(inner):
                inner, i = inner[int(parts[i + 1])], i + 1
                if i == len(parts) - 1:
                    raise SpectraceError("an entry of a list is edited by its own parameters", where=given)
            made, i = inner, i + 1

    def apply(self, scene: Scene) -> tuple[Scene, set[int], bool]:
        """`scene` with the staged edits made, the indices of its lights made again and whether an emitter was (a
        texture an emitter shares with a material changes both)."""
        memo: dict[int, Any] = {}

        def again(made: Any) -> Any:
            if made is None or id(made) in memo:
                return memo.get(id(made), made)
            call = call_of(made)
            new = made
            if call is not None:
                arguments = {name: swapped(value) for name, value in call.arguments.items()}
                origin = next(
                    (self.where[id(v)] for v in _recorded_in(call.arguments.values()) if id(v) in self.where), None
                )
                changed = any(arguments[n] is not v for n, v in call.arguments.items())
                if id(made) in self.pending:
                    arguments |= self.pending[id(made)]
                    changed, origin = True, self.where[id(made)]
                if changed:
                    try:
                        new = call.again(arguments)
                    except SpectraceError as error:
                        raise SpectraceError(error.message, where=origin) from None
                    except (TypeError, ValueError) as error:
                        raise SpectraceError(f"not a value this parameter takes ({error})", where=origin) from None
                    self.where[id(new)] = origin or ""
            memo[id(made)] = new
            return new

        def swapped(value: Any) -> Any:
            if isinstance(value, (list, tuple)):
                items = [swapped(item) for item in value]
                return value if all(a is b for a, b in zip(items, value)) else type(value)(items)
            return again(value) if call_of(value) is not None else value

        emitters = False

        def shapes_of(shapes: Iterable) -> list:
            nonlocal emitters
            out = []
            for shape in shapes:
                material, emitter, interior = again(shape.material), again(shape.emitter), again(shape.interior)
                emitters |= emitter is not shape.emitter
                if material is not shape.material or emitter is not shape.emitter or interior is not shape.interior:
                    _check_texture_coordinates(shape, material, self.where.get(id(material), ""))
                    shape = replace(shape, material=material, emitter=emitter, interior=interior)
                out.append(shape)
            return out

        shapes = shapes_of(scene.shapes)
        objects: dict[int, Any] = {}
        instances = []
        for instance in scene.instances:
            obj = instance.object
            if id(obj) not in objects:
                placed = shapes_of(obj.shapes)
                changed = any(a is not b for a, b in zip(placed, obj.shapes))
                objects[id(obj)] = replace(obj, shapes=placed) if changed else obj
            new_object = objects[id(obj)]
            instances.append(instance if new_object is obj else replace(instance, object=new_object))
        lights = [again(light) for light in scene.lights]
        relit = {i for i, (a, b) in enumerate(zip(lights, scene.lights)) if a is not b}
        edited = replace(scene, shapes=shapes, instances=instances, lights=lights)
        return edited, relit, emitters


def _recorded_in(values: Iterable[Any]) -> Iterable[Any]:
    for value in values:
        if isinstance(value, (list, tuple)):
            yield from _recorded_in(value)
        elif call_of(value) is not None:
            yield value


def _check_texture_coordinates(shape: Any, material: Any, where: str) -> None:
    from spectrace.materials import uv_material_textures

    if material is not None and shape.mesh.uvs is None and uv_material_textures(material):
        raise SpectraceError(
            f"shape '{shape.name}' has no texture coordinates, but its material has a texture "
            f"({', '.join(uv_material_textures(material))})",
            where=where or None,
        )
