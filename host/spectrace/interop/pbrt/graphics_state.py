"""pbrt-v4's graphics state: the transforms, the attribute stack, named materials, textures, media and objects,
read from the directives (spectrace.interop.pbrt.parser) into a `PbrtScene`.

The result holds the camera, film, sampler and integrator entities, and every shape, light, material and texture
with its world transform and the file:line it came from; the objects of ObjectBegin/ObjectEnd with their shapes
(under the transform at their definition) and each ObjectInstance's use of one (its CTM, which places the object's
shapes as pbrt-v4 does: the instance's CTM times each shape's). What the entities mean is left to the mapping
modules of spectrace.interop.pbrt.

Transforms follow pbrt-v4: each transform directive post-multiplies the current transform matrix (CTM),
`Transform`/`ConcatTransform` give the matrix column by column (translation in entries 12..14), `Rotate` normalises
its axis, `LookAt` sets the camera frame with image right = up × forward (pbrt's left-handed camera), and the CTM at
`Camera` is camera-from-world. `WorldBegin` resets the CTM; `AttributeBegin`/`AttributeEnd` save and restore the
whole graphics state.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from spectrace.core import limits
from spectrace.interop.pbrt.parser import Directive, Location, Parameter, error, parse_directives, shown

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
    world_from_texture: np.ndarray = field(default_factory=lambda: np.eye(4))  # the CTM where it was declared


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
    world_from_medium: dict[str, np.ndarray] = field(default_factory=dict)  # the CTM at each MakeNamedMedium
    camera_medium: str = ""  # the medium the camera sits in (MediumInterface's outside at Camera)
    entities: list[Entity] = field(default_factory=list)  # every entity read, for the unread-parameter report
    unsupported: list[str] = field(default_factory=list)  # "file:line: what" for directives not imported
    skipped: list[str] = field(default_factory=list)  # "file:line: ..." for Includes of missing files skipped
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


def read_scene(path: str | Path, skip_missing: bool = False) -> PbrtScene:
    """The scene a pbrt-v4 file describes, objects and their instances, every entity with its file:line;
    skip_missing: an Include or Import of a missing file is skipped (listed in `skipped`), not refused."""
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

    for directive in parse_directives(path, scene.skipped if skip_missing else None):
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
                entity(directive, kind, texture_name, target="texture"), value_type, state.ctm.copy()
            )
        elif name == "AreaLightSource":
            state.area_light = entity(directive, arguments[0], target="light")
        elif name == "LightSource":
            scene.lights.append(Light(entity(directive, arguments[0], target="light"), state.ctm.copy()))
        elif name == "MakeNamedMedium":
            if arguments[0] in scene.media:
                raise error(location, f"medium '{shown(arguments[0])}' defined twice")
            scene.media[arguments[0]] = entity(directive, "", arguments[0], target="medium")
            scene.world_from_medium[arguments[0]] = state.ctm.copy()
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
