"""A glTF file rendered by Cycles after Blender's own glTF importer, run in a child process (bpy stays out of the
test process): `python -m tests.interop.gltf_cycles MODEL.gltf VIEW.json OUT.exr`.

VIEW.json gives what both renderers must share and Blender's importer does not set: the camera spectrace imported
(`origin`, `target`, `up` in glTF's axes, `fov` in degrees on the vertical axis), the image size, the samples, and
whether a uniform white environment of radiance 1 lights the scene (`environment`: spectrace's stand-in for a
viewer's light when the file has none). Blender turns glTF's +y up into its +z up: (x, y, z) → (x, −z, y).
Cycles is set to follow paths as far as spectrace does (no bounce limits that matter, no clamping, no denoising)
and writes linear Rec. 709 (the sRGB primaries) to a 32-bit EXR."""

from __future__ import annotations

import json
import math
import sys

import bpy
import mathutils


def _blender(point) -> mathutils.Vector:
    return mathutils.Vector((point[0], -point[2], point[1]))


def _camera(scene, view: dict) -> None:
    data = bpy.data.cameras.new("comparison")
    data.sensor_fit = "VERTICAL"
    data.angle_y = math.radians(view["fov"])
    data.clip_start = 1e-4
    data.clip_end = 1e6
    camera = bpy.data.objects.new("comparison", data)
    scene.collection.objects.link(camera)
    origin, target = _blender(view["origin"]), _blender(view["target"])
    back = (origin - target).normalized()
    right = _blender(view["up"]).cross(back).normalized()
    up = back.cross(right)
    frame = mathutils.Matrix((right, up, back)).transposed().to_4x4()
    frame.translation = origin
    camera.matrix_world = frame
    scene.camera = camera


def _world(scene, radiance: float) -> None:
    world = bpy.data.worlds.new("comparison")
    world.use_nodes = True
    background = world.node_tree.nodes["Background"]
    background.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
    background.inputs["Strength"].default_value = radiance
    scene.world = world


def main() -> None:
    model, view_file, out = sys.argv[1:4]
    with open(view_file, encoding="utf-8") as file:
        view = json.load(file)
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.import_scene.gltf(filepath=model, export_import_convert_lighting_mode="SPEC")
    scene = bpy.context.scene
    for light in bpy.data.lights:
        # glTF's lights are punctual; Blender's importer leaves its own default radius and sun disc on them
        light.shadow_soft_size = 0.0
        if light.type == "SUN":
            light.angle = 0.0
    _camera(scene, view)
    _world(scene, 1.0 if view["environment"] else 0.0)
    scene.render.engine = "CYCLES"
    cycles = scene.cycles
    cycles.device = "CPU"
    cycles.samples = int(view["spp"])
    cycles.use_adaptive_sampling = False
    cycles.use_denoising = False
    cycles.seed = int(view.get("seed", 1))
    cycles.sample_clamp_direct = 0.0
    cycles.sample_clamp_indirect = 0.0
    cycles.blur_glossy = 0.0
    for bounces in ("max_bounces", "diffuse_bounces", "glossy_bounces", "transmission_bounces", "volume_bounces"):
        setattr(cycles, bounces, 64)
    cycles.transparent_max_bounces = 64
    cycles.caustics_reflective = cycles.caustics_refractive = True
    scene.view_settings.view_transform = "Standard"
    scene.view_settings.look = "None"
    scene.view_settings.exposure = 0.0
    scene.render.resolution_x, scene.render.resolution_y = int(view["width"]), int(view["height"])
    scene.render.resolution_percentage = 100
    scene.render.film_transparent = False
    scene.render.threads_mode = "FIXED"
    scene.render.threads = int(view.get("threads", 2))
    scene.render.filepath = out
    scene.render.image_settings.file_format = "OPEN_EXR"
    scene.render.image_settings.color_depth = "32"
    bpy.ops.render.render(write_still=True)


if __name__ == "__main__":
    main()
