"""Blender's world as spectrace's environment light: the Background node's colour times its strength as a
`constant` radiance (Cycles' units: radiance 1 renders as RGB 1), or an Environment Texture's image (an OpenEXR or
Radiance HDR file, copied beside the TOML) as an `envmap` scaled by the strength. Blender's equirectangular map is
z-up with its centre toward +x."""

from __future__ import annotations

import shutil
from functools import partial
from pathlib import Path

from spectrace.interop.blender.context import BlendImport


def environment(ctx: BlendImport, world) -> dict | None:
    if world is None:
        return None
    where = f"world '{world.name}'"
    if not world.use_nodes or world.node_tree is None:
        colour = [float(v) for v in world.color]
        return {"type": "constant", "radiance": {"rgb": colour}} if max(colour) > 0.0 else None
    tree = world.node_tree
    outputs = [n for n in tree.nodes if n.type == "OUTPUT_WORLD" and n.is_active_output] or [
        n for n in tree.nodes if n.type == "OUTPUT_WORLD"
    ]
    if not outputs or not outputs[0].inputs["Surface"].is_linked:
        return None
    node = outputs[0].inputs["Surface"].links[0].from_node
    if node.type != "BACKGROUND":
        ctx.warn(where, f"world shader node {node.bl_idname} is not imported (no environment light)")
        return None
    strength_socket = node.inputs["Strength"]
    if strength_socket.is_linked:
        ctx.warn(where, "a world strength driven by nodes is imported as its own value")
    strength = float(strength_socket.default_value)
    colour_socket = node.inputs["Color"]
    if strength <= 0.0:
        return None
    if not colour_socket.is_linked:
        colour = [float(v) for v in colour_socket.default_value[:3]]
        if max(colour) <= 0.0:
            return None
        return {"type": "constant", "radiance": {"rgb": colour, "scale": strength}}
    source = colour_socket.links[0].from_node
    image = getattr(source, "image", None) if source.type == "TEX_ENVIRONMENT" else None
    if image is None:
        ctx.warn(where, f"world colour from node {source.bl_idname} is not imported (no environment light)")
        return None
    path = Path(image.filepath_from_user()) if image.filepath else None
    if path is None or path.suffix.lower() not in (".exr", ".hdr", ".rgbe") or not path.is_file():
        ctx.warn(where, f"environment image '{image.name}' is not an OpenEXR or HDR file on disk: not imported")
        return None
    name = ctx.file_name(path.stem, path.suffix.lower())
    ctx.files[name] = partial(shutil.copyfile, path)
    if source.inputs["Vector"].is_linked:
        ctx.warn(where, "an environment texture's mapping is not imported")
    return {"type": "envmap", "file": name, "scale": strength, "up": [0.0, 0.0, 1.0], "front": [1.0, 0.0, 0.0]}
