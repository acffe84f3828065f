"""pbrt-v4 scenes -> spectrace scene TOML, for the subset spectrace represents (docs/pbrt.md).

spectrace.interop.pbrt.parser and .graphics_state read the file (tokens, directives, graphics state, instances
expanded); a module per kind maps what they read onto spectrace's scene format: cameras (camera, film, pixel
filter, sampler, integrator), shapes (and meshes), materials (dispatching to each material module's `from_pbrt`),
textures, media and lights, all reading pbrt's parameters through one `Context`. This module runs them and writes
the result, with the same writer (spectrace.interop.toml_writer), the same checks on the output and the same
one-line errors as the Mitsuba importer. Each convention the mappings bridge is checked by
tests/interop/test_pbrt_import.py.

Files: meshes, environment maps (resampled, spectrace.interop.pbrt.envmap) and scaled image textures go into a
folder beside the TOML, as PLY and OpenEXR.

Anything the file states that is not imported is reported: a parameter no mapping read, or a directive spectrace
has no counterpart for, as a warning naming file:line (an error with strict=True); an entity of a type spectrace
cannot represent (a realistic camera, a `measured` material, a `curve` shape) as an error
naming file:line.
"""

from __future__ import annotations

import tempfile
from collections.abc import Callable
from functools import partial
from pathlib import Path

import numpy as np

from spectrace.errors import SpectraceError
from spectrace.interop.pbrt import infinite_lights, lights, materials, textures
from spectrace.interop.pbrt.cameras import camera, integrator, sampler
from spectrace.interop.pbrt.context import Context, grouped
from spectrace.interop.pbrt.graphics_state import Entity, read_scene
from spectrace.interop.pbrt.lights import light_table
from spectrace.interop.pbrt.meshes import write_ply
from spectrace.interop.pbrt.parser import Location, error, shown
from spectrace.interop.pbrt.placeholders import check_policy
from spectrace.interop.pbrt.shapes import instanced_object, shape_table


class Import(Context):
    """The context each plugin module's `from_pbrt` is handed (material, light, camera, pixel filter, integrator,
    texture): the Context's readers, and what several mappings share (the plugin modules reach the importer only
    through it)."""

    def reflectance(self, entity: Entity, name: str, default: float) -> dict:
        """A reflectance: a spectrum (an RGB in [0, 1]), a spectrum texture, or the number `default`."""
        return materials.reflectance(self, entity, name, default)

    def rough(self, material: Entity, prefix: str = "") -> dict:
        """{"roughness": α} for a rough surface (pbrt's roughness remapped to the GGX α, a number or a float
        texture), {} for a smooth one; `prefix` names a layer's keys (`interface.`, `conductor.`)."""
        return materials.rough(self, material, prefix)

    def rough_anisotropic(self, material: Entity) -> dict:
        """As `rough`, with "roughness_v" too where uroughness and vroughness differ (an anisotropic lobe)."""
        return materials.rough_anisotropic(self, material)

    def ior(self, material: Entity) -> float | str:
        """`eta`: a number, or a named glass spectrace has (its name)."""
        return materials.ior(self, material)

    def material(self, reference: Entity | str | None, location: Location) -> str | None:
        """The TOML material name of a pbrt material (None for `interface`), each mapped once."""
        return materials.material_name(self, reference, location)

    def material_table(self, material: Entity) -> dict | None:
        """The TOML table of a pbrt material (None for `interface`)."""
        return materials.material_table(self, material)

    def texture_table(self, texture: Entity) -> dict:
        """The TOML table of a pbrt texture."""
        return textures.texture_table(self, texture)

    def texture_reference(self, entity: Entity, name: str) -> dict | None:
        """A `"texture name" "tex"` parameter as {"texture": key} (spectrum textures), or None."""
        return textures.texture_reference(self, entity, name)

    def environment_map(self, light: Entity, matrix: np.ndarray, scale: float) -> dict:
        """The `envmap` table of an image infinite light, its map resampled and written beside the TOML."""
        return lights.environment_map(self, light, matrix, scale)


def scene_data(context: Context) -> dict:
    """The scene data in the TOML format's structure; the context keeps the warnings, notes and files."""
    if not context.scene.has_world:
        raise SpectraceError("the file has no WorldBegin: is it a pbrt-v4 scene?", where=str(context.source))
    data: dict = {}
    camera(context, data)
    integrator(context, data)
    sampler(context, data)
    shapes: list[dict] = []
    lights: list[dict] = []
    for index, shape in enumerate(context.scene.shapes):
        if (table := shape_table(context, shape, index)) is not None:
            context.origins[f"shapes[{len(shapes)}]"] = shape.entity.location
            shapes.append(table)
    objects: dict[str, dict] = {}
    instances: list[dict] = []
    placed: dict[str, str] = {}  # pbrt object -> its spectrace object
    for use in context.scene.object_uses:
        if use.name not in placed:
            placed[use.name] = instanced_object(context, use.name, objects)
        if objects[placed[use.name]]["shapes"]:
            context.origins[f"instances[{len(instances)}]"] = use.location
            transform = [{"matrix": (context.world @ use.world_from_instance).tolist()}]
            instances.append({"object": placed[use.name], "transform": transform})
    objects = {name: table for name, table in objects.items() if table["shapes"]}
    entries = [(light, light_table(context, light)) for light in context.scene.lights]
    for light, table in infinite_lights.combine(context, entries):
        context.origins[f"lights[{len(lights)}]"] = light.entity.location
        lights.append(table)
    for entity in (
        context.scene.camera,
        context.scene.film,
        context.scene.pixel_filter,
        context.scene.sampler,
        context.scene.integrator,
    ):
        if entity is not None:
            context.read.add(id(entity))
    for entity in context.scene.entities:
        if id(entity) in context.read:
            for parameter in entity.parameters:
                if not parameter.used:
                    context.warn(parameter.location, f'{entity.label()}: parameter "{parameter.label()}" not imported')
    context.warnings, context.notes = grouped(context.warnings), grouped(context.notes)
    if context.textures:
        data["textures"] = context.textures
    data["materials"] = context.materials
    data["shapes"] = shapes
    data["lights"] = lights
    data["objects"] = objects
    data["instances"] = instances
    order = (
        "camera",
        "film",
        "integrator",
        "sampler",
        "textures",
        "materials",
        "shapes",
        "lights",
        "objects",
        "instances",
    )
    # materials stays even when empty: the scene format asks for the table.
    return {key: data[key] for key in order if key in data and (key == "materials" or data[key] not in ([], {}))}


def imported_error(context: Context, failure: SpectraceError, toml_path: Path) -> SpectraceError:
    """The loader's complaint about the written TOML, told at the pbrt line the value came from."""
    where = failure.where or ""
    key = where.split(": ", 1)[1] if where.startswith(f"{toml_path}: ") else ""
    matches = [p for p in context.origins if key == p or key.startswith((p + ".", p + "["))]
    detail = f" (imported as {key})" if key else ""
    if not matches:
        return SpectraceError(f"the imported scene does not load: {failure.message}{detail}", where=str(context.source))
    return error(context.origins[max(matches, key=len)], f"{failure.message}{detail}")


# ---------------------------------------------------------------- public API


def mesh_folder_name(toml_path: Path) -> str:
    """The folder beside the TOML that holds the meshes and environment maps an import writes."""
    return f"{toml_path.stem}_assets"


def pbrt_scene_data(
    pbrt_path: str | Path, toml_path: str | Path | None = None, missing_assets: str = "refuse"
) -> tuple[dict, Import]:
    """(scene data in the TOML format's structure, the importer with its warnings, notes and meshes to write).
    missing_assets: "refuse" (a missing file is an error naming it) or "placeholder" (placeholders.py)."""
    pbrt_path = Path(pbrt_path)
    toml_path = Path(toml_path) if toml_path is not None else pbrt_path.with_suffix(".toml")
    placeholder = check_policy(missing_assets) == "placeholder"
    scene = read_scene(pbrt_path, skip_missing=placeholder)
    importer = Import(scene, pbrt_path, toml_path.parent, mesh_folder_name(toml_path), missing_assets)
    return scene_data(importer), importer


def _write_image_file(path: Path, image: np.ndarray) -> None:
    """An image the import made: a one-channel float TIFF for a `.tif` (a roughness: one number per texel), a
    volume file for a `.vol` (a tabulated medium's density), else an OpenEXR."""
    if path.suffix == ".vol":
        from spectrace.geometry.grid_volume import vol_bytes

        path.write_bytes(vol_bytes(image))
    elif path.suffix == ".tif":
        from PIL import Image

        Image.fromarray(image, mode="F").save(path)
    else:
        from spectrace.io.exr import write_exr

        write_exr(path, image, None, {})


def import_pbrt(
    pbrt_path: str | Path,
    toml_path: str | Path,
    strict: bool = False,
    option: str = "the TOML file",
    missing_assets: str = "refuse",
) -> tuple[list[str], list[str]]:
    """Write the spectrace TOML scene (and its folder of meshes) for a pbrt-v4 scene and check that it loads;
    returns (warnings, notes). strict: every warning (something in the file not imported) is an error instead.
    option: what errors about the output call it (the command line's --output). missing_assets: "placeholder"
    stands in for missing meshes, images and data files, each a warning (placeholders.py; default "refuse").

    The output is checked and locked first (spectrace.io.output_lock: a second import writing it is refused); the
    TOML and its folder of meshes are replaced together, and only by a complete import whose TOML loads: a failed
    import leaves an earlier one, TOML and folder, as it was."""
    from spectrace.interop.toml_writer import check_import_output, lock_import

    pbrt_path, toml_path = Path(pbrt_path), Path(toml_path)
    check_import_output(toml_path, pbrt_path, "the pbrt scene", option)
    with lock_import(toml_path, option, "spectrace import-pbrt"):
        return _import_pbrt(pbrt_path, toml_path, strict, option, missing_assets)


def _import_pbrt(
    pbrt_path: Path, toml_path: Path, strict: bool, option: str, missing_assets: str
) -> tuple[list[str], list[str]]:
    from spectrace.interop.toml_writer import write_imported_scene

    data, importer = pbrt_scene_data(pbrt_path, toml_path, missing_assets)
    if strict and importer.warnings:
        raise SpectraceError(
            f"{len(importer.warnings)} things not imported (--strict): " + "; ".join(importer.warnings),
            where=str(pbrt_path),
        )
    header = "\n".join(
        [
            f"Imported from the pbrt-v4 scene {shown(pbrt_path.name, 200)} by `spectrace import-pbrt`.",
            *(f"warning: {text}" for text in importer.warnings),
            *(f"note: {text}" for text in importer.notes),
        ]
    )
    files: dict[str, Callable[[Path], object]] = {}
    for name, mesh in importer.meshes.items():
        files[f"{importer.mesh_folder}/{name}"] = partial(write_ply, mesh=mesh)
    for name, image in importer.files.items():
        files[f"{importer.mesh_folder}/{name}"] = partial(_write_image_file, image=image)

    found = write_imported_scene(
        toml_path, data, header, files, partial(imported_error, importer), option, "spectrace import-pbrt"
    )
    return [*importer.warnings, *found], importer.notes


def load_pbrt_scene(pbrt_path: str | Path, strict: bool = False, missing_assets: str = "refuse"):
    """A `Scene` from a pbrt-v4 file (through a temporary TOML file and mesh folder)."""
    from spectrace.scene.loader import load_scene
    from spectrace.scene.scene_warnings import warn

    with tempfile.TemporaryDirectory(prefix="spectrace-pbrt-") as folder:
        toml_path = Path(folder) / (Path(pbrt_path).stem + ".toml")
        import_pbrt(pbrt_path, toml_path, strict=strict, missing_assets=missing_assets)
        scene = load_scene(toml_path).with_overrides(source=Path(pbrt_path))
    warn(scene, pbrt_path)
    return scene
