"""pbrt-v4's shapes as spectrace's: spheres, disks and cylinders, whole or partial, as its analytic shapes; curves
as its curves (spectrace.interop.pbrt.curves); meshes
pbrt gives inline (trianglemesh, bilinearmesh), `loopsubdiv` and the few shapes spectrace has no exact surface for
(degenerate ones, an ellipsoid with cuts or texture coordinates) as binary PLY files beside the TOML
(spectrace.interop.pbrt.meshes); PLY files a scene names rewritten there too (pbrt's ReverseOrientation and
normal-facing rules applied, gzipped files read). Object instances become spectrace objects and instances.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np

from spectrace.geometry.analytic import similarity_problem
from spectrace.geometry.mesh import winding_against_normals
from spectrace.interop.pbrt.context import Context, unique_name
from spectrace.interop.pbrt.curves import curve_geometry
from spectrace.interop.pbrt.graphics_state import Entity, Shape
from spectrace.interop.pbrt.lights import area_light
from spectrace.interop.pbrt.materials import material_name
from spectrace.interop.pbrt.media import interior_table
from spectrace.interop.pbrt.meshes import (
    MeshData,
    cylinder_mesh,
    disk_mesh,
    sphere_mesh,
    vertex_normals,
    with_default_uvs,
)
from spectrace.interop.pbrt.parser import error, shown
from spectrace.interop.pbrt.subsurface import interior_of_material

SHAPES = ("trianglemesh", "plymesh", "bilinearmesh", "loopsubdiv", "sphere", "disk", "cylinder", "curve")


def shape_table(context: Context, shape: Shape, index: int) -> dict | None:
    entity = shape.entity
    context.read.add(id(entity))
    if entity.kind not in SHAPES:
        raise error(entity.location, f"shape '{shown(entity.kind)}': spectrace imports {', '.join(SHAPES)}")
    material = material_name(context, shape.material, entity.location)
    interior = interior_table(context, shape)
    if (own := interior_of_material(context, shape.material)) is not None:
        if interior is not None:
            context.warn(entity.location, "a MediumInterface inside a subsurface material: the material's medium used")
        interior = own
    if material is None and shape.area_light is None and interior is None:
        context.notes.append(f"{entity.location}: a shape with the interface material (no surface) left out")
        return None
    if material is None and shape.area_light is not None:
        material = material_name(context, None, entity.location)
    geometry, mesh = shape_geometry(context, shape, needs_uv=reads_uv(context, material))
    table: dict = {"name": f"{entity.kind}{index}", **geometry}
    if material is not None:  # an interface around a medium: an index-matched boundary in spectrace
        table["material"] = material
    if interior is not None:
        table["interior"] = interior
    alpha = entity.find("alpha", "float")
    if alpha is not None and float(alpha.values[0]) < 1.0 and shape.area_light is not None:
        context.warn(alpha.location, '"alpha" on an area light not imported (spectrace\'s emitters are opaque)')
    elif material is not None and alpha is not None and float(alpha.values[0]) < 1.0:
        table["material"] = with_opacity(context, material, float(alpha.values[0]))
    if shape.area_light is not None:
        table["emitter"] = area_light(context, shape.area_light, mesh, context.world @ shape.world_from_object, entity)
    return table


def instanced_object(context: Context, name: str, objects: dict[str, dict]) -> str:
    """The spectrace object (its name in `objects`, added there) for pbrt object `name`, its shapes in the
    object's own space and stored once however often it is placed. As in pbrt-v4, whose instances carry no area
    lights, an area light on an object's shape is left out, with pbrt's warning."""
    shapes = context.scene.objects[name]
    for shape in shapes:
        if shape.area_light is not None:
            context.warn(
                shape.entity.location,
                f"area light on a shape of object '{shown(name)}' not imported (pbrt-v4: \"Area lights not "
                'supported with object instancing"; its instances do not emit)',
            )
    shapes = [replace(shape, area_light=None) for shape in shapes]
    object_name = unique_name(name, objects)
    tables: list[dict] = []
    world, context.world = context.world, np.eye(4)  # the object's own space; each instance carries the mirror
    try:
        for index, shape in enumerate(shapes):
            if (table := shape_table(context, shape, index)) is not None:
                context.origins[f"objects.{object_name}.shapes[{len(tables)}]"] = shape.entity.location
                tables.append(table)
    finally:
        context.world = world
    objects[object_name] = {"shapes": tables}
    return object_name


def shape_geometry(context: Context, shape: Shape, needs_uv: bool = False) -> tuple[dict, MeshData | None]:
    """The spectrace geometry keys (type, file, transform) for a pbrt shape, and its mesh when one is written.
    The one place that decides how each pbrt shape becomes spectrace geometry (analytic shapes change it)."""
    entity = shape.entity
    matrix = context.world @ shape.world_from_object
    if entity.kind == "curve":
        return curve_geometry(context, shape, matrix), None
    if (analytic := analytic_geometry(context, shape, matrix, needs_uv)) is not None:
        return analytic, None
    key = id(entity), shape.reverse_orientation, needs_uv
    if key not in context.mesh_of:
        mesh = mesh_data(context, shape)
        if needs_uv and mesh.uvs is None:
            mesh = with_default_uvs(mesh, entity.kind)
        if shape.reverse_orientation:
            mesh.faces = mesh.faces[:, ::-1].copy()
            mesh.normals = None if mesh.normals is None else -mesh.normals
        file = unique_name(f"{entity.kind}_{entity.location.line}", {Path(n).stem for n in context.meshes}) + ".ply"
        context.meshes[file] = mesh
        context.mesh_of[key] = (file, mesh)
    file, mesh = context.mesh_of[key]
    table = {"type": "mesh", "file": f"{context.mesh_folder}/{file}", "transform": [{"matrix": matrix.tolist()}]}
    return table, mesh


def analytic_geometry(context: Context, shape: Shape, matrix: np.ndarray, needs_uv: bool) -> dict | None:
    """The spectrace analytic sphere, disk or cylinder for a pbrt one, whole or partial (phimax, a sphere's
    zmin/zmax, a disk's innerradius: exact surface, smooth normals, pbrt's texture coordinates and front side), or
    None when it needs triangles: degenerate ones, and a sphere under a map that is no similarity (an ellipsoid: the
    built-in tessellation when nothing depends on its orientation, uv or cuts)."""
    entity = shape.entity
    kind = entity.kind
    if kind not in ("sphere", "disk", "cylinder"):
        return None
    radius = context.one(entity, "radius", 1.0)
    if kind == "sphere" and not radius > 0:
        raise error(entity.location, f"a sphere's radius must be > 0, got {radius:g}")
    phimax = min(context.one(entity, "phimax", 360.0), 360.0)
    if not radius > 0 or not phimax > 0:
        return None
    cuts: dict = {"phi_max": phimax} if phimax < 360.0 else {}
    # pbrt's front: the object-space normal (outward; the disk's +z), flipped when ReverseOrientation is set
    # or the shape's own placement swaps handedness (Disk/Cylinder/Sphere InteractionFromIntersection), then
    # carried to the world by the inverse transpose, which is what spectrace's flip_normals does. The mirror
    # into spectrace's world (context.world) is not pbrt's and does not count.
    flip = shape.reverse_orientation != bool(np.linalg.det(shape.world_from_object[:3, :3]) < 0)
    if kind == "sphere":
        # pbrt-v4's Sphere: zmin, zmax ordered and clamped to [-radius, radius]; the unit sphere's heights here.
        zmin, zmax = context.one(entity, "zmin", -radius), context.one(entity, "zmax", radius)
        zmin, zmax = (float(np.clip(z, -radius, radius)) / radius for z in sorted((zmin, zmax)))
        if not zmax > zmin:
            return None
        if (zmin, zmax) != (-1.0, 1.0):
            cuts |= {"z_min": zmin, "z_max": zmax}
        steps: list[dict] = [{"scale": radius}, {"matrix": matrix.tolist()}]
        if similarity_problem(matrix) is not None:
            if needs_uv or flip or cuts:
                return None
            return {"type": "sphere", "transform": steps, "tessellated": True}
    elif kind == "disk":
        inner = context.one(entity, "innerradius", 0.0)
        if not 0.0 <= inner < radius:
            return None
        if inner > 0.0:
            cuts["inner_radius"] = inner / radius
        # Spectrace's unit disk (z = 0, facing +z) scaled to the radius and lifted to z = height.
        height = context.one(entity, "height", 0.0)
        steps = [{"scale": [radius, radius, 1.0]}, {"translate": [0.0, 0.0, height]}, {"matrix": matrix.tolist()}]
    else:
        # Spectrace's cylinder (radius 1, z from 0 to 1) stretched over [zmin, zmax]; pbrt orders them itself.
        z0, z1 = sorted((context.one(entity, "zmin", -1.0), context.one(entity, "zmax", 1.0)))
        if not z1 > z0:
            return None
        steps = [{"scale": [radius, radius, z1 - z0]}, {"translate": [0.0, 0.0, z0]}, {"matrix": matrix.tolist()}]
    table: dict = {"type": kind, "transform": steps} | cuts
    if flip:
        table["flip_normals"] = True
    if needs_uv and (kind != "cylinder" or cuts):  # the whole cylinders' (u, v) already agree
        table["uv_convention"] = "pbrt"
    return table


def mesh_data(context: Context, shape: Shape) -> MeshData:
    entity = shape.entity
    kind = entity.kind
    if kind in ("trianglemesh", "bilinearmesh"):
        points = context.floats(entity, "P", None, "point3", "point")
        if points is None:
            raise error(entity.location, f'{entity.label()} needs "point3 P"')
        vertices = np.array(points).reshape(-1, 3)
        per_face = 3 if kind == "trianglemesh" else 4
        indices_parameter = entity.find("indices", "integer")
        if indices_parameter is None:
            if len(vertices) != per_face:
                raise error(
                    entity.location,
                    f'{entity.label()} needs "integer indices" unless it has exactly {per_face} points',
                )
            indices = np.arange(per_face, dtype=np.float64)
        else:
            indices = np.array(indices_parameter.values, dtype=np.float64)
            if len(indices) % per_face or np.any(indices != np.round(indices)):
                raise error(indices_parameter.location, f'"integer indices" must be whole numbers, {per_face} per face')
            if indices.size and (indices.min() < 0 or indices.max() >= len(vertices)):
                raise error(indices_parameter.location, f"an index lies outside the {len(vertices)} points")
        faces = indices.astype(np.int64).reshape(-1, per_face)
        if kind == "bilinearmesh":
            # A patch (p00, p10, p01, p11) faces (p10 - p00) × (p01 - p00): split along p00-p11, same winding.
            faces = np.concatenate([faces[:, [0, 1, 3]], faces[:, [0, 3, 2]]])
        normals = context.floats(entity, "N", None, "normal3", "normal")
        uvs = context.floats(entity, "uv", None, "point2")
        mesh = MeshData(
            vertices,
            faces,
            None if normals is None else np.array(normals).reshape(-1, 3),
            None if uvs is None else np.array(uvs).reshape(-1, 2),
        )
        for name, array in (("N", mesh.normals), ("uv", mesh.uvs)):
            if array is not None and len(array) != len(vertices):
                raise error(entity.location, f'"{name}" has {len(array)} values, "P" {len(vertices)}')
    elif kind == "plymesh":
        mesh = ply_mesh(context, entity)
    elif kind == "loopsubdiv":
        mesh = subdivided_mesh(context, entity)
    elif kind == "sphere":
        radius = context.one(entity, "radius", 1.0)
        mesh = sphere_mesh(
            radius,
            max(context.one(entity, "zmin", -radius), -radius),
            min(context.one(entity, "zmax", radius), radius),
            context.one(entity, "phimax", 360.0),
        )
    elif kind == "disk":
        mesh = disk_mesh(
            context.one(entity, "height", 0.0),
            context.one(entity, "radius", 1.0),
            context.one(entity, "innerradius", 0.0),
            context.one(entity, "phimax", 360.0),
        )
    elif kind == "cylinder":
        mesh = cylinder_mesh(
            context.one(entity, "radius", 1.0),
            context.one(entity, "zmin", -1.0),
            context.one(entity, "zmax", 1.0),
            context.one(entity, "phimax", 360.0),
        )
    else:
        raise error(entity.location, f"shape '{shown(kind)}': spectrace imports {', '.join(SHAPES)}")
    if mesh.normals is not None:
        # pbrt turns a triangle's geometric normal toward its shading normals: the normals, not the winding,
        # say which side is the front (spectrace's renderer reads it so too); the file written keeps a winding
        # that agrees, for any other reader.
        a, b, c = (mesh.vertices[mesh.faces[:, i]] for i in range(3))
        back = winding_against_normals(a, b, c, mesh.normals[mesh.faces])
        mesh.faces = np.where(back[:, None], mesh.faces[:, ::-1], mesh.faces)
    return mesh


def subdivided_mesh(context: Context, entity: Entity) -> MeshData:
    """pbrt's `loopsubdiv`: the control mesh refined `levels` times by Loop's scheme (trimesh's), shaded with
    vertex normals; pbrt then moves the vertices onto the limit surface, which this leaves out (a note)."""
    from trimesh.remesh import subdivide_loop

    points = context.floats(entity, "P", None, "point3", "point")
    indices = entity.find("indices", "integer")
    if points is None or indices is None:
        raise error(entity.location, 'loopsubdiv needs "point3 P" and "integer indices"')
    vertices = np.array(points).reshape(-1, 3)
    faces = np.array(indices.values, dtype=np.float64)
    if len(faces) % 3 or np.any(faces != np.round(faces)) or faces.min() < 0 or faces.max() >= len(vertices):
        raise error(indices.location, f'"integer indices" must be whole numbers below {len(vertices)}, 3 a face')
    levels = context.integer(entity, "levels", 3, low=0)
    if levels > 6:
        raise error(entity.location, f"loopsubdiv levels {levels}: spectrace refines at most 6 times")
    entity.find("scheme", "string")  # pbrt-v4 reads it and uses Loop's scheme whatever it says
    faces_int = faces.astype(np.int64).reshape(-1, 3)
    if levels:
        vertices, faces_int = subdivide_loop(vertices, faces_int, iterations=levels)
    context.notes.append(
        f"{entity.location}: loopsubdiv refined {levels} times without pbrt's last step onto the limit surface"
    )
    return MeshData(np.asarray(vertices), np.asarray(faces_int), vertex_normals(vertices, faces_int), None)


def ply_mesh(context: Context, entity: Entity) -> MeshData:
    from spectrace.geometry.mesh import load_mesh

    if context.absent(entity, "filename", "a one-triangle placeholder mesh"):
        from spectrace.interop.pbrt.placeholders import triangle

        return triangle()
    path = context.file_path(entity, "filename")
    if path is None:
        raise error(entity.location, 'plymesh needs "string filename"')
    # A .ply.gz is inflated within the size its header declares (spectrace.io.compressed).
    loaded = load_mesh(path, str(entity.location))
    entity.find("edgelength")  # a displacement's dicing rate: nothing to do without the displacement
    if (displacement := entity.find("displacement")) is not None:
        context.warn(displacement.location, "plymesh displacement not imported")
    uvs = None if loaded.uvs is None else np.column_stack([loaded.uvs[:, 0], 1.0 - loaded.uvs[:, 1]])
    return MeshData(np.asarray(loaded.vertices), np.asarray(loaded.faces), loaded.normals, uvs)


def reads_uv(context: Context, material: str | None) -> bool:
    """Whether rendering the TOML material `material` reads texture coordinates: a parameter of it holds a
    texture, or one of a mix's materials reads them, at any depth (as the scene loader decides, through
    spectrace.materials.material_textures). A mesh without uv then gets pbrt's default ones."""
    table = context.materials.get(material or "", {})
    if any(isinstance(value, dict) and "texture" in value for value in table.values()):
        return True
    return table.get("type") == "mix" and any(reads_uv(context, part) for part in table.get("materials", []))


def with_opacity(context: Context, material: str, opacity: float) -> str:
    name = unique_name(f"{material}_alpha", context.materials)
    context.materials[name] = context.materials[material] | {"opacity": max(opacity, 0.0)}
    return name
