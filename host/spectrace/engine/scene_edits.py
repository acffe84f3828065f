"""Re-pack the parts of a scene's device buffers that an edit changes, leaving the rest (the triangles and their BVH)
as built: the material rows, the medium rows, the light rows with their sampling distribution, the instances' top
level.

Each takes the edited scene (the same shapes, lights and instances as the buffers were built from, in the same
order, some with other materials, interiors, emitters, lights or placements) and the buffers built with their packing
(build_scene_buffers(keep_packing=True)), and returns the new buffers with the names of those that changed
(SCENE_KERNEL_BUFFERS), or None where the edit changed the layout (a row more or fewer), which only a rebuild
follows. A re-packed row appends its spectra and textures to the table and texels already built, reusing what is
there (the table keeps each spectrum once), and a texture the edit brings takes the slot of one it let go where
their texels are as long (release_textures), so editing an image does not grow the texel buffer: a kernel reads the
same numbers as from a fresh build, so the image is the same bits."""

import dataclasses
from dataclasses import replace

import numpy as np

from spectrace.core.contract import LIGHT_DTYPE, MATERIAL_DTYPE, MEDIUM_DTYPE
from spectrace.engine.scene_buffers import SceneBuffers, ScenePacking, _radius_with_instances, light_distribution
from spectrace.geometry.grid_volume import medium_row
from spectrace.lights import DEVICE_LIGHTS, light_module
from spectrace.lights import area as area_light
from spectrace.lights.base import LightRows
from spectrace.materials import append_material_rows
from spectrace.scene.model import Scene
from spectrace.textures import is_texture

Edit = tuple[SceneBuffers, set[str]]


def _packing(buffers: SceneBuffers) -> ScenePacking:
    if buffers.packing is None:
        raise ValueError("these buffers were built without their packing (build_scene_buffers(keep_packing=True))")
    return buffers.packing


def _shared(buffers: SceneBuffers, packing: ScenePacking) -> Edit:
    """`buffers` with the spectrum table, texture rows and texels as rows appended to them left them, and which of
    those grew (an append never moves what was there)."""
    chunks = packing.textures.texel_chunks
    texels = np.concatenate(chunks) if len(chunks) > 1 else chunks[0]
    chunks[:] = [texels]
    changed = {"spectra"} if len(packing.table.data) != len(buffers.spectra) else set()
    rewritten, packing.textures.rewritten = packing.textures.rewritten, False
    if len(packing.textures.rows) != buffers.texture_count or rewritten:
        changed.add("textures")
    if len(texels) != len(buffers.texels) or rewritten:
        changed.add("texels")
    edited = replace(
        buffers,
        spectra=packing.table.data,
        textures=packing.textures.array(),
        texture_count=len(packing.textures.rows),
        texels=texels,
    )
    return edited, changed


def _shapes_in_order(scene: Scene) -> list:
    """The shapes in the order the build meets them: the scene's, then each instanced object's once."""
    shapes = list(scene.shapes)
    objects: set[int] = set()
    for instance in scene.instances:
        if id(instance.object) not in objects:
            objects.add(id(instance.object))
            shapes += instance.object.shapes
    return shapes


def materials_in_order(scene: Scene) -> list:
    """The materials in the order the build first meets them, which is the order of their rows."""
    return [shape.material for shape in _shapes_in_order(scene) if shape.material is not None]


def repack_materials(scene: Scene, buffers: SceneBuffers) -> Edit | None:
    """Every material row written again from `scene`'s materials."""
    packing = _packing(buffers)
    rows: list[np.ndarray] = []
    index: dict[int, int] = {}
    for material in materials_in_order(scene):
        append_material_rows(material, rows, packing.table, packing.textures, index)
    if not rows:
        return buffers, set()
    if len(rows) != len(buffers.materials):
        return None
    shared, changed = _shared(buffers, packing)
    return replace(shared, materials=np.array(rows, MATERIAL_DTYPE)), changed | {"materials"}


def repack_media(scene: Scene, buffers: SceneBuffers) -> Edit | None:
    """Every medium row written again from `scene`'s interiors."""
    packing = _packing(buffers)
    rows: list[tuple[int, int, float, int, int]] = []
    index: dict[int, int] = {}
    for shape in _shapes_in_order(scene):
        medium = shape.interior
        if medium is not None and id(medium) not in index:
            index[id(medium)] = len(rows)
            rows.append(medium_row(medium, packing.table))
    if len(rows) != buffers.medium_count:
        return None
    if not rows:
        return buffers, set()
    shared, changed = _shared(buffers, packing)
    return replace(shared, media=np.array(rows, MEDIUM_DTYPE)), changed | {"media"}


def repack_lights(
    scene: Scene, buffers: SceneBuffers, lights: set[int] | None = None, emitters: bool = True
) -> Edit | None:
    """The light rows of the shapes' emitters (unless not `emitters`) and of the scene's `lights` (their indices;
    None: all) written again from `scene`, the other rows kept, and the distribution lights are picked by made
    again. An environment map not written again keeps its texels and sampling tables."""
    packing = _packing(buffers)
    if not packing.light_power:
        return buffers, set()
    out = LightRows(
        packing.table, packing.scene_radius, DEVICE_LIGHTS.codes, packing.textures.texel_chunks, packing.textures
    )
    rows = buffers.lights.copy()
    power = list(packing.light_power)
    if emitters:
        shapes = [shape.emitter for shape in scene.shapes if shape.emitter is not None]
        emitting = area_light.write_rows(shapes, packing.triangle_emitter, packing.triangle_areas, out)
        area_light.write_shape_rows([(shapes[e], k, surface) for e, k, surface in packing.shape_emitters], out)
        if len(out.rows) != packing.area_rows or not np.array_equal(emitting, packing.emitting):
            return None
        if out.rows:
            rows[: packing.area_rows] = np.array(out.rows, LIGHT_DTYPE)
            power[: packing.area_rows] = out.power
    if len(scene.lights) != len(packing.light_spans):
        return None
    map_cdf = buffers.map_cdf
    for i, light in enumerate(scene.lights):
        if lights is not None and i not in lights:
            continue
        start, end = packing.light_spans[i]
        out.rows, out.power, out.environment_light = [], [], -1
        light_module(light).write_rows(light, out)
        written = start + out.environment_light if out.environment_light >= 0 else -1
        was = buffers.environment_light if start <= buffers.environment_light < end else -1
        if len(out.rows) != end - start or written != was:
            return None
        rows[start:end] = np.array(out.rows, LIGHT_DTYPE)
        power[start:end] = out.power
        if out.environment_light >= 0:
            map_cdf = out.map_cdf
    cdf = light_distribution(rows, power)
    packing.light_power = power
    shared, changed = _shared(buffers, packing)
    edited = replace(shared, lights=rows, light_cdf=cdf.astype(np.float32), map_cdf=map_cdf)
    return edited, changed | {"lights", "light_cdf"} | ({"map_cdf"} if map_cdf is not buffers.map_cdf else set())


def place_instances(scene: Scene, buffers: SceneBuffers) -> Edit | None:
    """The instances' top level built again for `scene`'s placements (each object's own BVH kept); the lights
    re-packed too where the scene's bounds, by which some lights are placed, moved."""
    packing = _packing(buffers)
    objects = packing.objects
    numbers: dict[int, int] = {}
    if [numbers.setdefault(id(i.object), len(numbers)) for i in scene.instances] != objects.object_of:
        return None
    objects.place(scene.instances)
    rows, nodes = objects.device_buffers(buffers.triangle_vertices)
    edited = replace(buffers, instances=rows, instance_nodes=nodes)
    changed = {"instances", "instance_nodes"}
    radius = _radius_with_instances(packing.own_radius, packing.own_box, objects.instance_boxes)
    if radius != packing.scene_radius:
        packing.scene_radius = radius
        lit = repack_lights(scene, edited)
        if lit is None:
            return None
        edited, more = lit
        changed |= more
    return edited, changed


def scene_textures(scene: Scene) -> set:
    """Every texture the scene's materials, emitters and lights hold, and the textures those hold in turn."""
    found: set = set()

    def walk(value: object) -> None:
        if isinstance(value, (list, tuple)):
            for item in value:
                walk(item)
        elif is_texture(value):
            if value not in found:
                found.add(value)
                for field in dataclasses.fields(value):  # type: ignore[arg-type]
                    walk(getattr(value, field.name))
        elif dataclasses.is_dataclass(value) and not isinstance(value, type):
            for field in dataclasses.fields(value):
                walk(getattr(value, field.name))

    for shape in _shapes_in_order(scene):
        walk((shape.material, shape.emitter))
    walk(scene.lights)
    return found


def release_textures(before: Scene, after: Scene, buffers: SceneBuffers) -> None:
    """Let the textures `before` held and `after` does not go, for those an edit brings to take their slots."""
    gone = scene_textures(before) - scene_textures(after)
    if gone and buffers.packing is not None:
        buffers.packing.textures.release(gone)
