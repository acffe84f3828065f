"""The import of one scene: the file read as Mitsuba's parser reads it (tree.py), the ids and references, then
each top-level element handed to its kind's module (sensors, shapes, emitters, integrators; bsdfs, textures and
media where a shape uses them), what nothing read reported, and the TOML written and checked (the public API:
`mitsuba_scene_data`, `import_mitsuba`, `load_mitsuba_scene`)."""

from __future__ import annotations

import tempfile
from functools import partial
from pathlib import Path

from spectrace.errors import SpectraceError
from spectrace.interop.mitsuba import emitters, integrators, materials, sensors, textures
from spectrace.interop.mitsuba.context import ImportContext
from spectrace.interop.mitsuba.emitters import light
from spectrace.interop.mitsuba.integrators import integrator
from spectrace.interop.mitsuba.plugins import KNOWN_TAGS, OBJECT_TAGS, supported_text
from spectrace.interop.mitsuba.sensors import sensor, whole_pixel_filter
from spectrace.interop.mitsuba.shapes import instance, shape
from spectrace.interop.mitsuba.tree import Element, SceneTree, read_scene, shown
from spectrace.lights import LIGHTS

WARNING_PREFIX = "warning: "


class MitsubaImporter(ImportContext):
    """What a plugin module's `from_mitsuba` receives: the import's context (context.py) with the helpers of the
    kinds that a mapping calls as methods: `spectrum` and `emission` for a colour or spectrum property, the rough
    BSDFs' shared `roughness` (`roughnesses` for an anisotropic lobe), `distribution` and `ior`, a one-number
    texture's `scalar_texture`, a blend's nested `material`, a texture's `uv_placement`."""

    NAMED_IOR = materials.NAMED_IOR  # Mitsuba 3's named indices of refraction, for int_ior / ext_ior
    spectrum = textures.spectrum
    texture = textures.texture
    scalar_texture = textures.scalar_texture
    texture_type = textures.texture_type
    uv_placement = textures.uv_placement
    emission = emitters.emission
    material = materials.material
    roughness = materials.roughness
    roughnesses = materials.roughnesses
    distribution = materials.distribution
    ior = materials.ior
    with_snake_case = staticmethod(integrators.with_snake_case)
    fov_x = sensors.fov_x


def report_unknown_tags(ctx: ImportContext, root: Element) -> None:
    """A warning (--strict: an error) for every element, at any depth, whose tag Mitsuba does not know: it and
    what it holds are not imported. Misspellings (<emiter>, <shpe>) would otherwise vanish unseen where nothing
    looks for them (the scene's top level, a declaration never used, a property's or a transform's children)."""
    pending = list(reversed(root.children))  # depth first, in document order
    while pending:
        element = pending.pop()
        if element.tag in KNOWN_TAGS:
            pending += reversed(element.children)
            continue
        ctx.unknown_tags += 1
        ctx.warnings.append(
            f"{shown(str(element.file or ctx.xml_path), 200)}:{element.line}: {element.path}: unknown tag "
            f"<{shown(element.tag)}> is not imported (Mitsuba 3 has no such element)"
        )


def run(ctx: ImportContext, tree: SceneTree) -> dict:
    root = tree.root
    ctx.search_folders = tree.search_folders
    report_unknown_tags(ctx, root)
    if tree.unused_parameters:
        ctx.notes.append(
            "parameters the scene does not use: " + ", ".join(shown(name) for name in tree.unused_parameters)
        )
    _collect_ids(ctx, root)
    referenced = _referenced_ids(ctx, root)
    data: dict = {"integrator": {"type": "path", "max_depth": -1}}
    shapes: list[dict] = []
    lights: list[dict] = []
    sensors = [c for c in root.children if c.tag == "sensor"]
    if not sensors:
        # Mitsuba 3 makes no default camera (its scene dropped the one it made before 3.0.0): it loads such a
        # file, usually a fragment for <include>, and refuses to render it ("No sensor specified").
        raise SpectraceError(
            "the scene has no <sensor>, and a camera is needed: Mitsuba 3 loads such a file but renders nothing "
            "from it either (it makes no default camera); add a <sensor>, or import the scene that includes "
            "this file",
            where=str(ctx.xml_path),
        )
    if len(sensors) > 1:
        ctx.notes.append(f"{ctx.at(sensors[1])}: only the first of {len(sensors)} sensors is imported")
    sensor(ctx, sensors[0], data)
    objects: dict[str, dict] = {}
    instances: list[dict] = []
    for index, child in enumerate(root.children):
        if child.tag == "shape" and child.get("type") == "shapegroup":
            continue  # a declaration: imported where an instance places it
        if child.tag == "shape" and child.get("type") == "instance":
            if (table := instance(ctx, child, objects)) is not None:
                ctx.origins[f"instances[{len(instances)}]"] = child
                instances.append(table)
        elif child.tag == "shape":
            if (table := shape(ctx, child, index)) is not None:
                ctx.origins[f"shapes[{len(shapes)}]"] = child
                shapes.append(table)
        elif child.tag == "emitter":
            if child.get("type") == "area" and child.get("id") in referenced:
                continue  # an area light declared here and given to shapes by reference
            if (table := light(ctx, child)) is not None:
                ctx.origins[f"lights[{len(lights)}]"] = child
                lights.append(table)
        elif child.tag == "integrator":
            integrator(ctx, child, data)
        elif child.tag in ("bsdf", "texture", "spectrum", "rgb", "default", "sensor", "alias"):
            continue  # declarations: imported where they are used
        elif child.tag in ("film", "sampler", "rfilter", "medium", "phase") and child.get("id") in referenced:
            continue  # the same, for what a sensor or a shape (its interior) refers to
        elif child.tag in OBJECT_TAGS:
            ctx.unsupported_object(child)
    if ctx.unsupported:
        raise SpectraceError(
            f"unsupported Mitsuba 3 plugins: {ctx.unsupported_text()} (spectrace imports {supported_text()})",
            where=str(ctx.xml_path),
        )
    environments = [
        ctx.origins[f"lights[{i}]"]
        for i, table in enumerate(lights)
        if getattr(LIGHTS[table["type"]], "IS_ENVIRONMENT", False)
    ]
    if len(environments) > 1:
        raise ctx.fail(environments[1], "a second environment emitter; spectrace takes one environment light")
    if ctx.unsupported:
        raise SpectraceError(
            f"unsupported Mitsuba 3 plugins: {ctx.unsupported_text()} (spectrace imports {supported_text()})",
            where=str(ctx.xml_path),
        )
    report_unread_properties(ctx)
    if ctx.textures:
        data["textures"] = ctx.textures
    data["materials"] = ctx.materials
    data["shapes"] = shapes
    data["lights"] = lights
    data["objects"] = {name: table for name, table in objects.items() if table["shapes"]}
    data["instances"] = instances
    if ctx.film_aovs and "film" in data:
        data["film"]["aovs"] = ctx.film_aovs
    whole_pixel_filter(ctx, data)
    order = ("camera", "film", "integrator", "sampler", "textures", "materials", "shapes", "lights")
    # materials stays even when empty (the scene format asks for the table); objects only when some are placed.
    kept = {key: data[key] for key in order if key in data and data[key] != []}
    return kept | {key: data[key] for key in ("objects", "instances") if data[key]}


def report_unread_properties(ctx: ImportContext) -> None:
    """A warning for each property of an imported object that nothing read: spectrace does not know it."""
    for properties in ctx.property_tables.values():
        owner = properties.owner
        for key in properties.unread():
            child = dict.__getitem__(properties, key)
            if child.tag not in KNOWN_TAGS:
                continue  # reported as an unknown tag
            name = child.label() if key.startswith("#") or "#" in key else f"'{shown(key)}'"
            ctx.warnings.append(
                f"{shown(str(child.file or ctx.xml_path), 200)}:{child.line}: {owner.label()}: property "
                f"{name} is not imported (spectrace does not know it)"
            )


def _referenced_ids(ctx: ImportContext, root: Element) -> set[str]:
    found: set[str] = set()
    pending = [root]
    while pending:
        element = pending.pop()
        if element.tag == "ref" and (identifier := element.get("id")) is not None:
            found.add(identifier)
        pending += element.children
    return found


def _collect_ids(ctx: ImportContext, root: Element) -> None:
    aliases: list[Element] = []
    pending = [root]
    while pending:
        element = pending.pop()
        for child in element.children:
            identifier = child.get("id") if child.tag not in ("ref", "alias") else None
            # Mitsuba refuses a scene whose objects share an id: a <ref> could not tell them apart.
            if identifier is not None and (other := ctx.ids.setdefault(identifier, child)) is not child:
                first, second = sorted((other, child), key=lambda e: (e.file != ctx.xml_path, e.line))
                raise ctx.fail(second, f"duplicate id '{shown(identifier)}' (also at {ctx.at(first)})", "id")
            if child.tag == "alias":
                aliases.append(child)
            pending.append(child)
    for alias in sorted(aliases, key=lambda e: e.line):  # <alias id="a" as="b"/>: b names a's object too
        source, target = ctx.required(alias, "id"), ctx.required(alias, "as")
        if source not in ctx.ids:
            raise ctx.fail(alias, f"alias of an undefined id '{shown(source)}'", "id")
        if target in ctx.ids:
            raise ctx.fail(alias, f"alias '{shown(target)}' names an id already taken", "as")
        ctx.ids[target] = ctx.ids[source]


def check_output_path(toml_path: Path, xml_path: Path | None = None, option: str = "the TOML file") -> None:
    """Refuse, before any work, an output that could not be written or would destroy the input: what every output
    is refused for (spectrace.io.output_files), and the XML itself. Missing folders are created when the TOML is
    written."""
    from spectrace.interop.toml_writer import check_import_output

    check_import_output(toml_path, xml_path, "the Mitsuba scene", option)


def _imported(importer: MitsubaImporter, strict: bool) -> dict:
    """The scene data; the properties nothing read are warnings among the notes, or with `strict` one error."""
    data = run(importer, read_scene(importer.xml_path, importer.parameters))
    if importer.warnings and strict:
        properties, tags = len(importer.warnings) - importer.unknown_tags, importer.unknown_tags
        counts = [f"{properties} {'property' if properties == 1 else 'properties'}"] if properties else []
        counts += [f"{tags} unknown {'tag' if tags == 1 else 'tags'}"] if tags else []
        raise SpectraceError(
            f"{' and '.join(counts)} not imported (--strict): {'; '.join(importer.warnings)}",
            where=str(importer.xml_path),
        )
    importer.notes += [WARNING_PREFIX + warning for warning in importer.warnings]
    return data


def mitsuba_scene_data(
    xml_path: str | Path,
    toml_folder: str | Path | None = None,
    parameters: dict[str, str] | None = None,
    strict: bool = False,
) -> tuple[dict, list[str]]:
    """(scene data in the TOML format's structure, notes) for a Mitsuba 3 XML scene. Mesh paths are written relative
    to `toml_folder` (default: the XML's folder). `parameters` set `$name` values, as `mitsuba -D name=value`.
    Raises SpectraceError naming every unsupported plugin. Properties spectrace does not know are notes starting
    with "warning: ", or with `strict` an error naming each."""
    xml_path = Path(xml_path)
    importer = MitsubaImporter(xml_path, Path(toml_folder) if toml_folder else xml_path.parent, parameters or {})
    return _imported(importer, strict), importer.notes


def import_mitsuba(
    xml_path: str | Path,
    toml_path: str | Path,
    parameters: dict[str, str] | None = None,
    strict: bool = False,
    option: str = "the TOML file",
) -> list[str]:
    """Write the spectrace TOML scene for a Mitsuba 3 XML scene and check that it loads; returns the notes.
    option: what errors about the output call it (the command line's --output).

    The output is checked first (a folder, a read-only place) and locked (spectrace.io.output_lock: a second import
    writing it is refused); the TOML and the files beside it that it refers to (`side_files`) are replaced
    together, and only by a complete import whose TOML loads: a failed import leaves an earlier one as it was."""
    from spectrace.interop.toml_writer import lock_import

    xml_path, toml_path = Path(xml_path), Path(toml_path)
    check_output_path(toml_path, xml_path, option)
    with lock_import(toml_path, option, "spectrace import-mitsuba"):
        return _import_mitsuba(xml_path, toml_path, parameters, strict, option)


def _import_mitsuba(
    xml_path: Path, toml_path: Path, parameters: dict[str, str] | None, strict: bool, option: str
) -> list[str]:
    from spectrace.interop.toml_writer import write_imported_scene

    importer = MitsubaImporter(xml_path, toml_path.parent, parameters or {})
    importer.side_stem = toml_path.stem
    data = _imported(importer, strict)
    header = "\n".join(
        [
            f"Imported from the Mitsuba 3 scene {shown(xml_path.name, 200)} by `spectrace import-mitsuba`.",
            *(note if note.startswith(WARNING_PREFIX) else f"note: {note}" for note in importer.notes),
        ]
    )
    files = {name: partial(_write_side, content=content) for name, content in importer.side_files.items()}
    found = write_imported_scene(
        toml_path, data, header, files, importer.imported_error, option, "spectrace import-mitsuba"
    )
    return [*importer.notes, *(f"{WARNING_PREFIX}{text}" for text in found)]


def _write_side(path: Path, content: str | bytes) -> None:
    if isinstance(content, bytes):
        path.write_bytes(content)
    else:
        path.write_text(content, encoding="utf-8")


def load_mitsuba_scene(xml_path: str | Path, parameters: dict[str, str] | None = None, strict: bool = False):
    """A `Scene` from a Mitsuba 3 XML file (through a temporary TOML file)."""
    from spectrace.scene.loader import load_scene
    from spectrace.scene.scene_warnings import warn

    with tempfile.TemporaryDirectory(prefix="spectrace-mitsuba-") as folder:
        toml_path = Path(folder) / (Path(xml_path).stem + ".toml")
        import_mitsuba(xml_path, toml_path, parameters, strict)
        scene = load_scene(toml_path).with_overrides(source=Path(xml_path))
    warn(scene, xml_path)
    return scene
