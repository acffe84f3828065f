"""The import of a .blend file through Blender's own Python module (`bpy`, installed apart): the file opened,
its scene's EVALUATED state read from the depsgraph (modifiers, geometry nodes and collection instances applied),
each object handed to its kind's module, and the TOML with its folder of PLY meshes and PNG textures written all
or nothing and checked by loading it (`import_blend`, `load_blend_scene`).

A mesh several instances place (collection instances, geometry-nodes instances, linked duplicates), none of its
materials emitting, becomes one `[objects.NAME]` placed by an `[[instances]]` row each (stored once on the
device); a mesh placed once, or with an emissive material (spectrace's objects hold no emitters), becomes
`[[shapes]]` with its world transform."""

from __future__ import annotations

import contextlib
import importlib
import os
import sys
import tempfile
from functools import partial
from pathlib import Path

import numpy as np

from spectrace.errors import SpectraceError
from spectrace.interop.blender.context import BlendImport
from spectrace.interop.mitsuba.context import unique_name
from spectrace.interop.pbrt.meshes import write_ply

WARNING_PREFIX = "warning: "
SUFFIXES = (".blend",)
EXTRA_MESSAGE = "needs Blender's Python module bpy (Python 3.11: pip install bpy; docs/blender.md)"


@contextlib.contextmanager
def _quiet():
    """Blender's own chatter on the process's stdout and stderr held back: its log lines on opening a file, and the
    numpy ABI notice bpy prints when imported beside numpy 2 (bpy's wheels are built against numpy 1; the arrays
    used here go through the buffer protocol, which is unaffected)."""
    sys.stdout.flush()
    sys.stderr.flush()
    saved = [os.dup(1), os.dup(2)]
    try:
        with open(os.devnull, "w") as sink:
            os.dup2(sink.fileno(), 1)
            os.dup2(sink.fileno(), 2)
            yield
    finally:
        os.dup2(saved[0], 1)
        os.dup2(saved[1], 2)
        for fd in saved:
            os.close(fd)


def require_bpy(where: str):
    """The bpy module, or one line saying how to install it."""
    try:
        with _quiet():
            return importlib.import_module("bpy")  # an optional module, untyped
    except ImportError:
        raise SpectraceError(EXTRA_MESSAGE, where=where) from None


def _matrix(matrix) -> np.ndarray:
    return np.array([list(row) for row in matrix], dtype=np.float64)


def _transform(world: np.ndarray) -> list[dict]:
    if np.array_equal(world, np.eye(4)):
        return []
    return [{"matrix": [[float(v) for v in row] for row in world]}]


def scene_data(ctx: BlendImport, bpy, scene, depsgraph=None) -> dict:
    """The scene table of a Blender scene's evaluated state (`depsgraph`: a render's, default the view layer's)."""
    from spectrace.interop.blender.cameras import camera
    from spectrace.interop.blender.lights import light
    from spectrace.interop.blender.materials import material_name, normal_mapped
    from spectrace.interop.blender.meshes import evaluated_meshes
    from spectrace.interop.blender.world import environment

    depsgraph = depsgraph if depsgraph is not None else bpy.context.evaluated_depsgraph_get()
    # Each placement of an object: its key (the evaluated data it shows), its object and its world matrix. The
    # iterator's objects live only during the step, so each distinct mesh is read when first met.
    placements: dict[str, list[np.ndarray]] = {}
    pieces: dict[str, list[tuple[str, str]]] = {}  # mesh key -> [(PLY file, material name)]
    names: dict[str, str] = {}
    lights: list[dict] = []
    shapes: list[dict] = []
    for instance in depsgraph.object_instances:
        obj = instance.object
        matrix = _matrix(instance.matrix_world)
        if obj.type == "LIGHT":
            rows, light_shapes = light(ctx, obj, matrix)
            lights += rows
            shapes += light_shapes
            continue
        if obj.type in ("CAMERA", "EMPTY"):
            continue
        if obj.type not in ("MESH", "CURVE", "SURFACE", "META", "FONT", "CURVES", "POINTCLOUD", "VOLUME"):
            ctx.warn(f"object '{obj.name}'", f"object type {obj.type} is not imported")
            continue
        if obj.type in ("CURVES", "POINTCLOUD", "VOLUME"):
            ctx.warn(f"object '{obj.name}'", f"object type {obj.type} is not imported")
            continue
        if abs(np.linalg.det(matrix[:3, :3])) < 1e-12:
            continue
        key = f"{obj.original.name}/{obj.data.name if obj.data is not None else ''}"
        if key not in pieces:
            found = []
            slots = obj.material_slots
            where = f"object '{obj.original.name}'"
            tangents = normal_mapped(ctx, obj, where)
            for slot, mesh in evaluated_meshes(obj, tangents, partial(ctx.warn, where)).items():
                material = slots[slot].material if slot < len(slots) else None
                base = obj.original.name
                file = ctx.file_name(f"{base}_{slot}" if len(slots) > 1 else base, ".ply")
                ctx.files[file] = partial(write_ply, mesh=mesh)
                found.append((file, material_name(ctx, material)))
            pieces[key] = found
            names[key] = obj.original.name
        placements.setdefault(key, []).append(matrix)
    objects: dict[str, dict] = {}
    instances: list[dict] = []
    for key, matrices in placements.items():
        found = pieces[key]
        if not found:
            continue
        emitting = any(ctx.emitters[material] is not None for _, material in found)
        if len(matrices) > 1 and not emitting:
            name = unique_name(names[key], objects)
            objects[name] = {"shapes": [{"type": "mesh", "file": f, "material": m} for f, m in found]}
            for matrix in matrices:
                row: dict = {"object": name}
                if transform := _transform(matrix):
                    row["transform"] = transform
                instances.append(row)
            continue
        for matrix in matrices:
            for file, material in found:
                table: dict = {"type": "mesh", "file": file, "material": material, "name": names[key]}
                if transform := _transform(matrix):
                    table["transform"] = transform
                if (emitter := ctx.emitters[material]) is not None:
                    table["emitter"] = emitter
                shapes.append(table)
    if scene.camera is None:
        raise SpectraceError(f"scene '{scene.name}' has no active camera", where=str(ctx.blend_path))
    camera_object = scene.camera.evaluated_get(depsgraph)
    camera_table, film = camera(ctx, scene, camera_object, _matrix(camera_object.matrix_world))
    if (env := environment(ctx, scene.world)) is not None:
        lights.append(env)
    if not lights and not any("emitter" in shape for shape in shapes):
        raise SpectraceError(
            f"scene '{scene.name}' has no lights, no emitting materials and a black world", where=str(ctx.blend_path)
        )
    integrator: dict = {"type": "path"}
    hidden = [shape.pop("hidden") for shape in shapes if "hidden" in shape]
    if any(hidden):
        # Blender's lights are hidden from the camera by default; spectrace hides area lights only all together
        # with the environment and emitting surfaces (hide_emitters), so only where nothing else emits.
        if all(hidden) and len(hidden) == sum("emitter" in shape for shape in shapes) and env is None:
            integrator["hide_emitters"] = True
        else:
            ctx.warn("lights", "area lights hidden from the camera in Blender are seen by spectrace's camera")
    max_bounces = int(getattr(scene.cycles, "max_bounces", 12)) if hasattr(scene, "cycles") else 12
    if hasattr(scene, "cycles"):
        # spectrace ends every path at one depth; Cycles also ends diffuse, glossy and transmission chains sooner
        # (4, 4 and 12 by default), which darkens its indirect light where those limits bind
        lower = [
            f"{kind} {limit}"
            for kind in ("diffuse", "glossy", "transmission")
            if (limit := int(getattr(scene.cycles, f"{kind}_bounces", max_bounces))) < max_bounces
        ]
        if lower:
            limits = ", ".join(lower)
            ctx.note(f"Cycles' {limits} bounce limits are not imported: paths end at Max Bounces {max_bounces}")
    data: dict = {
        "camera": camera_table,
        "film": film,
        "integrator": integrator | {"max_depth": max_bounces + 2},
        "materials": ctx.materials,
        "shapes": shapes,
        "lights": lights,
        "objects": objects,
        "instances": instances,
    }
    return {key: value for key, value in data.items() if key == "materials" or value not in ([], {})}


def assets_folder_name(toml_path: Path) -> str:
    return f"{toml_path.stem}_assets"


def _open(blend_path: Path):
    """bpy with the file open; its active scene is the one imported."""
    bpy = require_bpy(str(blend_path))
    if not blend_path.is_file():
        raise SpectraceError("no such file", where=str(blend_path))
    try:
        with _quiet():
            bpy.ops.wm.open_mainfile(filepath=str(blend_path.resolve()), load_ui=False)
    except RuntimeError as error:
        reason = str(error).strip().splitlines()[-1] if str(error).strip() else "not a .blend file"
        raise SpectraceError(f"Blender cannot open it ({reason})", where=str(blend_path)) from None
    return bpy, bpy.context.scene


def blend_scene_data(ctx: BlendImport, bpy, scene, strict: bool = False, depsgraph=None) -> dict:
    data = scene_data(ctx, bpy, scene, depsgraph)
    if strict and ctx.warnings:
        raise SpectraceError(
            f"{len(ctx.warnings)} things not imported (--strict): " + "; ".join(ctx.warnings),
            where=str(ctx.blend_path),
        )
    return data


def import_blend(
    blend_path: str | Path,
    toml_path: str | Path,
    strict: bool = False,
    option: str = "the TOML file",
) -> list[str]:
    """Write the spectrace TOML scene (and its folder of meshes and textures) for a .blend file's scene and check
    that it loads; returns the notes, the warnings among them starting with "warning: "."""
    from spectrace.interop.toml_writer import check_import_output, lock_import

    blend_path, toml_path = Path(blend_path), Path(toml_path)
    require_bpy(str(blend_path))
    check_import_output(toml_path, blend_path, "the .blend file", option)
    with lock_import(toml_path, option, "spectrace import-blend"):
        bpy, scene = _open(blend_path)
        return write_blend_import(bpy, scene, blend_path, toml_path, strict, option)


def write_blend_import(
    bpy, scene, blend_path: Path, toml_path: Path, strict: bool, option: str, depsgraph=None
) -> list[str]:
    """The import of the scene open in bpy (as `depsgraph` evaluates it, default the view layer's), written to
    `toml_path` with its files (the caller holds the lock)."""
    from spectrace.interop.mitsuba.tree import shown
    from spectrace.interop.toml_writer import write_imported_scene

    ctx = BlendImport(blend_path, assets_folder_name(toml_path))
    data = blend_scene_data(ctx, bpy, scene, strict, depsgraph)
    notes = [WARNING_PREFIX + text for text in ctx.warnings] + ctx.notes
    header = "\n".join(
        [
            f"Imported from the Blender file {shown(blend_path.name, 200)} by `spectrace import-blend`.",
            *(note if note.startswith(WARNING_PREFIX) else f"note: {note}" for note in notes),
        ]
    )

    def told_at(failure: SpectraceError, path: Path) -> SpectraceError:
        return SpectraceError(f"the imported scene does not load: {failure.message}", where=str(blend_path))

    write_imported_scene(toml_path, data, header, ctx.files, told_at, option, "spectrace import-blend")
    return notes


def load_blend_scene(blend_path: str | Path):
    """A `Scene` from a .blend file (through a temporary TOML file and asset folder)."""
    from spectrace.scene import load_scene

    with tempfile.TemporaryDirectory(prefix="spectrace-blend-") as folder:
        toml_path = Path(folder) / (Path(blend_path).stem + ".toml")
        import_blend(blend_path, toml_path)
        return load_scene(toml_path).with_overrides(source=Path(blend_path))
