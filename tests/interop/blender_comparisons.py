"""Scenes built with Blender's own Python module (bpy) to compare spectrace with Cycles, run in a child process:
`python -m tests.interop.blender_comparisons KIND OUT.blend CYCLES_PREFIX SPP SEEDS [ENVIRONMENT.exr]` saves the
scene and renders it with Cycles on the CPU once per seed 1..SEEDS, to CYCLES_PREFIX<seed>.exr (linear Rec.709);
`--import OUT.toml` before KIND then runs `spectrace import-blend OUT.blend -o OUT.toml` through its entry point in
this process, which has paid for bpy already.

Every scene is 48 × 48 pixels, seen by a camera 3.2 units in front of a room 2 units wide (an inward box without
its front wall) or a floor and a back wall; Cycles' settings that would bias its estimate are turned off (light
clamping, glossy filtering) and every kind of bounce is limited alike, as spectrace's max_depth limits them."""

import math
import sys

import bpy
from tests.interop.blender_builder import _camera, _light, _material, _object, _reset

SIZE = 48
BOUNCES = 8
GREY = (0.5, 0.5, 0.5, 1.0)


def _scene():
    scene = _reset()
    scene.render.resolution_x = scene.render.resolution_y = SIZE
    return scene


def _room(scene, material, front=False):
    """The inward box [−1, 1]³ without its front wall (−y), unless `front` keeps it."""
    import bmesh  # importable once bpy is

    room = _object(scene, "room", bpy.ops.mesh.primitive_cube_add, material, size=2.0)
    mesh = room.data
    bm = bmesh.new()
    bm.from_mesh(mesh)
    bmesh.ops.reverse_faces(bm, faces=bm.faces)
    if not front:
        bm.faces.ensure_lookup_table()
        bmesh.ops.delete(bm, geom=[f for f in bm.faces if f.calc_center_median().y < -0.99], context="FACES_ONLY")
    bm.to_mesh(mesh)
    bm.free()
    return room


def _front_camera(scene):
    return _camera(scene, (0.0, -3.2, 0.0), (math.pi / 2, 0.0, 0.0), lens=30.0)


def _floor_and_wall(scene, material):
    _object(scene, "floor", bpy.ops.mesh.primitive_plane_add, material, size=4.0, location=(0.0, 0.0, -1.0))
    _object(
        scene,
        "wall",
        bpy.ops.mesh.primitive_plane_add,
        material,
        size=4.0,
        location=(0.0, 1.0, 1.0),
        rotation=(math.pi / 2, 0.0, 0.0),
    )


def grey_room():
    """The allowance scene: grey Lambertian walls, a grey block, a white square area light under the ceiling."""
    scene = _scene()
    grey, _ = _material("grey", "ShaderNodeBsdfDiffuse", Color=GREY)
    _room(scene, grey)
    _object(scene, "block", bpy.ops.mesh.primitive_cube_add, grey, size=0.6, location=(0.3, 0.2, -0.7))
    _light(scene, "panel", "AREA", (0.0, 0.0, 0.95), size=0.8, energy=40.0)
    _front_camera(scene)
    return scene


GREY_LIGHTS = {  # kind -> (settings, location, rotation): a white light over a grey floor before a grey wall
    "POINT": ({"energy": 150.0, "shadow_soft_size": 0.0}, (0.3, -0.5, 1.0), (0.0, 0.0, 0.0)),
    "SPOT": (
        {"energy": 300.0, "shadow_soft_size": 0.0, "spot_size": math.radians(70.0), "spot_blend": 0.3},
        (0.0, -0.5, 1.2),
        (math.radians(-20.0), 0.0, 0.0),
    ),
    "SUN": ({"energy": 2.0, "angle": 0.0}, (0.0, 0.0, 3.0), (math.radians(40.0), 0.0, math.radians(30.0))),
    "AREA": ({"energy": 150.0, "size": 0.6, "shape": "SQUARE"}, (0.0, -0.3, 1.2), (0.0, 0.0, 0.0)),
}


def grey_light(kind):
    """One white light of `kind` over a grey Lambertian floor before a grey wall (a block casting a shadow)."""
    scene = _scene()
    grey, _ = _material("grey", "ShaderNodeBsdfDiffuse", Color=GREY)
    _floor_and_wall(scene, grey)
    _object(scene, "block", bpy.ops.mesh.primitive_cube_add, grey, size=0.5, location=(-0.3, 0.2, -0.75))
    settings, location, rotation = GREY_LIGHTS[kind]
    _light(scene, "light", kind, location, rotation, **settings)
    _front_camera(scene)
    return scene


def principled_box():
    """Four spheres of Principled BSDF kinds in a grey room lit by an area light: diffuse-like (rough, not
    metallic), a rough metal, a plastic (a rough dielectric coat over a colour) and a clear glass."""
    scene = _scene()
    grey, _ = _material("grey", "ShaderNodeBsdfDiffuse", Color=GREY)
    _room(scene, grey)
    kinds = {
        "diffuse_like": {"Base Color": (0.8, 0.3, 0.2, 1.0), "Roughness": 1.0},
        "metal": {"Base Color": (0.9, 0.7, 0.3, 1.0), "Metallic": 1.0, "Roughness": 0.3},
        "plastic": {"Base Color": (0.1, 0.3, 0.8, 1.0), "Roughness": 0.3},
        "glass": {"Transmission Weight": 1.0, "IOR": 1.5, "Roughness": 0.0},
    }
    for (name, inputs), (x, z) in zip(kinds.items(), [(-0.5, 0.1), (0.5, 0.1), (-0.5, -0.6), (0.5, -0.6)]):
        material, _ = _material(name, "ShaderNodeBsdfPrincipled", **inputs)
        ball = _object(scene, name, bpy.ops.mesh.primitive_uv_sphere_add, material, radius=0.35, location=(x, 0, z))
        bpy.ops.object.shade_smooth()
        ball.name = name
    _light(scene, "panel", "AREA", (0.0, -0.3, 0.95), size=0.8, energy=60.0)
    _front_camera(scene)
    return scene


LEVELS = (0.0, 0.25, 0.75, 1.0)


def specular_levels():
    """Specular IOR Level, constant and textured, over a dark Principled base: four spheres of levels 0, 0.25,
    0.75 and 1 (IOR 1.5), and a poster on the back wall (IOR 1.45) whose level is an image of four stripes of those
    levels, where the area light's highlight falls."""
    scene = _scene()
    grey, _ = _material("grey", "ShaderNodeBsdfDiffuse", Color=GREY)
    _room(scene, grey)
    dark = (0.05, 0.1, 0.3, 1.0)
    for i, level in enumerate(LEVELS):
        inputs = {"Base Color": dark, "Roughness": 0.3, "Specular IOR Level": level}
        material, _ = _material(f"level{i}", "ShaderNodeBsdfPrincipled", **inputs)
        x = -0.75 + 0.5 * i
        _object(scene, f"ball{i}", bpy.ops.mesh.primitive_uv_sphere_add, material, radius=0.22, location=(x, 0, -0.6))
        bpy.ops.object.shade_smooth()
    material, principled = _material(
        "striped", "ShaderNodeBsdfPrincipled", **{"Base Color": dark, "Roughness": 0.3, "IOR": 1.45}
    )
    image = bpy.data.images.new("levels", 4, 1)
    image.colorspace_settings.name = "Non-Color"
    image.pixels = [value for level in LEVELS for value in (level, level, level, 1.0)]
    image.pack()
    node = material.node_tree.nodes.new("ShaderNodeTexImage")
    node.image = image
    node.interpolation = "Closest"
    material.node_tree.links.new(node.outputs["Color"], principled.inputs["Specular IOR Level"])
    _object(
        scene,
        "poster",
        bpy.ops.mesh.primitive_plane_add,
        material,
        size=1.8,
        location=(0.0, 0.98, 0.2),
        rotation=(math.pi / 2, 0.0, 0.0),
    )
    _light(scene, "panel", "AREA", (0.0, -0.3, 0.95), size=0.8, energy=60.0)
    _front_camera(scene)
    return scene


# A tangent-space normal tilted 17° toward +u and 17° toward +v, as a Normal Map node reads the image's colour
TILTED = (0.3, 0.3, math.sqrt(1.0 - 0.18))


def _mirrored_poster(material):
    """Two quads on the back wall facing the camera, x in [−0.9, 0] and [0, 0.9], z in [−0.1, 0.9]: u runs right on
    the left one and left on the right one (a mirrored UV layout, handedness −1 there); v runs up on both."""
    mesh = bpy.data.meshes.new("poster")
    xs, bottom, top, y = (-0.9, 0.0, 0.9), -0.1, 0.9, 0.98
    mesh.from_pydata([(x, y, z) for z in (bottom, top) for x in xs], [], [(0, 1, 4, 3), (1, 2, 5, 4)])
    layer = mesh.uv_layers.new(name="UVMap")
    uv = {0: (0, 0), 1: (1, 0), 4: (1, 1), 3: (0, 1)}  # left quad: vertex -> (u, v)
    uv_right = {1: (1, 0), 2: (0, 0), 5: (0, 1), 4: (1, 1)}
    for polygon, table in zip(mesh.polygons, (uv, uv_right)):
        for corner in polygon.loop_indices:
            layer.data[corner].uv = table[mesh.loops[corner].vertex_index]
    mesh.materials.append(material)
    poster = bpy.data.objects.new("poster", mesh)
    bpy.context.scene.collection.objects.link(poster)
    return poster


def normal_mapped(ball=False):
    """A Normal Map of a constant tilt (TILTED) on a grey Lambertian mirrored-UV poster (flat faces) and, with
    `ball`, a smooth sphere, in a grey room under an area light: Cycles frames the map with the mesh's MikkTSpace
    tangents and bitangent signs. (The sphere is left out of the comparison with Cycles: below its terminator,
    where the tilted normal sees the light the surface does not, the two renderers differ by up to 10 %, with
    Blender's tangents and with those of the texture coordinates alike.)"""
    scene = _scene()
    grey, _ = _material("grey", "ShaderNodeBsdfDiffuse", Color=GREY)
    _room(scene, grey)
    material, shader = _material("bumpy", "ShaderNodeBsdfDiffuse", Color=(0.7, 0.7, 0.7, 1.0))
    image = bpy.data.images.new("tilt", 4, 4)
    image.colorspace_settings.name = "Non-Color"
    image.pixels = [v for _ in range(16) for v in (*(0.5 + 0.5 * c for c in TILTED), 1.0)]
    image.pack()
    tree = material.node_tree
    texture = tree.nodes.new("ShaderNodeTexImage")
    texture.image = image
    texture.interpolation = "Closest"
    normal_map = tree.nodes.new("ShaderNodeNormalMap")
    tree.links.new(texture.outputs["Color"], normal_map.inputs["Color"])
    tree.links.new(normal_map.outputs["Normal"], shader.inputs["Normal"])
    _mirrored_poster(material)
    if ball:
        _object(scene, "ball", bpy.ops.mesh.primitive_uv_sphere_add, material, radius=0.35, location=(0, 0, -0.6))
        bpy.ops.object.shade_smooth()
    _light(scene, "panel", "AREA", (0.0, -0.3, 0.95), size=0.8, energy=60.0)
    _front_camera(scene)
    return scene


def sky(image_path):
    """An HDRI world (an OpenEXR file the test writes) and a sun over a grey floor and a green Lambertian cube."""
    scene = _scene()
    tree = scene.world.node_tree
    background = tree.nodes["Background"]
    background.inputs["Strength"].default_value = 1.0
    texture = tree.nodes.new("ShaderNodeTexEnvironment")
    texture.image = bpy.data.images.load(image_path)
    texture.interpolation = "Closest"  # spectrace looks an environment image up texel by texel
    tree.links.new(texture.outputs["Color"], background.inputs["Color"])
    grey, _ = _material("grey", "ShaderNodeBsdfDiffuse", Color=GREY)
    _object(scene, "floor", bpy.ops.mesh.primitive_plane_add, grey, size=6.0, location=(0.0, 0.0, -1.0))
    paint, _ = _material("paint", "ShaderNodeBsdfDiffuse", Color=(0.2, 0.6, 0.3, 1.0))
    _object(scene, "cube", bpy.ops.mesh.primitive_cube_add, paint, size=0.8, location=(0.0, 0.3, -0.6))
    _light(scene, "sun", "SUN", (0, 0, 3), (math.radians(35.0), 0.0, math.radians(-40.0)), energy=2.0, angle=0.0)
    _front_camera(scene)
    return scene


def textured():
    """A plane whose Principled Base Color is an image of 4 × 4 colours on the back wall of a grey room."""
    scene = _scene()
    grey, _ = _material("grey", "ShaderNodeBsdfDiffuse", Color=GREY)
    _room(scene, grey)
    material, principled = _material("textured", "ShaderNodeBsdfPrincipled", Roughness=1.0)
    # 4 × 4 texels of distinct colours (sRGB code values), each seen over about 4 × 4 pixels: the lookup's
    # orientation and its sRGB decoding, not how the two renderers filter a minified image
    image = bpy.data.images.new("grid", 4, 4)
    codes = [((i % 4) * 0.3 + 0.05, ((i * 7) % 16) / 15.0, 1.0 - i / 15.0) for i in range(16)]
    image.pixels = [value for rgb in codes for value in (*rgb, 1.0)]
    image.pack()  # saved in the .blend file, which the export reads
    node = material.node_tree.nodes.new("ShaderNodeTexImage")
    node.image = image
    # Cycles filters an 8-bit sRGB image in its encoded values and then decodes, spectrace in linear values: over
    # these contrasts up to 30 % apart between texel centres (3 % over the image), so the texels are compared here
    node.interpolation = "Closest"
    material.node_tree.links.new(node.outputs["Color"], principled.inputs["Base Color"])
    _object(
        scene,
        "poster",
        bpy.ops.mesh.primitive_plane_add,
        material,
        size=1.6,
        location=(0.0, 0.98, 0.0),
        rotation=(math.pi / 2, 0.0, 0.0),
    )
    _light(scene, "panel", "AREA", (0.0, -0.3, 0.95), size=0.8, energy=60.0)
    _front_camera(scene)
    return scene


def glass():
    """A Glass BSDF sphere (IOR 1.5, smooth) before a coloured back wall of a grey room lit by an area light."""
    scene = _scene()
    grey, _ = _material("grey", "ShaderNodeBsdfDiffuse", Color=GREY)
    _room(scene, grey)
    red, _ = _material("red", "ShaderNodeBsdfDiffuse", Color=(0.7, 0.2, 0.1, 1.0))
    _object(
        scene,
        "backdrop",
        bpy.ops.mesh.primitive_plane_add,
        red,
        size=1.9,
        location=(0.0, 0.98, 0.0),
        rotation=(math.pi / 2, 0.0, 0.0),
    )
    clear, _ = _material("clear", "ShaderNodeBsdfGlass", IOR=1.5, Roughness=0.0)
    _object(scene, "ball", bpy.ops.mesh.primitive_uv_sphere_add, clear, radius=0.45, location=(0.0, 0.0, -0.4))
    bpy.ops.object.shade_smooth()
    _light(scene, "panel", "AREA", (0.0, -0.3, 0.95), size=0.8, energy=60.0)
    _front_camera(scene)
    return scene


SCENES = {"grey_room": grey_room, "principled_box": principled_box, "textured": textured, "glass": glass}
SCENES["specular_levels"] = specular_levels
SCENES["normal_mapped"] = normal_mapped
SCENES["normal_mapped_ball"] = lambda: normal_mapped(ball=True)
SCENES |= {f"grey_{kind.lower()}": (lambda kind=kind: grey_light(kind)) for kind in GREY_LIGHTS}


def corner_tangents(blend, out):
    """`--tangents IN.blend OUT.npz`: each mesh object's face corners as Blender holds them after evaluation, in
    object space: position, UV (active map) and MikkTSpace tangent with bitangent sign (Mesh.calc_tangents), under
    the object's name."""
    import numpy as np

    bpy.ops.wm.open_mainfile(filepath=blend)
    depsgraph = bpy.context.evaluated_depsgraph_get()
    found = {}
    for obj in bpy.context.scene.objects:
        if obj.type != "MESH":
            continue
        mesh = obj.evaluated_get(depsgraph).to_mesh()
        mesh.calc_tangents(uvmap=mesh.uv_layers.active.name)
        corners = [(*mesh.vertices[c.vertex_index].co, *mesh.uv_layers.active.uv[c.index].vector, *c.tangent,
                    c.bitangent_sign) for c in mesh.loops]  # fmt: skip
        found[obj.name] = np.array(corners, dtype=np.float64)
    np.savez(out, **found)


def main() -> None:
    if sys.argv[1] == "--tangents":
        corner_tangents(sys.argv[2], sys.argv[3])
        return
    args = sys.argv[1:]
    toml = None
    if args[0] == "--import":
        toml, args = args[1], args[2:]
    kind, out, prefix, spp, seeds = args[0], args[1], args[2], int(args[3]), int(args[4])
    scene = sky(args[5]) if kind == "sky" else SCENES[kind]()
    cycles = scene.cycles
    cycles.max_bounces = cycles.diffuse_bounces = cycles.glossy_bounces = BOUNCES
    cycles.transmission_bounces = cycles.transparent_max_bounces = BOUNCES
    bpy.ops.wm.save_as_mainfile(filepath=out)
    scene.render.engine = "CYCLES"
    cycles.device = "CPU"
    cycles.samples = spp
    cycles.use_adaptive_sampling = False
    cycles.use_denoising = False
    cycles.sample_clamp_direct = cycles.sample_clamp_indirect = 0.0
    cycles.blur_glossy = 0.0
    cycles.caustics_reflective = cycles.caustics_refractive = True
    scene.view_settings.view_transform = "Standard"
    scene.render.image_settings.file_format = "OPEN_EXR"
    scene.render.image_settings.color_depth = "32"
    for seed in range(1, seeds + 1):
        cycles.seed = seed
        scene.render.filepath = f"{prefix}{seed}.exr"
        bpy.ops.render.render(write_still=True)
    if toml is not None:
        from spectrace import cli

        sys.argv = ["spectrace", "import-blend", out, "-o", toml]
        cli.main()


if __name__ == "__main__":
    main()
