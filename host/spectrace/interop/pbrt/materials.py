"""pbrt-v4's materials: each material module of spectrace.materials maps the pbrt types it lists in
PBRT_MATERIALS with its `from_pbrt(context, material) -> dict | None` (its TOML table, or None where the material
is no surface), or says why it maps none in PBRT_NONE; this module dispatches to them through the registry
(spectrace.materials.MATERIALS), refuses what spectrace has no counterpart for, and holds what several mappings
read: reflectances, roughness (pbrt's remapping to the GGX α) and indices of refraction.

A shape's material becomes a named TOML material, each pbrt material once (`material_name`); pbrt's `interface`
(no surface) is none.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from spectrace.interop.pbrt.context import GLASSES, Context, unique_name
from spectrace.interop.pbrt.graphics_state import Entity
from spectrace.interop.pbrt.parser import Location, error, shown
from spectrace.interop.pbrt.textures import texture_reference, texture_table
from spectrace.materials import MATERIALS

# pbrt material type -> the spectrace material module whose from_pbrt maps it.
# A module that declares PBRT_MATERIALS has from_pbrt (tests/interop/test_pbrt_mapping.py).
_MAPPINGS: dict[str, Any] = {
    kind: module for module in MATERIALS.values() for kind in getattr(module, "PBRT_MATERIALS", ())
}
# What the import takes: the modules' types and `interface`, a boundary without a surface.
IMPORTED_MATERIALS = (*_MAPPINGS, "interface", "subsurface")


def material_name(context: Context, reference: Entity | str | None, location: Location) -> str | None:
    """The TOML material name for a shape's material (None for pbrt's `interface`)."""
    if reference is None:
        key: int | str = "default"
        entity = Entity("Material", "diffuse", [], location)
    elif isinstance(reference, str):
        key = reference
        if reference not in context.scene.named_materials:
            raise error(location, f"NamedMaterial '{shown(reference)}', which no MakeNamedMaterial defined")
        entity = context.scene.named_materials[reference]
    else:
        key, entity = id(reference), reference
    if key in context.material_of:
        return context.material_of[key]
    table = material_table(context, entity)
    name = None if table is None else unique_name(entity.name or entity.kind, context.materials)
    if name is not None and table is not None:
        context.materials[name] = table
    context.material_of[key] = name
    return name


def material_table(context: Context, material: Entity) -> dict | None:
    """The TOML table of a pbrt material (None for `interface`), from the module that maps its type."""
    context.read.add(id(material))
    kind = material.kind
    if material.directive == "MakeNamedMaterial":
        kind = context.string(material, "type") or ""
        if not kind:
            raise error(material.location, f"named material '{shown(material.name)}' needs \"string type\"")
    if material.directive == "Material" and kind in ("", "none"):
        # pbrt-v4's deprecated names of `interface` (Material::Create warns and makes no material)
        context.notes.append(f'{material.location}: Material "{kind}" is pbrt-v4\'s former name of "interface"')
        kind = "interface"
    imported = ", ".join(IMPORTED_MATERIALS)
    if kind not in IMPORTED_MATERIALS:
        raise error(material.location, f"unknown material '{shown(kind)}' (spectrace imports {imported})")
    for key in ("normalmap", "displacement"):
        if (parameter := material.find(key)) is not None:
            context.warn(parameter.location, f'"{parameter.label()}" not imported')
    if kind == "interface":
        return None
    if kind == "subsurface":  # a dielectric around a medium (the shape's interior: interop/pbrt/subsurface.py)
        from spectrace.interop.pbrt.subsurface import subsurface_table

        return subsurface_table(context, material, rough(context, material))
    return _MAPPINGS[kind].from_pbrt(context, material)


def reflectance(context: Context, entity: Entity, name: str, default: float) -> dict:
    return context.spectrum(entity, name, "albedo") or texture_reference(context, entity, name) or {"value": default}


def rough(context: Context, material: Entity, prefix: str = "") -> dict:
    alpha = roughness(context, material, prefix)
    return {"roughness": alpha} if isinstance(alpha, dict) or alpha > 0 else {}


def rough_anisotropic(context: Context, material: Entity) -> dict:
    """{"roughness": α along dp/du, "roughness_v": α along the bitangent} where pbrt's uroughness and vroughness
    differ (pbrt-v4 frames its BSDFs along the shading dp/du, as spectrace's anisotropic conductor), else as
    `rough`. Each is a number or a float texture, remapped as pbrt remaps it (`remaproughness`)."""
    u, v = (_axis_roughness(context, material, key) for key in ("uroughness", "vroughness"))
    if u == v:
        return rough(context, material)
    return {"roughness": u, "roughness_v": v}


def _axis_roughness(context: Context, material: Entity, key: str) -> float | dict:
    """One axis's GGX α: `key` (a number or a float texture), else `roughness`, else 0."""
    for name in (key, "roughness"):
        if (texture := material.find(name, "texture")) is not None:
            return roughness_texture(context, material, texture)
        if (number := context.one(material, name, -1.0)) >= 0:
            return min(math.sqrt(number) if context.boolean(material, "remaproughness", True) else number, 1.0)
    return 0.0


def roughness(context: Context, material: Entity, prefix: str = "") -> float | dict:
    """The GGX α: a number, or for a `"texture roughness"` a one-channel texture of α per point; `prefix` names a
    layer's keys (a coated conductor's `interface.` and `conductor.`)."""
    keys = [prefix + key for key in ("roughness", "uroughness", "vroughness")]
    if (texture := material.find(keys[0], "texture")) is not None and not any(
        material.find(key, "texture", "float") for key in keys[1:]
    ):
        return roughness_texture(context, material, texture)
    values = [context.one(material, key, -1.0) for key in keys]
    for key in keys:
        if (parameter := material.find(key, "texture")) is not None:
            context.warn(parameter.location, f'"{parameter.label()}": a roughness texture is not imported (0 used)')
    u = values[1] if values[1] >= 0 else max(values[0], 0.0)
    v = values[2] if values[2] >= 0 else max(values[0], 0.0)
    if u != v:
        context.warn(
            material.location,
            f"{material.label()}: anisotropic {prefix}roughness ({u:g}, {v:g}) imported as their mean",
        )
    roughness = (u + v) / 2.0
    # pbrt-v4 remaps a roughness to the Trowbridge-Reitz (GGX) alpha as sqrt(roughness) unless told not to.
    alpha = math.sqrt(roughness) if context.boolean(material, "remaproughness", True) else roughness
    return min(alpha, 1.0)


def roughness_texture(context: Context, material: Entity, parameter) -> float | dict:
    """A float texture as the roughness: a `constant` one is its number; an `imagemap` becomes a one-channel
    float TIFF of α beside the TOML: pbrt's float lookup averages an image's channels, and its remapping
    (`remaproughness`, default true: α = √roughness) is applied to each texel, as pbrt applies it to the value
    it looks up (exact for nearest lookups; a filtered lookup differs by √ of a blend against a blend of √)."""
    from spectrace.io.images import read_texture_image
    from spectrace.textures.bitmap import decoded

    key = ("float", str(parameter.values[0]))
    if key not in context.scene.textures:
        raise error(parameter.location, f"\"{parameter.label()}\" names '{shown(key[1])}', which no Texture defined")
    texture = context.scene.textures[key].entity
    table = texture_table(context, texture)
    remap = context.boolean(material, "remaproughness", True)
    if "texture" not in table:
        value = max(float(table.get("value", 0.0)) * float(table.get("scale", 1.0)), 0.0)
        return min(math.sqrt(value) if remap else value, 1.0)
    if table["texture"] != "bitmap":
        raise error(parameter.location, f'"{parameter.label()}": spectrace takes an imagemap or a constant here')
    source = (context.toml_folder / table["file"]).resolve()
    written = str(table["file"]).removeprefix(f"{context.mesh_folder}/")
    if written in context.files:  # a scaled image this import made (a `scale` texture): not on disk yet
        linear = np.asarray(context.files[written], np.float64)
    else:
        values, encoded = read_texture_image(source, str(texture.location))
        linear = decoded(values, encoded, bool(table.get("raw", False)))
    roughness = np.clip(linear.mean(axis=-1), 0.0, None)
    alpha = np.minimum(np.sqrt(roughness) if remap else roughness, 1.0)
    file = unique_name(f"{source.stem}_alpha", {Path(n).stem for n in context.files}) + ".tif"
    context.files[file] = alpha.astype(np.float32)
    return table | {"file": f"{context.mesh_folder}/{file}", "raw": True}


def ior(context: Context, material: Entity) -> float | str:
    parameter = material.find("eta", "float", "spectrum", "rgb")
    if parameter is None:
        return 1.5
    if parameter.type == "float":
        return float(parameter.values[0])
    if parameter.type == "spectrum" and isinstance(parameter.values[0], str) and parameter.values[0] in GLASSES:
        return GLASSES[parameter.values[0]]
    raise error(
        parameter.location,
        f'"{parameter.label()}": spectrace takes a number or a named glass ({", ".join(GLASSES)}) as eta',
    )
