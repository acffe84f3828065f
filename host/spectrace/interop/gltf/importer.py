"""The import of one glTF 2.0 file: the document read (document.py), the scene's nodes placed (nodes.py), each
node's mesh, camera and light handed to its kind's module, and the TOML with its folder of PLY meshes and PNG
textures written all or nothing and checked by loading it (the public API: `gltf_scene_data`, `import_gltf`,
`load_gltf_scene`).

A mesh that several nodes place, none of its primitives emitting, becomes one `[objects.NAME]` placed by an
`[[instances]]` row per node (stored once on the device); a mesh placed once, or with an emissive material
(spectrace's objects hold no emitters), becomes `[[shapes]]` with the node's world transform."""

from __future__ import annotations

import tempfile
from functools import partial
from pathlib import Path

import numpy as np

from spectrace.errors import SpectraceError
from spectrace.interop.gltf.cameras import camera, choose_camera, framing_camera
from spectrace.interop.gltf.context import GltfImport
from spectrace.interop.gltf.document import COMPRESSION_EXTENSIONS, GltfDocument
from spectrace.interop.gltf.lights import light
from spectrace.interop.gltf.materials import IMPORTED_EXTENSIONS, material_name
from spectrace.interop.gltf.meshes import MODE_NAMES, primitive_mesh, unread_attributes
from spectrace.interop.gltf.nodes import PlacedNode, placed_nodes
from spectrace.interop.mitsuba.context import unique_name
from spectrace.interop.pbrt.meshes import write_ply

WARNING_PREFIX = "warning: "
MATERIAL_MODELS = ("principled", "diffuse")
SUFFIXES = (".gltf", ".glb")
# Extensions the importer reads, or whose absence changes nothing a renderer shows (the mesh quantization is
# the accessors' normalized integers, which document.py reads).
SUPPORTED_EXTENSIONS = (
    "KHR_lights_punctual",
    "KHR_texture_transform",
    "KHR_mesh_quantization",
    # Variants only offer other materials; each primitive's own `material` is the default a viewer shows.
    "KHR_materials_variants",
    *IMPORTED_EXTENSIONS,
)


def _check_extensions(doc: GltfDocument, ctx: GltfImport) -> None:
    required = doc.array("extensionsRequired")
    for i, name in enumerate(required):
        if name in COMPRESSION_EXTENSIONS:
            raise doc.fail(
                f"/extensionsRequired/{i}", f"the file needs {name}, compressed data spectrace does not decode"
            )
        if name not in SUPPORTED_EXTENSIONS:
            raise doc.fail(f"/extensionsRequired/{i}", f"the file needs {name}, which spectrace does not read")
    asset = doc.json.get("asset")
    version = asset.get("version") if isinstance(asset, dict) else None
    if not isinstance(version, str) or not version.startswith("2."):
        raise doc.fail("/asset/version", f"glTF version {version!r}; spectrace reads glTF 2.0")


def _mesh_files(ctx: GltfImport, index: int) -> list[tuple[str, str, int | None]]:
    """(PLY file, material name, material index) of each triangle primitive of meshes[index], written once."""
    doc = ctx.doc
    pointer = f"/meshes/{index}"
    entry = doc.item("meshes", index, pointer)
    primitives = entry.get("primitives")
    if not isinstance(primitives, list) or not primitives:
        raise doc.fail(f"{pointer}/primitives", "must be a non-empty array")
    mesh_name = entry.get("name")
    base = mesh_name if isinstance(mesh_name, str) else f"mesh{index}"
    found = []
    for p, primitive in enumerate(primitives):
        where = f"{pointer}/primitives/{p}"
        if not isinstance(primitive, dict):
            raise doc.fail(where, "must be an object")
        mesh = primitive_mesh(doc, primitive, where)
        if mesh is None:
            ctx.warn(where, f"{MODE_NAMES[primitive['mode']]} are not imported (they have no area to render)")
            ctx.unrendered_modes.add(MODE_NAMES[primitive["mode"]])
            continue
        for name in unread_attributes(primitive):
            kind = name.split("_")[0]
            ctx.warn(f"{where}/attributes/{name}", f"vertex attribute {kind} is not imported")
        if "targets" in primitive:
            ctx.warn(f"{where}/targets", "morph targets are not imported (the base shape is)")
        if len(mesh.faces) == 0:
            continue
        material = doc.index(primitive, "material", where)
        name = material_name(ctx, material, where)
        file = ctx.file_name(f"{base}_{p}" if len(primitives) > 1 else base, ".ply")
        ctx.files[file] = partial(write_ply, mesh=mesh)
        ctx.meshes[file] = mesh
        found.append((file, name, material))
    return found


def _shape(ctx: GltfImport, file: str, material: str, material_index: int | None) -> dict:
    table: dict = {"type": "mesh", "file": file, "material": material}
    if (interior := ctx.interiors[material_index]) is not None:
        table["interior"] = interior
    return table


def _matrix(world: np.ndarray) -> list[dict]:
    if np.array_equal(world, np.eye(4)):
        return []
    return [{"matrix": [[float(v) for v in row] for row in world]}]


def scene_data(ctx: GltfImport, camera_choice: str | None = None) -> dict:
    doc = ctx.doc
    _check_extensions(doc, ctx)
    for i, name in enumerate(doc.array("extensionsUsed")):
        if name not in SUPPORTED_EXTENSIONS and not str(name).startswith("KHR_materials_"):
            ctx.warn(f"/extensionsUsed/{i}", f"extension {name} is not imported")
    if doc.extension(doc.json, "KHR_materials_variants", "") is not None:
        ctx.warn("/extensions/KHR_materials_variants", "material variants are not imported (the default materials are)")
    if doc.array("animations"):
        ctx.warn("/animations", "animations are not imported (the nodes keep their rest transforms)")
    nodes = placed_nodes(doc)
    placed_meshes: list[PlacedNode] = []
    lights: list[dict] = []
    for placed in nodes:
        node = placed.node
        if "skin" in node:
            ctx.warn(f"{placed.pointer}/skin", "skins are not imported (meshes keep their bind pose)")
        if "mesh" in node:
            if abs(np.linalg.det(placed.world[:3, :3])) < 1e-12:
                ctx.note(f"{placed.pointer}: a node scaled to nothing (a hidden mesh) is left out")
            else:
                placed_meshes.append(placed)
        if doc.extension(node, "KHR_lights_punctual", placed.pointer) is not None:
            imported = light(ctx, placed)
            if imported is not None:
                ctx.origins[f"lights[{len(lights)}]"] = placed.pointer
                lights.append(imported)
    uses: dict[int, int] = {}
    for placed in placed_meshes:
        index = doc.index(placed.node, "mesh", placed.pointer)
        assert index is not None
        doc.item("meshes", index, f"{placed.pointer}/mesh")  # a reference to no mesh, told where it is made
        uses[index] = uses.get(index, 0) + 1
    files = {index: _mesh_files(ctx, index) for index in uses}
    shapes: list[dict] = []
    objects: dict[str, dict] = {}
    object_of_mesh: dict[int, str] = {}
    instances: list[dict] = []
    world_points = []
    for placed in placed_meshes:
        index = placed.node["mesh"]
        transform = _matrix(placed.world)
        for file, _, _ in files[index]:
            # the corners of the mesh's box, moved: bounds enough to frame, at 8 points a placement
            vertices = ctx.meshes[file].vertices
            if len(vertices):
                low, high = vertices.min(axis=0), vertices.max(axis=0)
                corners = np.array([[(low, high)[(i >> axis) & 1][axis] for axis in range(3)] for i in range(8)])
                world_points.append(corners @ placed.world[:3, :3].T + placed.world[:3, 3])
        emitting = any(ctx.emitters[material] is not None for _, _, material in files[index])
        if uses[index] > 1 and not emitting:
            if index not in object_of_mesh:
                mesh_name = doc.item("meshes", index, placed.pointer).get("name")
                name = unique_name(mesh_name if isinstance(mesh_name, str) else f"mesh{index}", objects)
                object_of_mesh[index] = name
                objects[name] = {"shapes": [_shape(ctx, *used) for used in files[index]]}
                ctx.origins[f"objects.{name}"] = f"/meshes/{index}"
            ctx.origins[f"instances[{len(instances)}]"] = placed.pointer
            instances.append(
                {"object": object_of_mesh[index], "transform": transform}
                if transform
                else {"object": object_of_mesh[index]}
            )
            continue
        for file, material, material_index in files[index]:
            table = _shape(ctx, file, material, material_index)
            if transform:
                table["transform"] = transform
            if (emitter := ctx.emitters[material_index]) is not None:
                table["emitter"] = emitter
            name = placed.node.get("name")
            if isinstance(name, str):
                table["name"] = name
            ctx.origins[f"shapes[{len(shapes)}]"] = placed.pointer
            shapes.append(table)
    chosen = choose_camera(ctx, nodes, camera_choice)
    if chosen is not None:
        camera_table, film = camera(ctx, chosen)
        ctx.origins["camera"] = f"/cameras/{chosen.node['camera']}"
    else:
        points = np.concatenate(world_points) if world_points else np.zeros((0, 3))
        camera_table, film = framing_camera(ctx, points)
    if not lights and not any("emitter" in shape for shape in shapes):
        # A viewer lights such a file with an environment of its own; a render without any light would be black.
        lights.append({"type": "constant", "radiance": {"rgb": [1.0, 1.0, 1.0]}})
        ctx.note("the file has no lights and no emissive materials: a uniform white environment lights it")
    data: dict = {
        "camera": camera_table,
        "film": film,
        "integrator": {"type": "path", "max_depth": -1},
    }
    data["textures"] = {}
    data["materials"] = ctx.materials
    data["shapes"] = shapes
    data["lights"] = lights
    data["objects"] = objects
    data["instances"] = instances
    return {key: value for key, value in data.items() if key == "materials" or value not in ([], {})}


def assets_folder_name(toml_path: Path) -> str:
    """The folder beside the TOML that holds the meshes and images an import writes."""
    return f"{toml_path.stem}_assets"


def _context(gltf_path: Path, toml_path: Path, material_model: str) -> GltfImport:
    if material_model not in MATERIAL_MODELS:
        raise SpectraceError(f"unknown material model '{material_model}' ({', '.join(MATERIAL_MODELS)})")
    return GltfImport(GltfDocument(gltf_path), assets_folder_name(toml_path), material_model)


def _imported(ctx: GltfImport, camera_choice: str | None, strict: bool) -> dict:
    data = scene_data(ctx, camera_choice)
    if strict and ctx.warnings:
        raise SpectraceError(
            f"{len(ctx.warnings)} things not imported (--strict): " + "; ".join(ctx.warnings),
            where=str(ctx.doc.path),
        )
    return data


def gltf_scene_data(
    gltf_path: str | Path,
    toml_path: str | Path | None = None,
    camera: str | None = None,
    material_model: str = "principled",
    strict: bool = False,
) -> tuple[dict, GltfImport]:
    """(scene data in the TOML format's structure, the import with its warnings, notes and files to write) for a
    glTF 2.0 file (.gltf or .glb). `camera`: a camera's index or name (default the first placed one)."""
    gltf_path = Path(gltf_path)
    toml_path = Path(toml_path) if toml_path is not None else gltf_path.with_suffix(".toml")
    ctx = _context(gltf_path, toml_path, material_model)
    return _imported(ctx, camera, strict), ctx


def _imported_error(ctx: GltfImport, failure: SpectraceError, toml_path: Path) -> SpectraceError:
    """The loader's complaint about the written TOML, told at the JSON pointer the value came from."""
    where = failure.where or ""
    key = where.split(": ", 1)[1] if where.startswith(f"{toml_path}: ") else ""
    matches = [p for p in ctx.origins if key == p or key.startswith((p + ".", p + "["))]
    detail = f" (imported as {key})" if key else ""
    pointer = ctx.origins[max(matches, key=len)] if matches else ""
    if not matches:
        return SpectraceError(f"the imported scene does not load: {failure.message}{detail}", where=str(ctx.doc.path))
    return ctx.doc.fail(pointer, f"{failure.message}{detail}")


def import_gltf(
    gltf_path: str | Path,
    toml_path: str | Path,
    camera: str | None = None,
    material_model: str = "principled",
    strict: bool = False,
    option: str = "the TOML file",
) -> list[str]:
    """Write the spectrace TOML scene (and its folder of meshes and textures) for a glTF 2.0 file and check that
    it loads; returns the notes, the warnings among them starting with "warning: ". option: what errors about the
    output call it (the command line's --output).

    The output is checked and locked first (spectrace.io.output_lock); the TOML and its folder are replaced
    together, and only by a complete import whose TOML loads: a failed import leaves an earlier one as it was."""
    from spectrace.interop.toml_writer import check_import_output, lock_import

    gltf_path, toml_path = Path(gltf_path), Path(toml_path)
    check_import_output(toml_path, gltf_path, "the glTF file", option)
    with lock_import(toml_path, option, "spectrace import-gltf"):
        return _import_gltf(gltf_path, toml_path, camera, material_model, strict, option)


def _import_gltf(
    gltf_path: Path, toml_path: Path, camera: str | None, material_model: str, strict: bool, option: str
) -> list[str]:
    from spectrace.interop.mitsuba.tree import shown
    from spectrace.interop.toml_writer import write_imported_scene

    ctx = _context(gltf_path, toml_path, material_model)
    data = _imported(ctx, camera, strict)
    notes = [WARNING_PREFIX + text for text in ctx.warnings] + ctx.notes
    header = "\n".join(
        [
            f"Imported from the glTF file {shown(gltf_path.name, 200)} by `spectrace import-gltf`.",
            *(note if note.startswith(WARNING_PREFIX) else f"note: {note}" for note in notes),
        ]
    )
    write_imported_scene(
        toml_path, data, header, ctx.files, partial(_imported_error, ctx), option, "spectrace import-gltf"
    )
    return notes


def load_gltf_scene(gltf_path: str | Path, camera: str | None = None, material_model: str = "principled"):
    """A `Scene` from a glTF 2.0 file (through a temporary TOML file and asset folder)."""
    from spectrace.scene import load_scene

    with tempfile.TemporaryDirectory(prefix="spectrace-gltf-") as folder:
        toml_path = Path(folder) / (Path(gltf_path).stem + ".toml")
        import_gltf(gltf_path, toml_path, camera, material_model)
        return load_scene(toml_path).with_overrides(source=Path(gltf_path))
