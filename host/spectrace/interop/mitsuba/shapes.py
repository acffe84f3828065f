"""Shapes: obj, ply, serialized (shape_index), rectangle, cube, the analytic sphere (center, radius), disk and cylinder
(p0, p1, radius), the sdfgrid (filename, normals), the linearcurve and bsplinecurve (their curve files),
face_normals on obj, ply, serialized and sphere; each with its bsdf (materials.py), its emitter (emitters.py) and
its interior medium (media.py). A shapegroup is a spectrace object, placed by each instance."""

from __future__ import annotations

import math

import numpy as np

from spectrace.interop.mitsuba.context import ImportContext, unique_name
from spectrace.interop.mitsuba.emitters import shape_emitter
from spectrace.interop.mitsuba.materials import material
from spectrace.interop.mitsuba.media import interior_medium
from spectrace.interop.mitsuba.plugins import SUPPORTED
from spectrace.interop.mitsuba.transforms import to_world, transform_steps
from spectrace.interop.mitsuba.tree import Element

# Shapes whose Mitsuba texture coordinates run v up the image where spectrace's (for the same surface) run down:
# Mitsuba's rectangle has v = 0 at y = -1, spectrace's at y = +1; Mitsuba reads a PLY's v as stored, spectrace
# flips it (as both do an OBJ's vt). Textures on them are imported with v flipped.
V_UP_SHAPES = ("rectangle", "ply", "serialized")
# Mitsuba 3's curve plugins and their basis in spectrace's curve shape.
CURVE_BASES = {"linearcurve": "linear", "bsplinecurve": "bspline"}


def shape(ctx: ImportContext, element: Element, index: int) -> dict | None:
    """A <shape> as a [[shapes]] table with its material, emitter and interior; None where it is not imported
    (recorded)."""
    kind = ctx.kind(element)
    if kind not in SUPPORTED["shape"]:
        ctx.unsupported_object(element)
        return None
    properties = ctx.properties(element)
    name = element.get("id") or element.get("name") or f"{kind}{index}"
    table: dict = {"name": name}
    steps: list[dict] = []
    if kind in ("obj", "ply", "serialized"):
        filename = ctx.child(properties, "filename", element)
        table |= {"type": "mesh", "file": ctx.input_file(filename, "mesh file")}
        if kind == "serialized" and "shape_index" in properties:
            table["shape_index"] = ctx.integer(properties["shape_index"], low=0)
    elif kind == "sdfgrid":  # Mitsuba's grid tensor exists only in Python; XML gives a volume file
        table |= {"type": "sdfgrid", "file": ctx.input_file(ctx.child(properties, "filename", element), "volume file")}
        if "normals" in properties:
            table["normals"] = ctx.choice(properties["normals"], ("smooth", "analytic"))
        if ctx.nested(properties, "emitter"):
            raise ctx.fail(ctx.nested(properties, "emitter")[0], "an sdfgrid cannot emit (nor in Mitsuba 3)")
    elif kind in CURVE_BASES:
        # Mitsuba 3's curve file, read as it reads it; its to_world moves the points, not the radii, as spectrace's
        # transform does.
        filename = ctx.child(properties, "filename", element)
        table |= {"type": "curve", "file": ctx.input_file(filename, "curve file"), "basis": CURVE_BASES[kind]}
        table["uv_convention"] = "mitsuba"
    else:
        table["type"] = kind
    if kind == "sphere":
        radius = ctx.number(properties["radius"]) if "radius" in properties else 1.0
        if not radius > 0.0:
            raise ctx.fail(properties["radius"], f"a sphere's radius must be > 0, got {radius:g}", "value")
        centre = ctx.vector(properties["center"]) if "center" in properties else [0.0, 0.0, 0.0]
        steps += [{"scale": radius}, {"translate": centre}]
    if kind == "cylinder":
        steps += cylinder_steps(ctx, properties)
    if "to_world" in properties:
        steps += transform_steps(ctx, properties["to_world"])
    flip = "flip_normals" in properties and ctx.boolean(properties["flip_normals"])
    if flip and kind in ("sphere", "disk", "cylinder"):
        table["flip_normals"] = True
    elif flip:
        if kind != "rectangle":
            ctx.unsupported_plugin(element, " with flip_normals")
        steps.insert(0, {"scale": [1.0, 1.0, -1.0]})  # mirroring the flat square turns its face over
    if steps:
        table["transform"] = steps
    if kind in ("obj", "ply", "serialized", "sphere"):
        face_normals = ctx.boolean(properties["face_normals"]) if "face_normals" in properties else False
        # Mitsuba 3 shades its meshes smoothly, computing vertex normals when the file has none, unless
        # face_normals is set; spectrace makes none up unless asked (face_normals = false) and shades the sphere
        # smoothly by default.
        if face_normals or kind != "sphere":
            table["face_normals"] = face_normals
    bsdf = next(iter(ctx.nested(properties, "bsdf")), None)
    emitter = next(iter(ctx.nested(properties, "emitter")), None)
    interior = interior_medium(ctx, properties)
    if interior is not None:
        table["interior"] = interior
    # Mitsuba's null bsdf: a surface without material, which every ray crosses unchanged (the index-matched boundary
    # of a medium, a light seen through), or, with neither, nothing to render.
    null = bsdf is not None and ctx.kind(ctx.resolve(bsdf)) == "null"
    if null and interior is None and emitter is None:
        ctx.notes.append(f"{ctx.at(element)}: shape '{name}' with a null bsdf is invisible: not imported")
        return None
    if not null:
        table["material"] = material(ctx, bsdf, name, flip_v=kind in V_UP_SHAPES, emits=emitter is not None)
    if emitter is not None and (emitter_table := shape_emitter(ctx, emitter)) is not None:
        table["emitter"] = emitter_table
    if null:
        return table if "emitter" in table or "interior" in table else None  # an emitter not imported is recorded
    return table if table["material"] is not None else None


def instance(ctx: ImportContext, element: Element, objects: dict[str, dict]) -> dict | None:
    """A Mitsuba `instance`: its shapegroup (imported once, as a spectrace object) placed by its to_world."""
    properties = ctx.properties(element)
    groups = ctx.nested(properties, "shape")
    if len(groups) != 1 or ctx.kind(groups[0]) != "shapegroup":
        raise ctx.fail(element, 'an instance places exactly one shapegroup (<ref id="..."/>)')
    (group,) = groups
    if id(group) not in ctx.object_names:
        ctx.object_names[id(group)] = shapegroup(ctx, group, objects)
    name = ctx.object_names[id(group)]
    if not objects[name]["shapes"]:
        return None
    table: dict = {"object": name}
    if "to_world" in properties:
        steps = transform_steps(ctx, ctx.resolve(properties["to_world"]))
        to_world(ctx, properties)  # the same steps, checked as for shapes: non-zero scales, a finite product
        if steps:
            table["transform"] = steps
    return table


def shapegroup(ctx: ImportContext, group: Element, objects: dict[str, dict]) -> str:
    """A Mitsuba `shapegroup` as a spectrace object (its shapes in their own space, stored once); its name in
    `objects`. Mitsuba 3 refuses emitters ("Instancing of emitters is not supported") and nested instancing in a
    shapegroup; so does the import. Spheres, disks and cylinders stay exact, as in Mitsuba's instances."""
    name = unique_name(group.get("id") or "shapegroup", objects)
    tables: list[dict] = []
    for index, child in enumerate(ctx.nested(ctx.properties(group), "shape")):
        kind = ctx.kind(child)
        if kind in ("shapegroup", "instance"):
            raise ctx.fail(child, f"a {kind} inside a shapegroup: nested instancing is not supported")
        emitters = [c for c in ctx.properties(child).values() if ctx.resolve(c).tag == "emitter"]
        if emitters:
            raise ctx.fail(
                emitters[0], "emitters cannot be instanced: a shapegroup's shapes do not emit (nor in Mitsuba 3)"
            )
        if (table := shape(ctx, child, index)) is None:
            continue
        ctx.origins[f"objects.{name}.shapes[{len(tables)}]"] = child
        tables.append(table)
    objects[name] = {"shapes": tables}
    return name


def cylinder_steps(ctx: ImportContext, properties: dict[str, Element]) -> list[dict]:
    """Mitsuba's cylinder from p0 to p1 of `radius`: the unit cylinder scaled by (r, r, |p1 − p0|), turned by the
    frame Mitsuba builds around the axis (its coordinate_system, Duff et al. 2017, which sets where u = 0 is),
    moved to p0."""
    radius = ctx.number(properties["radius"]) if "radius" in properties else 1.0
    if not radius > 0.0:
        raise ctx.fail(properties["radius"], f"a cylinder's radius must be > 0, got {radius:g}", "value")
    p0 = np.array(ctx.vector(properties["p0"]) if "p0" in properties else [0.0, 0.0, 0.0])
    p1 = np.array(ctx.vector(properties["p1"]) if "p1" in properties else [0.0, 0.0, 1.0])
    length = float(np.linalg.norm(p1 - p0))
    if not length > 0.0:
        raise ctx.fail(properties.get("p1") or properties["p0"], "a cylinder's p0 and p1 must differ", "x")
    n = (p1 - p0) / length
    sign = math.copysign(1.0, n[2])
    a = -1.0 / (sign + n[2])
    b = n[0] * n[1] * a
    s = [1.0 + sign * n[0] * n[0] * a, sign * b, -sign * n[0]]
    t = [b, sign + n[1] * n[1] * a, -n[1]]
    frame = np.eye(4)
    frame[:3, 0], frame[:3, 1], frame[:3, 2], frame[:3, 3] = s, t, n, p0
    return [{"scale": [radius, radius, length]}, {"matrix": frame.tolist()}]
