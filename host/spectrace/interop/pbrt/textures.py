"""pbrt-v4's textures as spectrace's: those the texture modules name in PBRT_TEXTURES (imagemap, checkerboard,
dots, mix, the solid ones: their `from_pbrt`, handed pbrt's (u, v) mapping), `constant` as a spectrum, and `scale`
of a spectrum or an image (the scaled image written beside the TOML as OpenEXR), which are no texture of
spectrace's."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from spectrace.interop.pbrt.context import Context, unique_name
from spectrace.interop.pbrt.graphics_state import Entity
from spectrace.interop.pbrt.parser import error, shown
from spectrace.textures import TEXTURES as TEXTURE_MODULES
from spectrace.textures.mapping import MAPPINGS

# pbrt-v4 texture type -> the texture module that maps it (spectrace.textures, each module's PBRT_TEXTURES).
_MODULES: dict[str, Any] = {kind: module for module in TEXTURE_MODULES.values() for kind in module.PBRT_TEXTURES}
TEXTURES = (*_MODULES, "constant")


def texture_reference(context: Context, entity: Entity, name: str) -> dict | None:
    """A `"texture name" "tex"` parameter as {"texture": key} (spectrum textures), or None."""
    parameter = entity.find(name, "texture")
    if parameter is None:
        return None
    key = ("spectrum", str(parameter.values[0]))
    if key not in context.scene.textures:
        if ("float", key[1]) in context.scene.textures:
            context.warn(
                parameter.location,
                f'"{parameter.label()}": a float texture where spectrace takes a spectrum; not imported',
            )
            return None
        raise error(parameter.location, f"\"{parameter.label()}\" names '{shown(key[1])}', which no Texture defined")
    if key not in context.texture_of:
        texture = context.scene.textures[key].entity
        table = texture_table(context, texture)
        if "texture" not in table:
            return table
        context.texture_of[key] = unique_name(texture.name, context.textures)
        context.textures[context.texture_of[key]] = {"type": table.pop("texture"), **table}
    return {"texture": context.texture_of[key]}


def texture_table(context: Context, texture: Entity) -> dict:
    context.read.add(id(texture))
    kind = texture.kind
    if kind == "scale":
        return scaled_texture(context, texture)
    if kind == "constant":
        return context.spectrum(texture, "value", "albedo") or {"value": 1.0}
    if kind not in TEXTURES:
        raise error(texture.location, f"texture '{shown(kind)}': spectrace imports {', '.join(TEXTURES)}")
    if not any(parameter.name == "mapping" for parameter in _MODULES[kind].PARAMETERS):
        return _MODULES[kind].from_pbrt(context, texture, (1.0, 1.0, 0.0, 0.0))  # pbrt reads no mapping of theirs
    mapping = context.string(texture, "mapping", "uv")
    if mapping not in MAPPINGS:
        raise error(
            texture.location,
            f"{texture.label()}: mapping '{shown(str(mapping))}' (spectrace takes {', '.join(MAPPINGS)})",
        )
    if mapping == "uv":
        us, vs = context.one(texture, "uscale", 1.0), context.one(texture, "vscale", 1.0)
        ud, vd = context.one(texture, "udelta", 0.0), context.one(texture, "vdelta", 0.0)
        return _MODULES[kind].from_pbrt(context, texture, (us, vs, ud, vd))
    # The mapping's (s, t) stand where a mesh's (u, v) would, so each module's uv handling applies with pbrt's
    # planar offsets as its udelta and vdelta (pbrt's other mappings read none).
    ud, vd = (context.one(texture, key, 0.0) for key in ("udelta", "vdelta")) if mapping == "planar" else (0.0, 0.0)
    table = _MODULES[kind].from_pbrt(context, texture, (1.0, 1.0, ud, vd))
    if "texture" not in table:  # a constant stand-in (an absent image)
        return table
    table["mapping"] = mapping
    if mapping == "planar":
        table["v1"] = [float(v) for v in context.vector(texture, "v1", [1.0, 0.0, 0.0])]
        table["v2"] = [float(v) for v in context.vector(texture, "v2", [0.0, 1.0, 0.0])]
    declared = next(t for t in context.scene.textures.values() if t.entity is texture)
    matrix = np.asarray(declared.world_from_texture, np.float64)
    if not np.allclose(matrix, np.eye(4)):
        table["transform"] = [{"matrix": matrix.tolist()}]
    return table


def scaled_texture(context: Context, texture: Entity) -> dict:
    """pbrt's `scale` texture: `tex` times a number. A scaled spectrum stays a spectrum; a scaled image becomes a
    linear OpenEXR copy of it, multiplied, beside the TOML (pbrt scales the uplifted spectrum, spectrace uplifts
    the scaled colour: the same colour under D65, docs/pbrt.md)."""
    value_type = next(t.value_type for t in context.scene.textures.values() if t.entity is texture)
    factor = context.one(texture, "scale", 1.0)
    if (factor_texture := texture.find("scale", "texture")) is not None:
        # A constant float texture as the factor is its number (pbrt-v4's scenes write scales so).
        key = ("float", str(factor_texture.values[0]))
        constant = context.scene.textures.get(key)
        if constant is None or constant.entity.kind != "constant":
            raise error(
                factor_texture.location,
                f'{texture.label()}: a texture as "scale" other than a constant one (spectrace takes a number)',
            )
        context.read.add(id(constant.entity))
        factor = context.one(constant.entity, "value", 1.0)
    if factor < 0:
        raise error(texture.location, f"{texture.label()}: a negative scale")
    inner = context.spectrum(texture, "tex", "albedo")
    if inner is None:
        reference = texture.find("tex", "texture")
        if reference is None:
            inner = {"value": 1.0}
        else:
            key = (value_type, str(reference.values[0]))
            if key not in context.scene.textures:
                raise error(reference.location, f"\"texture tex\" names '{shown(key[1])}', which no Texture defined")
            inner = texture_table(context, context.scene.textures[key].entity)
    if inner.get("texture") == "bitmap":
        return inner | {"file": scaled_image(context, inner, factor, texture), "raw": True}
    if "texture" in inner:
        raise error(texture.location, f"{texture.label()}: spectrace scales spectra and image textures only")
    return inner | {"scale": inner.get("scale", 1.0) * factor}


def scaled_image(context: Context, table: dict, factor: float, texture: Entity) -> str:
    from spectrace.io.images import read_texture_image
    from spectrace.textures.bitmap import decoded

    source = (context.toml_folder / table["file"]).resolve()
    values, encoded = read_texture_image(source, str(texture.location))
    linear = decoded(values, encoded, bool(table.get("raw", False))) * factor
    if linear.shape[-1] == 1:
        linear = np.repeat(linear, 3, axis=-1)
    if linear.max(initial=0.0) > 1.0:
        context.warn(texture.location, f"{texture.label()}: texels above 1 after scaling clamped to 1 (a reflectance)")
        linear = np.minimum(linear, 1.0)
    file = unique_name(f"{source.stem}_x{factor:g}", {Path(n).stem for n in context.files}) + ".exr"
    context.files[file] = linear.astype(np.float32)
    return f"{context.mesh_folder}/{file}"
