"""KHR_lights_punctual in the units it defines: point and spot lights' `intensity` in candela (lm/sr), directional
lights' in lux (lm/m²), times the linear RGB `color`. Each becomes the D65-shaped spectrum `{ rgb = color }`
(luminance factor Y(color)) scaled by intensity / (683 lm/W · ∫ȳ dλ): its photometric value is then
intensity · Y(color) candela or lux, exactly the intensity for a white light. Lights shine along their node's −z.
A spot's cone: full intensity within innerConeAngle, falling to zero at outerConeAngle (spectrace's smooth falloff
between the two, where glTF suggests a squared linear ramp in cos θ). `range` (a cutoff glTF leaves optional) is not
imported: spectrace's lights fall off with the inverse square everywhere."""

from __future__ import annotations

import math

import numpy as np

from spectrace.interop.gltf.context import GltfImport, photometric_scale
from spectrace.interop.gltf.nodes import PlacedNode


def light(ctx: GltfImport, placed: PlacedNode) -> dict | None:
    doc = ctx.doc
    reference = (doc.extension(placed.node, "KHR_lights_punctual", placed.pointer) or {}).get("light")
    pointer = f"{placed.pointer}/extensions/KHR_lights_punctual/light"
    definitions = doc.extension(doc.json, "KHR_lights_punctual", "") or {}
    lights = definitions.get("lights", [])
    if not isinstance(lights, list):
        raise doc.fail("/extensions/KHR_lights_punctual/lights", "must be an array")
    if isinstance(reference, bool) or not isinstance(reference, int) or not 0 <= reference < len(lights):
        raise doc.fail(pointer, f"refers to light {reference}, which /extensions/KHR_lights_punctual/lights lacks")
    where = f"/extensions/KHR_lights_punctual/lights/{reference}"
    entry = lights[reference]
    if not isinstance(entry, dict):
        raise doc.fail(where, "must be an object")
    color = doc.numbers(entry, "color", where, 3, [1.0, 1.0, 1.0])
    if any(value < 0.0 for value in color):
        raise doc.fail(f"{where}/color", "must not be negative")
    intensity = doc.number(entry, "intensity", where, 1.0)
    if intensity < 0.0:
        raise doc.fail(f"{where}/intensity", "must not be negative")
    if "range" in entry:
        ctx.warn(f"{where}/range", "a light's range is not imported (spectrace's lights have no cutoff)")
    if intensity == 0.0 or max(color) == 0.0:
        return None
    spectrum = {"rgb": color, "scale": intensity / photometric_scale()}
    world = placed.world
    position = [float(v) for v in world[:3, 3]]
    axis = world[:3, :3] @ np.array([0.0, 0.0, -1.0])
    if not np.linalg.norm(axis) > 0.0:
        raise doc.fail(placed.pointer, "the light's node transform is degenerate (a zero scale)")
    axis = axis / np.linalg.norm(axis)
    kind = entry.get("type")
    if kind == "point":
        return {"type": "point", "position": position, "intensity": spectrum}
    if kind == "directional":
        return {"type": "distant", "direction": [float(v) for v in axis], "irradiance": spectrum}
    if kind == "spot":
        cone = doc.obj(entry, "spot", where)
        inner = doc.number(cone, "innerConeAngle", f"{where}/spot", 0.0)
        outer = doc.number(cone, "outerConeAngle", f"{where}/spot", math.pi / 4.0)
        if not 0.0 <= inner < outer <= math.pi / 2.0:
            raise doc.fail(f"{where}/spot", "needs 0 <= innerConeAngle < outerConeAngle <= π/2")
        return {
            "type": "spot",
            "position": position,
            "target": [float(p + a) for p, a in zip(position, axis, strict=True)],
            "cutoff_angle": math.degrees(outer),
            "falloff_start": math.degrees(inner),
            "intensity": spectrum,
        }
    raise doc.fail(f"{where}/type", f"unknown light type {kind!r} (point, spot, directional)")
