"""Blender materials (their Cycles node trees) as spectrace materials and area emitters, through the node linked
to the active Material Output's Surface:

- Principled BSDF (v2) -> `principled`, as docs/materials.md's table maps it (Roughness is perceptual in both;
  IOR with Specular IOR Level -> eta, or a level texture -> specular; Transmission Weight -> spec_trans;
  Coat -> clearcoat; Sheen -> sheen; Alpha -> opacity);
- Diffuse BSDF -> `diffuse`; Glossy BSDF -> a `conductor` that reflects everything (η = 0, k = 1) tinted by its
  colour; Glass BSDF -> `dielectric` (Cycles squares Roughness into the microfacet α, as spectrace's α is);
  Translucent BSDF -> `principledthin` with `diff_trans` 2 (Lambertian transmission alone);
- Emission, and a Principled BSDF's emission -> an area emitter on the shapes using the material, radiance
  colour × strength in Cycles' units (radiance 1 renders as RGB 1), on both faces as Cycles emits.

An Image Texture linked (directly) to a colour, roughness, metallic or alpha input, or through a Normal Map node
to Normal, becomes a `bitmap` (its pixels written as a PNG; sRGB-encoded unless the image's colour space is
Non-Color). Any other node in the way is named once in a warning and its input's own value is used."""

from __future__ import annotations

import math

import numpy as np

from spectrace.interop.blender.context import BlendImport
from spectrace.interop.mitsuba.context import unique_name

DEFAULT: dict = {"type": "diffuse", "reflectance": {"rgb": [0.8, 0.8, 0.8]}}
# The shader nodes imported; each takes a normal map on its Normal input.
_READ_SHADERS = ("BSDF_PRINCIPLED", "BSDF_DIFFUSE", "BSDF_GLOSSY", "BSDF_GLASS", "BSDF_TRANSLUCENT")


def material_name(ctx: BlendImport, material) -> str:
    """The TOML name of a Blender material (None: Blender's default grey), converted on first use."""
    key = material.name if material is not None else ""
    if key not in ctx.material_names:
        name = unique_name(key or "default", ctx.materials)
        if material is None:
            table, emitter = dict(DEFAULT), None
        else:
            table, emitter = convert(ctx, material)
        ctx.materials[name] = table
        ctx.emitters[name] = emitter
        ctx.material_names[key] = name
    return ctx.material_names[key]


def _surface_node(material):
    tree = material.node_tree
    outputs = [n for n in tree.nodes if n.type == "OUTPUT_MATERIAL" and n.is_active_output] or [
        n for n in tree.nodes if n.type == "OUTPUT_MATERIAL"
    ]
    if not outputs or not outputs[0].inputs["Surface"].is_linked:
        return None
    return outputs[0].inputs["Surface"].links[0].from_node


def convert(ctx: BlendImport, material) -> tuple[dict, dict | None]:
    where = f"material '{material.name}'"
    if not material.use_nodes or material.node_tree is None:
        return {"type": "diffuse", "reflectance": {"rgb": [float(v) for v in material.diffuse_color[:3]]}}, None
    node = _surface_node(material)
    if node is None:
        return {"type": "diffuse", "reflectance": {"value": 0.0}}, None
    if material.node_tree.nodes and any(
        n.type == "OUTPUT_MATERIAL" and n.inputs["Volume"].is_linked for n in material.node_tree.nodes
    ):
        ctx.warn(where, "volume shaders are not imported")
    table, emitter = _shader(ctx, node, where)
    if node.type in _READ_SHADERS and "Normal" in node.inputs and node.inputs["Normal"].is_linked:
        _normal_map(ctx, node.inputs["Normal"].links[0].from_node, table, where)
    return table, emitter


def _normal_map(ctx: BlendImport, source, table: dict, where: str) -> None:
    """A shader's Normal input from a tangent-space Normal Map node of an Image Texture: the material's
    `normal_map`, framed by the mesh's tangents and bitangent signs (MikkTSpace's, which the mesh export hands
    where a material has a normal map) or, without them, by its texture coordinates with their handedness."""
    image_socket = source.inputs["Color"] if source.type == "NORMAL_MAP" else None
    if image_socket is None or not image_socket.is_linked or image_socket.links[0].from_node.type != "TEX_IMAGE":
        ctx.warn(where, f"a normal from node {source.bl_idname} is not imported")
        return
    if source.space != "TANGENT":
        ctx.warn(where, f"a Normal Map in {source.space.lower()} space is not imported (tangent space is)")
        return
    if abs(_number(ctx, source, "Strength", where) - 1.0) > 1e-6:
        ctx.warn(where, "a Normal Map's strength other than 1 is not imported")
    table["normal_map"] = _image(ctx, image_socket.links[0].from_node, "normal", where)
    table["normal_map_handedness"] = True  # Blender's tangent space is MikkTSpace's, signed per face


def _shader(ctx: BlendImport, node, where: str) -> tuple[dict, dict | None]:
    kind = node.type
    if kind == "BSDF_PRINCIPLED":
        return _principled(ctx, node, where)
    if kind == "BSDF_DIFFUSE":
        if _number(ctx, node, "Roughness", where) > 0.0:
            ctx.warn(where, "a Diffuse BSDF's roughness (Oren-Nayar) is not imported (Lambertian)")
        return {"type": "diffuse", "reflectance": _colour(ctx, node, "Color", where)}, None
    if kind == "BSDF_GLOSSY":
        roughness = _number(ctx, node, "Roughness", where)
        return {
            "type": "conductor",
            "eta": {"value": 0.0},
            "k": {"value": 1.0},
            "specular_tint": _colour(ctx, node, "Color", where),
            "roughness": roughness * roughness,
        }, None
    if kind == "BSDF_GLASS":
        roughness = _number(ctx, node, "Roughness", where)
        table: dict = {"type": "dielectric", "ior": _ior(ctx, _number(ctx, node, "IOR", where), where)}
        if roughness > 0.0:
            table["roughness"] = roughness * roughness
        tint = _colour(ctx, node, "Color", where)
        if tint != {"rgb": [1.0, 1.0, 1.0]}:
            table["specular_tint"] = tint
        return table, None
    if kind == "BSDF_TRANSLUCENT":
        # Lambertian transmission alone, color/π to the other side: the thin principled sheet whose diffuse part
        # all transmits (diff_trans 2) and that has no specular part.
        return {"type": "principledthin", "base_color": _colour(ctx, node, "Color", where), "diff_trans": 2.0}, None
    if kind == "EMISSION":
        emitter = _emitter(ctx, node, "Color", "Strength", where)
        return {"type": "diffuse", "reflectance": {"value": 0.0}}, emitter
    ctx.warn(where, f"shader node {node.bl_idname} is not imported (a grey diffuse material stands for it)")
    return dict(DEFAULT), None


def _ior(ctx: BlendImport, value: float, where: str) -> float:
    if not 1.0 < value <= 4.0:
        ctx.warn(where, f"IOR {value:g} outside (1, 4] is clamped into it")
        return min(4.0, max(1.0001, value))
    return value


def _principled(ctx: BlendImport, node, where: str) -> tuple[dict, dict | None]:
    table: dict = {"type": "principled", "base_color": _colour(ctx, node, "Base Color", where)}
    table["metallic"] = _grey(ctx, node, "Metallic", where)
    table["roughness"] = _grey(ctx, node, "Roughness", where)
    for socket, key in (("Transmission Weight", "spec_trans"), ("Anisotropic", "anisotropic")):
        value = _grey(ctx, node, socket, where)
        if value != 0.0:
            table[key] = value
    table |= _specular_level(ctx, node, table.get("spec_trans", 0.0), where)
    if "anisotropic" in table:
        # Cycles turns the tangent about the normal by Anisotropic Rotation × 2π (counter-clockwise)
        turns = _number(ctx, node, "Anisotropic Rotation", where)
        if math.fmod(turns, 1.0) != 0.0:
            table["anisotropic_rotation"] = 360.0 * math.fmod(turns, 1.0)
        if node.inputs["Tangent"].is_linked:
            ctx.warn(where, "a Principled BSDF's Tangent input is not imported (anisotropy follows the UV map's u)")
    coat = _grey(ctx, node, "Coat Weight", where)
    if coat != 0.0:
        table["clearcoat"] = coat
        table["clearcoat_gloss"] = 1.0 - _number(ctx, node, "Coat Roughness", where)
    sheen = _grey(ctx, node, "Sheen Weight", where)
    if sheen != 0.0:
        table["sheen"] = sheen
        ctx.warn(where, "Blender's microfiber sheen is approximated by the principled (Burley) sheen")
    for socket in ("Subsurface Weight", "Thin Film Thickness"):
        if socket in node.inputs and _number(ctx, node, socket, where) > 0.0:
            ctx.warn(where, f"the Principled BSDF's {socket} is not imported")
    alpha = _grey(ctx, node, "Alpha", where)
    if alpha != 1.0:
        table["opacity"] = alpha
    emitter = _emitter(ctx, node, "Emission Color", "Emission Strength", where)
    if emitter is not None and "opacity" in table:
        ctx.warn(where, "an emissive material's alpha is not imported (emitters are opaque)")
        del table["opacity"]
    return table, emitter


def _f0(eta: float) -> float:
    return ((eta - 1.0) / (eta + 1.0)) ** 2


def _specular_level(ctx: BlendImport, node, transmission, where: str) -> dict:
    """IOR and Specular IOR Level as the principled material's index: Cycles scales the dielectric layer's F0 by
    2 × level (0.5 keeps the IOR's own F0, 0 takes the reflection away) and turns it back into the index of that
    layer, η' = (1 + √F0')/(1 − √F0'); its glass (transmission) part keeps the IOR. spectrace's principled has one
    index for both, so η' is taken where nothing transmits and the IOR where everything does. A texture becomes
    the `specular` level s = F0'/0.08 texel by texel (F0' = 2 F0(IOR) × level), which the kernel turns into η'."""
    ior = _ior(ctx, _number(ctx, node, "IOR", where), where)
    socket = node.inputs["Specular IOR Level"]
    image = _linked_image(ctx, socket, where)
    if transmission == 1.0 or (image is None and abs(float(socket.default_value) - 0.5) <= 1e-6):
        return {"eta": ior}
    if transmission != 0.0:
        ctx.warn(where, "a Specular IOR Level other than 0.5 also sets the index of the transmission here")
    factor = 2.0 * _f0(ior) / 0.08  # s per unit of the level
    if image is not None:
        return {"specular": _image(ctx, image, "level", where, scale=factor)}
    f0 = 2.0 * _f0(ior) * max(float(socket.default_value), 0.0)
    if f0 > 0.36:  # η' = 4, the index's upper limit
        ctx.warn(where, f"a Specular IOR Level of {socket.default_value:g} gives an index above 4: clamped to 4")
    root = math.sqrt(min(f0, 0.36))
    return {"eta": max(1.0001, (1.0 + root) / (1.0 - root))}


def normal_mapped(ctx: BlendImport, obj, where: str) -> bool:
    """Whether a material of the object shades it through a Normal Map node in tangent space (the import then
    hands the mesh's MikkTSpace tangents). A Normal Map naming a UV map other than the active one is warned of:
    the export reads the active map, for the textures and the tangents alike."""
    found = False
    for slot in obj.material_slots:
        material = slot.material
        if material is None or not material.use_nodes or material.node_tree is None:
            continue
        for node in material.node_tree.nodes:
            if node.type == "NORMAL_MAP" and node.space == "TANGENT" and node.outputs["Normal"].is_linked:
                found = True
                layers = getattr(obj.data, "uv_layers", None)
                active = layers.active.name if layers is not None and layers.active is not None else ""
                if node.uv_map and node.uv_map != active:
                    ctx.warn(where, f"a Normal Map's UV map '{node.uv_map}' is not imported (the active one is)")
    return found


def _emitter(ctx: BlendImport, node, colour_socket: str, strength_socket: str, where: str) -> dict | None:
    strength = _number(ctx, node, strength_socket, where)
    radiance = _colour(ctx, node, colour_socket, where)
    if strength <= 0.0 or radiance == {"rgb": [0.0, 0.0, 0.0]}:
        return None
    return {"radiance": radiance, "scale": strength, "two_sided": True}


def _linked_image(ctx: BlendImport, socket, where: str):
    """The Image Texture node feeding `socket` directly, or None (a warning for any other node)."""
    if not socket.is_linked:
        return None
    source = socket.links[0].from_node
    if source.type == "TEX_IMAGE" and source.image is not None:
        if source.inputs["Vector"].is_linked:
            ctx.warn(where, "texture coordinate nodes are not imported (the active UV map is used)")
        return source
    ctx.warn(where, f"node {source.bl_idname} is not imported (the input's own value is used)")
    return None


def _number(ctx: BlendImport, node, name: str, where: str) -> float:
    socket = node.inputs[name]
    if socket.is_linked:
        ctx.warn(where, f"a node linked to {name} is not imported (its own value is used)")
    return float(socket.default_value)


def _grey(ctx: BlendImport, node, name: str, where: str) -> float | dict:
    socket = node.inputs[name]
    image = _linked_image(ctx, socket, where)
    if image is not None:
        return _image(ctx, image, "grey", where)
    return float(socket.default_value)


def _colour(ctx: BlendImport, node, name: str, where: str) -> dict:
    socket = node.inputs[name]
    image = _linked_image(ctx, socket, where)
    if image is not None:
        return _image(ctx, image, "colour", where)
    return {"rgb": [float(v) for v in socket.default_value[:3]]}


def _image(ctx: BlendImport, node, role: str, where: str, scale: float = 1.0) -> dict:
    """A bitmap of an Image Texture node's image: its pixels as Blender holds them (rows bottom-up, as UV v runs
    up), encoded as 8-bit PNG. A colour image keeps its sRGB encoding; data (Non-Color) images are read raw;
    a grey role takes the image's luminance, as Blender converts a colour to a number; the "level" role writes
    that luminance times `scale`, raw (values above 1 are clamped, with a warning)."""
    image = node.image
    raw = image.colorspace_settings.name in ("Non-Color", "Raw", "Linear", "Linear Rec.709")
    key = (image.name, role, scale)
    if key not in ctx.images:
        width, height = image.size
        if width == 0 or height == 0:
            ctx.warn(where, f"image '{image.name}' has no pixels: not imported")
            return {"value": 0.5} if role in ("grey", "level") else {"rgb": [0.5, 0.5, 0.5]}
        pixels = np.empty(width * height * 4, dtype=np.float32)
        image.pixels.foreach_get(pixels)
        rgb = pixels.reshape(height, width, 4)[::-1, :, :3]
        if role == "level":
            ctx.images[key] = ctx.add_png(f"{image.name}_{role}", _scaled_luminance(ctx, image, rgb, raw, scale))
        else:
            if image.is_float and not raw:  # float buffers hold linear values: encode them as sRGB
                rgb = np.where(
                    rgb <= 0.0031308, 12.92 * rgb, 1.055 * np.power(np.clip(rgb, 0.0, None), 1 / 2.4) - 0.055
                )
            ctx.images[key] = ctx.add_png(f"{image.name}_{role}", np.round(np.clip(rgb, 0.0, 1.0) * 255.0))
    table: dict = {"texture": "bitmap", "file": ctx.images[key]}
    if raw or role in ("normal", "level"):
        table["raw"] = True
    if role == "grey":
        table["luminance"] = True
    if node.interpolation == "Closest":
        table["filter"] = "nearest"
    if node.extension in ("EXTEND", "CLIP"):
        table["wrap"] = "clamp"
    elif node.extension == "MIRROR":
        table["wrap"] = "mirror"
    return table


def _scaled_luminance(ctx: BlendImport, image, rgb: np.ndarray, raw: bool, scale: float) -> np.ndarray:
    """8-bit code values of `scale` × the luminance of an image's linear values (a byte image's code values
    decoded from sRGB unless it is data), as Blender turns a colour into a number (Rec. 709's Y)."""
    linear = rgb
    if not raw and not image.is_float:
        linear = np.where(rgb <= 0.04045, rgb / 12.92, np.power((np.clip(rgb, 0.0, None) + 0.055) / 1.055, 2.4))
    value = scale * (linear @ np.array([0.2126, 0.7152, 0.0722], dtype=np.float32))
    if value.max() > 1.0 + 0.5 / 255.0:
        ctx.warn(f"image '{image.name}'", "a textured Specular IOR Level above 0.04/F0(IOR) is clamped there")
    return np.round(np.clip(value, 0.0, 1.0) * 255.0)
