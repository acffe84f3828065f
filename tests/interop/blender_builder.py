"""Test scenes built with Blender's own Python module (bpy), run in a child process: `python -m
tests.interop.blender_builder KIND OUT.blend [CYCLES.exr SPP]` saves the scene, and renders it with Cycles on the
CPU when given an image path; `--many FOLDER KIND...` saves each scene as FOLDER/KIND.blend in one process (bpy's
start-up paid once). Kept out of the test process so that Blender's libraries never meet the renderer's."""

import math
import sys

import bpy

WIDTH, HEIGHT = 32, 24


def _reset():
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.render.resolution_x, scene.render.resolution_y, scene.render.resolution_percentage = WIDTH, HEIGHT, 100
    world = bpy.data.worlds.new("world")
    world.use_nodes = True
    world.node_tree.nodes["Background"].inputs["Strength"].default_value = 0.0
    scene.world = world
    return scene


def _material(name, kind, **inputs):
    material = bpy.data.materials.new(name)
    material.use_nodes = True
    tree = material.node_tree
    for node in list(tree.nodes):
        tree.nodes.remove(node)
    output = tree.nodes.new("ShaderNodeOutputMaterial")
    node = tree.nodes.new(kind)
    for key, value in inputs.items():
        node.inputs[key].default_value = value
    tree.links.new(node.outputs[0], output.inputs["Surface"])
    return material, node


def _object(scene, name, mesh_op, material=None, **place):
    mesh_op(**place)
    obj = bpy.context.active_object
    obj.name = name
    if material is not None:
        obj.data.materials.append(material)
    return obj


def _camera(scene, location, rotation, **settings):
    data = bpy.data.cameras.new("camera")
    for key, value in settings.items():
        setattr(data, key, value)
    obj = bpy.data.objects.new("camera", data)
    scene.collection.objects.link(obj)
    obj.location, obj.rotation_euler = location, rotation
    scene.camera = obj
    return obj


def _light(scene, name, kind, location, rotation=(0.0, 0.0, 0.0), **settings):
    data = bpy.data.lights.new(name, kind)
    for key, value in settings.items():
        setattr(data, key, value)
    obj = bpy.data.objects.new(name, data)
    scene.collection.objects.link(obj)
    obj.location, obj.rotation_euler = location, rotation
    return obj


def grey_box():
    """A grey diffuse room (an inward box without its front wall) lit by an area light under its ceiling."""
    scene = _reset()
    grey, _ = _material("grey", "ShaderNodeBsdfDiffuse", Color=(0.5, 0.5, 0.5, 1.0))
    room = _object(scene, "room", bpy.ops.mesh.primitive_cube_add, grey, size=2.0)
    bpy.ops.object.mode_set(mode="EDIT")
    bpy.ops.mesh.select_all(action="SELECT")
    bpy.ops.mesh.flip_normals()
    bpy.ops.object.mode_set(mode="OBJECT")
    # the front wall (facing the camera, −y) removed: the camera sees inside
    mesh = room.data
    front = [p.index for p in mesh.polygons if p.center.y < -0.99]
    import bmesh

    bm = bmesh.new()
    bm.from_mesh(mesh)
    bm.faces.ensure_lookup_table()
    bmesh.ops.delete(bm, geom=[bm.faces[i] for i in front], context="FACES_ONLY")
    bm.to_mesh(mesh)
    bm.free()
    _object(scene, "block", bpy.ops.mesh.primitive_cube_add, grey, size=0.6, location=(0.3, 0.2, -0.7))
    _light(scene, "panel", "AREA", (0.0, 0.0, 0.95), size=0.8, energy=40.0)
    _camera(scene, (0.0, -3.2, 0.0), (math.pi / 2, 0.0, 0.0), lens=30.0)
    return scene


def materials_box():
    """Principled materials of several kinds, a glass, a glossy, an emission, a textured object; an area light, a sun,
    a point and a spot; a thin-lens camera; a constant world; instances of a collection; a modifier."""
    scene = _reset()
    scene.world.node_tree.nodes["Background"].inputs["Color"].default_value = (0.2, 0.3, 0.4, 1.0)
    scene.world.node_tree.nodes["Background"].inputs["Strength"].default_value = 0.5
    plastic, _ = _material(
        "plastic", "ShaderNodeBsdfPrincipled", **{"Base Color": (0.8, 0.1, 0.1, 1.0), "Roughness": 0.3}
    )
    metal, _ = _material(
        "metal",
        "ShaderNodeBsdfPrincipled",
        **{"Base Color": (0.9, 0.6, 0.2, 1.0), "Metallic": 1.0, "Roughness": 0.2, "Coat Weight": 0.5},
    )
    glassy, _ = _material(
        "glassy", "ShaderNodeBsdfPrincipled", **{"Transmission Weight": 1.0, "IOR": 1.45, "Roughness": 0.0}
    )
    brushed, _ = _material(
        "brushed",
        "ShaderNodeBsdfPrincipled",
        **{"Metallic": 1.0, "Roughness": 0.4, "Anisotropic": 0.6, "Anisotropic Rotation": 0.125},
    )
    glass, _ = _material("glass", "ShaderNodeBsdfGlass", IOR=1.5, Roughness=0.2)
    glossy, _ = _material("glossy", "ShaderNodeBsdfGlossy", Roughness=0.4)
    lamp, _ = _material("lamp", "ShaderNodeEmission", Color=(1.0, 0.9, 0.8, 1.0), Strength=3.0)
    textured, principled = _material("textured", "ShaderNodeBsdfPrincipled")
    image = bpy.data.images.new("checker", 8, 4)
    image.generated_type = "COLOR_GRID"
    node = textured.node_tree.nodes.new("ShaderNodeTexImage")
    node.image = image
    textured.node_tree.links.new(node.outputs["Color"], principled.inputs["Base Color"])
    _object(scene, "floor", bpy.ops.mesh.primitive_plane_add, plastic, size=6.0, location=(0.0, 0.0, -1.0))
    sphere = _object(scene, "ball", bpy.ops.mesh.primitive_uv_sphere_add, metal, radius=0.4, location=(-0.8, 0, -0.6))
    sphere.modifiers.new("smooth", "SUBSURF").levels = 1
    _object(scene, "gem", bpy.ops.mesh.primitive_ico_sphere_add, glass, radius=0.3, location=(0.8, 0.0, -0.7))
    _object(scene, "jar", bpy.ops.mesh.primitive_cylinder_add, glassy, radius=0.2, depth=0.6, location=(0, 1, -0.7))
    _object(scene, "tile", bpy.ops.mesh.primitive_plane_add, textured, size=0.8, location=(0.0, -0.5, -0.99))
    _object(scene, "bulb", bpy.ops.mesh.primitive_plane_add, lamp, size=0.3, location=(0.0, 0.0, 1.5))
    _object(scene, "plate", bpy.ops.mesh.primitive_plane_add, brushed, size=0.4, location=(1.5, 1.5, -0.99))
    # one mesh in a collection, placed twice by collection instances
    pebbles = bpy.data.collections.new("pebbles")
    bpy.ops.mesh.primitive_cube_add(size=0.2)
    pebble = bpy.context.active_object
    pebble.name = "pebble"
    pebble.data.materials.append(glossy)
    for collection in list(pebble.users_collection):
        collection.objects.unlink(pebble)
    pebbles.objects.link(pebble)
    for i, x in enumerate((-1.5, 1.5)):
        holder = bpy.data.objects.new(f"pebbles{i}", None)
        holder.instance_type = "COLLECTION"
        holder.instance_collection = pebbles
        holder.location = (x, 0.5, -0.9)
        scene.collection.objects.link(holder)
    _light(scene, "panel", "AREA", (0.0, 0.0, 2.0), size=1.0, size_y=0.5, shape="RECTANGLE", energy=50.0)
    _light(scene, "sun", "SUN", (0, 0, 5), (math.radians(30), 0.0, 0.0), energy=2.5, color=(1.0, 0.95, 0.9))
    _light(scene, "bulb_point", "POINT", (1.0, -1.0, 1.0), energy=80.0, shadow_soft_size=0.0)
    _light(
        scene,
        "spot",
        "SPOT",
        (-1.0, -1.0, 1.5),
        energy=120.0,
        spot_size=math.radians(50),
        spot_blend=0.2,
        shadow_soft_size=0.0,
    )
    camera = _camera(scene, (0.0, -5.0, 1.0), (math.radians(80), 0.0, 0.0), lens=35.0)
    camera.data.dof.use_dof = True
    camera.data.dof.focus_distance = 5.0
    camera.data.dof.aperture_fstop = 4.0
    return scene


def unsupported():
    """Two materials whose Roughness a Noise Texture drives, and a Toon BSDF: nodes spectrace does not import."""
    scene = _reset()
    for i in range(2):
        material, principled = _material(f"noisy{i}", "ShaderNodeBsdfPrincipled")
        noise = material.node_tree.nodes.new("ShaderNodeTexNoise")
        material.node_tree.links.new(noise.outputs["Fac"], principled.inputs["Roughness"])
        _object(scene, f"cube{i}", bpy.ops.mesh.primitive_cube_add, material, size=0.5, location=(i - 0.5, 0.0, 0.0))
    toon, _ = _material("toon", "ShaderNodeBsdfToon")
    _object(scene, "toon", bpy.ops.mesh.primitive_plane_add, toon, size=4.0, location=(0.0, 0.0, -0.5))
    _light(scene, "sun", "SUN", (0.0, 0.0, 5.0), energy=3.0)
    _camera(scene, (0.0, -5.0, 1.0), (math.radians(80), 0.0, 0.0))
    return scene


def environment(image_path):
    """A world lit by an equirectangular image (an OpenEXR file the test writes) through an Environment Texture."""
    scene = _reset()
    tree = scene.world.node_tree
    background = tree.nodes["Background"]
    background.inputs["Strength"].default_value = 2.0
    texture = tree.nodes.new("ShaderNodeTexEnvironment")
    texture.image = bpy.data.images.load(image_path)
    tree.links.new(texture.outputs["Color"], background.inputs["Color"])
    _camera(scene, (0.0, -5.0, 1.0), (math.radians(80), 0.0, 0.0))
    return scene


LIGHT_COLOUR = (1.0, 0.5, 0.25)
LIGHT_HEIGHT = 2.0
LIGHTS = {  # kind -> (settings, rotation): each light above the origin, shining down (−z) or tilted 30°
    "POINT": ({"energy": 100.0, "shadow_soft_size": 0.0}, (0.0, 0.0, 0.0)),
    "SPOT": ({"energy": 100.0, "shadow_soft_size": 0.0, "spot_size": math.radians(60.0)}, (0.0, 0.0, 0.0)),
    "SUN": ({"energy": 3.0}, (math.radians(30.0), 0.0, 0.0)),
    "AREA": ({"energy": 100.0, "size": 0.4, "shape": "SQUARE"}, (0.0, 0.0, 0.0)),
}


def light_only(kind):
    """One light of `kind` LIGHT_HEIGHT above the origin (a sun tilted 30° from the zenith) and a camera."""
    scene = _reset()
    settings, rotation = LIGHTS[kind]
    _light(scene, "light", kind, (0.0, 0.0, LIGHT_HEIGHT), rotation, color=LIGHT_COLOUR, **settings)
    _camera(scene, (0.0, -5.0, 1.0), (math.radians(80), 0.0, 0.0))
    return scene


def dense(triangles):
    """A subdivided grid of about `triangles` triangles (a Subdivision Surface modifier, applied at evaluation),
    lit by a sun: the import's timing at scale."""
    scene = _reset()
    cuts = max(1, int(math.sqrt(triangles / 2.0 / 16.0)))  # 2 levels of subdivision: 16 quads per quad
    bpy.ops.mesh.primitive_grid_add(x_subdivisions=cuts, y_subdivisions=cuts, size=4.0)
    bpy.context.active_object.modifiers.new("subdivision", "SUBSURF").levels = 2
    _light(scene, "sun", "SUN", (0.0, 0.0, 5.0), energy=3.0)
    _camera(scene, (0.0, -5.0, 3.0), (math.radians(60), 0.0, 0.0))
    return scene


def translucent():
    """A sheet of Translucent BSDF (a leaf, a lampshade) under a sun."""
    scene = _reset()
    leaf, _ = _material("leaf", "ShaderNodeBsdfTranslucent", Color=(0.5, 0.5, 0.5, 1.0))
    _object(scene, "leaf", bpy.ops.mesh.primitive_plane_add, leaf, size=1.0)
    _light(scene, "sun", "SUN", (0.0, 0.0, 3.0), energy=2.0)
    _camera(scene, (0.0, 0.0, -3.0), (math.pi, 0.0, 0.0))
    return scene


SCENES = {
    "translucent": translucent,
    "grey_box": grey_box,
    "materials_box": materials_box,
    "unsupported": unsupported,
    "dense": lambda: dense(1_000_000),
}
SCENES |= {f"light_{kind}": (lambda kind=kind: light_only(kind)) for kind in LIGHTS}


def main() -> None:
    if sys.argv[1] == "--many":
        for kind in sys.argv[3:]:
            SCENES[kind]()
            bpy.ops.wm.save_as_mainfile(filepath=f"{sys.argv[2]}/{kind}.blend")
        return
    kind, out = sys.argv[1], sys.argv[2]
    scene = environment(kind.split(":", 1)[1]) if kind.startswith("environment:") else SCENES[kind]()
    bpy.ops.wm.save_as_mainfile(filepath=out)
    if len(sys.argv) > 3:
        scene.render.engine = "CYCLES"
        scene.cycles.device = "CPU"
        scene.cycles.samples = int(sys.argv[4])
        scene.cycles.use_denoising = False
        scene.cycles.seed = 1
        scene.view_settings.view_transform = "Standard"
        scene.render.filepath = sys.argv[3]
        scene.render.image_settings.file_format = "OPEN_EXR"
        scene.render.image_settings.color_depth = "32"
        bpy.ops.render.render(write_still=True)


if __name__ == "__main__":
    main()
