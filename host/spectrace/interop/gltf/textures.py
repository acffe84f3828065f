"""glTF textures (glTF 2.0, 3.8-3.9) as spectrace `bitmap` textures: each image decoded once and the channels a
material reads written as PNG files beside the TOML (spectrace's bitmaps have no channel selection, and glTF packs
metallic into B and roughness into G of one image, alpha into A of the base colour's), with the material's constant
factor multiplied in where glTF multiplies it (linearly: the sRGB base and emissive colours are decoded, scaled
and encoded again). The sampler's wrap and filter and KHR_texture_transform's offset and scale map onto the
bitmap's `wrap`, `filter`, `uv_offset` and `uv_scale` (glTF's (u, v), v down the image, is spectrace's)."""

from __future__ import annotations

import io
from collections.abc import Callable

import numpy as np

from spectrace.interop.gltf.context import GltfImport

WRAPS = {10497: "repeat", 33071: "clamp", 33648: "mirror"}
NEAREST = 9728
# A texture's role -> (channels taken, sRGB-encoded colour or raw data)
ROLES = {
    "base": ((0, 1, 2), True),
    "emissive": ((0, 1, 2), True),
    "normal": ((0, 1, 2), False),
    "alpha": ((3,), False),
    "roughness": ((1,), False),  # glTF 2.0, 3.9.2: roughness in G, metalness in B
    "metallic": ((2,), False),
    "red": ((0,), False),  # KHR_materials_transmission, _clearcoat: their factor in R
    "gloss": ((1,), False),  # KHR_materials_clearcoat's roughness texture: G, written as 1 − roughness
    "blue": ((2,), False),  # KHR_materials_anisotropy's strength: B
    "rgb": ((0, 1, 2), False),  # code values for a curve of all three (which decodes an sRGB colour itself)
}


def srgb_decode(code: np.ndarray) -> np.ndarray:
    c = code / 255.0
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def srgb_encode(linear: np.ndarray) -> np.ndarray:
    c = np.clip(linear, 0.0, 1.0)
    encoded = np.where(c <= 0.0031308, 12.92 * c, 1.055 * np.power(c, 1 / 2.4) - 0.055)
    return np.round(encoded * 255.0)


def decoded_image(ctx: GltfImport, index: int, pointer: str) -> np.ndarray:
    """images[index] as (h, w, 4) 8-bit code values (a grey image repeated into RGB, a missing alpha 255)."""
    if index in ctx.decoded:
        return ctx.decoded[index]
    from PIL import Image, UnidentifiedImageError

    data, name = ctx.doc.image_bytes(index, pointer)
    try:
        with Image.open(io.BytesIO(data)) as image:
            if image.mode in ("I;16", "I;16B", "I"):  # 16-bit: kept to 8 bits, the PNGs' depth
                pixels = np.asarray(image, dtype=np.float64) / 257.0
                rgba = np.repeat(np.round(pixels)[..., None], 4, axis=2)
                rgba[..., 3] = 255
            else:
                rgba = np.asarray(image.convert("RGBA"), dtype=np.float64)
    except (UnidentifiedImageError, OSError, ValueError, Image.DecompressionBombError) as error:
        raise ctx.doc.fail(f"/images/{index}", f"cannot decode {name} ({error})") from None
    ctx.decoded[index] = rgba
    return rgba


def texture(
    ctx: GltfImport,
    info: object,
    pointer: str,
    role: str,
    factor: list[float] | float = 1.0,
    cutoff: float | None = None,
    curve: tuple[str, Callable[[np.ndarray], np.ndarray]] | None = None,
) -> dict | None:
    """The `bitmap` for a textureInfo (`{ index, texCoord, extensions }`) read in `role`, its values times
    `factor` (and with `cutoff`, 1 where that is at least the cutoff, else 0: an alpha mask; with `curve`, a name
    and a map of [0, 1] onto [0, 1], that map of each value: a parameter glTF defines another way); None (with a
    warning) for one spectrace cannot read."""
    doc = ctx.doc
    if not isinstance(info, dict):
        raise doc.fail(pointer, "a texture reference must be an object with an 'index'")
    index = doc.index(info, "index", pointer)
    if index is None:
        raise doc.fail(f"{pointer}/index", "is required")
    entry = doc.item("textures", index, f"{pointer}/index")
    where = f"/textures/{index}"
    source = doc.index(entry, "source", where)
    if source is None:
        names = ", ".join(doc.obj(entry, "extensions", where)) or "none"
        ctx.warn(where, f"a texture without a PNG or JPEG source (its extensions: {names}) is not imported")
        return None
    transform = doc.extension(info, "KHR_texture_transform", pointer) or {}
    tex_coord = doc.index(info, "texCoord", pointer) or 0
    if "texCoord" in transform:
        tex_coord = doc.index(transform, "texCoord", f"{pointer}/extensions/KHR_texture_transform") or 0
    if tex_coord != 0:
        ctx.warn(f"{pointer}/texCoord", "textures on a second set of texture coordinates are not imported")
        return None
    factors = np.broadcast_to(np.asarray(factor, dtype=np.float64), (len(ROLES[role][0]),))
    key = (source, role, tuple(factors), cutoff, curve[0] if curve else None)
    if key not in ctx.images:
        channels, colour = ROLES[role]
        pixels = decoded_image(ctx, source, f"{where}/source")[..., list(channels)]
        if colour and not np.all(factors == 1.0):
            pixels = srgb_encode(srgb_decode(pixels) * factors)
        elif not np.all(factors == 1.0):
            pixels = np.round(np.clip(pixels * factors, 0.0, 255.0))
        if role == "gloss":
            pixels = 255.0 - pixels
        if cutoff is not None:
            pixels = (pixels >= cutoff * 255.0) * 255.0
        if curve is not None:  # a curve of several channels may return one
            pixels = np.round(np.clip(curve[1](pixels / 255.0), 0.0, 1.0) * 255.0)
        base = f"image{source}_{curve[0] if curve else role if cutoff is None else 'mask'}"
        ctx.images[key] = ctx.add_png(base, pixels[..., 0] if pixels.shape[2] == 1 else pixels)
    table: dict = {"texture": "bitmap", "file": ctx.images[key]}
    if not ROLES[role][1]:
        table["raw"] = True
    if cutoff is not None:
        table["filter"] = "nearest"
    sampler_index = doc.index(entry, "sampler", where)
    if sampler_index is not None:
        sampler = doc.item("samplers", sampler_index, f"{where}/sampler")
        s_pointer = f"/samplers/{sampler_index}"
        wrap, wrap_t = (doc.choice(sampler, key, s_pointer, WRAPS, 10497) for key in ("wrapS", "wrapT"))
        if wrap != wrap_t:
            ctx.warn(s_pointer, "different wraps along u and v are imported as wrapS's")
        if wrap != "repeat":
            table["wrap"] = wrap
        if sampler.get("magFilter") == NEAREST:
            table["filter"] = "nearest"
    if transform:
        t_pointer = f"{pointer}/extensions/KHR_texture_transform"
        offset = doc.numbers(transform, "offset", t_pointer, 2, [0.0, 0.0])
        scale = doc.numbers(transform, "scale", t_pointer, 2, [1.0, 1.0])
        if doc.number(transform, "rotation", t_pointer, 0.0) != 0.0:
            ctx.warn(f"{t_pointer}/rotation", "KHR_texture_transform rotations are not imported (offset and scale are)")
        if scale != [1.0, 1.0]:
            table["uv_scale"] = scale
        if offset != [0.0, 0.0]:
            table["uv_offset"] = offset
    return table
