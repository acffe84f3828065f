"""glTF materials (glTF 2.0, 3.9: metallic-roughness, normal map, alpha modes, double-sidedness, emission) as
spectrace materials and area emitters.

The metallic-roughness model maps onto the `principled` material (Mitsuba 3's parameter names: base_color,
metallic, roughness, eta, spec_trans): glTF's roughness is the perceptual one, which principled squares into the
microfacet α as glTF does. `material_model = "diffuse"` instead keeps only the base colour as a Lambertian
reflectance (a preview, and the fallback where spectrace has no principled material): metallic, roughness and the
extensions are then left out, named in a note. KHR_materials_unlit's colour, shown as it is by a rasteriser, becomes
such a diffuse reflectance (with a warning): under the uniform white environment a file without lights gets, an
unshadowed surface shows it.

Emission (emissiveFactor × emissiveTexture × KHR_materials_emissive_strength) is luminance in nits (cd/m²): the
radiance `{ rgb = ..., scale = 1 / (683 lm/W · ∫ȳ dλ) }` whose luminance is that many nits for a white emissive
colour, as an area emitter on the primitives that use the material."""

from __future__ import annotations

import math

from spectrace.interop.gltf import material_extensions
from spectrace.interop.gltf.context import GltfImport, photometric_scale
from spectrace.interop.gltf.textures import texture
from spectrace.interop.mitsuba.context import unique_name

# Extensions whose parameters are imported; the others a material uses are named in a warning.
IMPORTED_EXTENSIONS = (
    "KHR_materials_emissive_strength",
    "KHR_materials_ior",
    "KHR_materials_transmission",
    "KHR_materials_clearcoat",
    "KHR_materials_sheen",
    "KHR_materials_volume",
    "KHR_materials_unlit",
    "KHR_materials_diffuse_transmission",
    *material_extensions.EXTENSIONS,
)
UNLIT = "KHR_materials_unlit"

# The material glTF gives a primitive without one (glTF 2.0, 3.9.6: white, fully metallic, fully rough).
DEFAULT_MATERIAL: dict = {}


def material_name(ctx: GltfImport, index: int | None, user: str) -> str:
    """The TOML name of materials[index] (None: glTF's default material), converted on first use; `user` is the
    pointer of the primitive that uses it, where a problem with the default material is told."""
    if index not in ctx.material_names:
        doc = ctx.doc
        pointer = f"/materials/{index}" if index is not None else "/materials"
        entry = DEFAULT_MATERIAL if index is None else doc.item("materials", index, pointer)
        base = entry.get("name") if isinstance(entry.get("name"), str) else None
        name = unique_name(base or (f"material{index}" if index is not None else "default"), ctx.materials)
        table, emitter = convert(ctx, entry, pointer)
        ctx.materials[name] = table
        ctx.material_names[index] = name
        thin = table["type"] in ("diffuse", "principledthin")  # nothing inside
        ctx.interiors[index] = None if thin else _interior(ctx, entry, pointer, table)
        ctx.origins[f"materials.{name}"] = pointer if index is not None else user
        ctx.emitters[index] = emitter
    return ctx.material_names[index]


def convert(ctx: GltfImport, entry: dict, pointer: str) -> tuple[dict, dict | None]:
    doc = ctx.doc
    pbr = doc.obj(entry, "pbrMetallicRoughness", pointer)
    p_pointer = f"{pointer}/pbrMetallicRoughness"
    extensions = doc.obj(entry, "extensions", pointer)
    base_factor = doc.numbers(pbr, "baseColorFactor", p_pointer, 4, [1.0, 1.0, 1.0, 1.0])
    for i, value in enumerate(base_factor):
        if not 0.0 <= value <= 1.0:
            raise doc.fail(f"{p_pointer}/baseColorFactor/{i}", f"must lie in [0, 1], got {value:g}")
    base: dict | None = None
    if "baseColorTexture" in pbr:
        base = texture(ctx, pbr["baseColorTexture"], f"{p_pointer}/baseColorTexture", "base", base_factor[:3])
    unlit = UNLIT in extensions
    table: dict = {"type": "diffuse" if unlit else ctx.material_model}
    colour = base or {"rgb": base_factor[:3]}
    if unlit:
        # A path tracer has no surface that shows its colour whatever lights it; a Lambertian one of that colour
        # shows it where nothing shadows it under a uniform environment of radiance 1 (E = π, L = ρ E / π).
        table["reflectance"] = colour
        ctx.warn(
            f"{pointer}/extensions/{UNLIT}",
            "unlit materials are imported as diffuse surfaces of their base colour (lit by the scene's light)",
        )
    elif ctx.material_model == "diffuse":
        table["reflectance"] = colour
        ctx.note(
            "materials imported as their base colour, diffuse (--materials diffuse): metallic, roughness and the "
            "material extensions are left out"
        )
    else:
        table["base_color"] = colour
        metallic = _unit(doc, pbr, "metallicFactor", p_pointer)
        roughness = _unit(doc, pbr, "roughnessFactor", p_pointer)
        packed = pbr.get("metallicRoughnessTexture")
        where = f"{p_pointer}/metallicRoughnessTexture"
        metallic_map = texture(ctx, packed, where, "metallic", metallic) if packed is not None else None
        roughness_map = texture(ctx, packed, where, "roughness", roughness) if packed is not None else None
        table["metallic"] = metallic_map or metallic
        table["roughness"] = roughness_map or roughness
        _extensions(ctx, table, entry, pointer)
        material_extensions.apply(ctx, table, entry, pointer, roughness)
        _diffuse_transmission(ctx, table, entry, pointer)
    if "normalTexture" in entry:
        where = f"{pointer}/normalTexture"
        info = entry["normalTexture"]
        if isinstance(info, dict) and doc.number(info, "scale", where, 1.0) != 1.0:
            ctx.warn(f"{where}/scale", "a normal map's scale other than 1 is not imported")
        normal = texture(ctx, info, where, "normal")
        if normal is not None:
            table["normal_map"] = normal
            # glTF's bitangent is cross(normal, tangent) · w, w following the texture layout's handedness
            table["normal_map_handedness"] = True
    for key in ("occlusionTexture",):
        if key in entry:
            ctx.warn(
                f"{pointer}/{key}", "ambient occlusion maps are not imported (the renderer finds occlusion itself)"
            )
    _alpha(ctx, entry, pbr, table, base_factor[3], pointer)
    double_sided = entry.get("doubleSided", False)
    if not isinstance(double_sided, bool):
        raise doc.fail(f"{pointer}/doubleSided", "must be true or false")
    if not double_sided:
        table["two_sided"] = False
    for name in extensions:
        if name not in IMPORTED_EXTENSIONS:
            ctx.warn(f"{pointer}/extensions/{name}", f"material extension {name} is not imported")
    emitter = _emitter(ctx, entry, pointer, double_sided)
    if emitter is not None and "opacity" in table:
        ctx.warn(f"{pointer}/alphaMode", "an emissive material's alpha is not imported (emitters are opaque)")
        del table["opacity"]
    return table, emitter


def _unit(doc, table: dict, key: str, pointer: str, default: float = 1.0) -> float:
    value = doc.number(table, key, pointer, default)
    if not 0.0 <= value <= 1.0:
        raise doc.fail(f"{pointer}/{key}", f"must lie in [0, 1], got {value:g}")
    return value


def _extensions(ctx: GltfImport, table: dict, entry: dict, pointer: str) -> None:
    doc = ctx.doc
    if (ior := doc.extension(entry, "KHR_materials_ior", pointer)) is not None:
        where = f"{pointer}/extensions/KHR_materials_ior"
        value = doc.number(ior, "ior", where, 1.5)
        if value == 0.0:  # the extension's "0: a fully specular surface"; principled's eta lies in (1, 4]
            ctx.warn(f"{where}/ior", "ior 0 (a purely specular surface) is imported as ior 1.5")
        elif value == 1.0:
            ctx.warn(f"{where}/ior", "ior 1 is imported as 1.0001 (the principled material's index exceeds 1)")
            table["eta"] = 1.0001
        elif not 1.0 < value <= 4.0:
            raise doc.fail(f"{where}/ior", f"must be 0 or lie in [1, 4], got {value:g}")
        else:
            table["eta"] = value
    if (transmission := doc.extension(entry, "KHR_materials_transmission", pointer)) is not None:
        where = f"{pointer}/extensions/KHR_materials_transmission"
        factor = _unit(doc, transmission, "transmissionFactor", where, 0.0)
        info = transmission.get("transmissionTexture")
        mapped = texture(ctx, info, f"{where}/transmissionTexture", "red", factor) if info is not None else None
        if mapped is not None or factor > 0.0:
            table["spec_trans"] = mapped or factor
    if (coat := doc.extension(entry, "KHR_materials_clearcoat", pointer)) is not None:
        where = f"{pointer}/extensions/KHR_materials_clearcoat"
        factor = _unit(doc, coat, "clearcoatFactor", where, 0.0)
        info = coat.get("clearcoatTexture")
        mapped = texture(ctx, info, f"{where}/clearcoatTexture", "red", factor) if info is not None else None
        if mapped is not None or factor > 0.0:
            table["clearcoat"] = mapped or factor
            # principled's clearcoat_gloss is 1 − the coat's roughness
            rough = _unit(doc, coat, "clearcoatRoughnessFactor", where, 0.0)
            info = coat.get("clearcoatRoughnessTexture")
            at = f"{where}/clearcoatRoughnessTexture"
            gloss = texture(ctx, info, at, "gloss", rough) if info is not None else None
            table["clearcoat_gloss"] = gloss or 1.0 - rough
        if "clearcoatNormalTexture" in coat:
            ctx.warn(f"{where}/clearcoatNormalTexture", "a clearcoat's own normal map is not imported")
    if (sheen := doc.extension(entry, "KHR_materials_sheen", pointer)) is not None:
        # glTF's sheen is a coloured Charlie lobe with its own roughness, principled's Burley's amount and tint:
        # the amount is the colour's largest component, tinted toward the base colour where the colour is not grey.
        where = f"{pointer}/extensions/KHR_materials_sheen"
        colour = doc.numbers(sheen, "sheenColorFactor", where, 3, [0.0, 0.0, 0.0])
        if max(colour) > 0.0:
            table["sheen"] = min(1.0, max(colour))
            if max(colour) - min(colour) > 1e-6:
                table["sheen_tint"] = 1.0
            ctx.warn(where, "KHR_materials_sheen is approximated by the principled sheen (amount and tint)")
        for key in ("sheenColorTexture", "sheenRoughnessTexture"):
            if key in sheen:
                ctx.warn(f"{where}/{key}", f"the sheen's {key} is not imported")


# The principled keys a thin sheet (principledthin) has no counterpart of.
_NOT_THIN = ("metallic", "clearcoat", "clearcoat_gloss", "specular", "anisotropic_rotation", "anisotropic_direction")


def _diffuse_transmission(ctx: GltfImport, table: dict, entry: dict, pointer: str) -> None:
    """KHR_materials_diffuse_transmission makes the surface a thin sheet whose diffuse part is partly Lambertian
    transmission: the `principledthin` material, diff_trans = 2 × diffuseTransmissionFactor (its range is 0–2). Its
    transmission colour is taken to be the base colour; its texture, the metal and the coat are left out, each
    named."""
    doc = ctx.doc
    extension = doc.extension(entry, "KHR_materials_diffuse_transmission", pointer)
    if extension is None:
        return
    where = f"{pointer}/extensions/KHR_materials_diffuse_transmission"
    factor = _unit(doc, extension, "diffuseTransmissionFactor", where, 0.0)
    if "diffuseTransmissionTexture" in extension:
        ctx.warn(
            f"{where}/diffuseTransmissionTexture", "a diffuse transmission texture is not imported (its factor is)"
        )
    if factor == 0.0:
        return
    colour = doc.numbers(extension, "diffuseTransmissionColorFactor", where, 3, [1.0, 1.0, 1.0])
    if colour != [1.0, 1.0, 1.0] or "diffuseTransmissionColorTexture" in extension:
        ctx.warn(where, "the diffuse transmission's colour is approximated by the base colour")
    for key in _NOT_THIN:
        value = table.pop(key, None)
        if value is not None and value != 0.0 and key != "clearcoat_gloss":
            ctx.warn(where, f"a diffusely transmitting sheet has no {key} here (principledthin): it is left out")
    table["type"] = "principledthin"
    table["diff_trans"] = 2.0 * factor


def _alpha(ctx: GltfImport, entry: dict, pbr: dict, table: dict, alpha: float, pointer: str) -> None:
    """OPAQUE: alpha ignored; MASK: opaque where alpha ≥ alphaCutoff, a hole elsewhere; BLEND: alpha is the
    opacity (the probability a ray meets the surface: a stochastic blend, the same on average)."""
    doc = ctx.doc
    mode = entry.get("alphaMode", "OPAQUE")
    if mode not in ("OPAQUE", "MASK", "BLEND"):
        raise doc.fail(f"{pointer}/alphaMode", f"unknown alpha mode {mode!r} (OPAQUE, MASK, BLEND)")
    if mode == "OPAQUE":
        return
    info = pbr.get("baseColorTexture")
    where = f"{pointer}/pbrMetallicRoughness/baseColorTexture"
    if mode == "MASK":
        cutoff = doc.number(entry, "alphaCutoff", pointer, 0.5)
        if info is None:
            if alpha < cutoff:
                table["opacity"] = 0.0
            return
        mapped = texture(ctx, info, where, "alpha", alpha, cutoff=cutoff)
        if mapped is not None:
            table["opacity"] = mapped
        return
    mapped = texture(ctx, info, where, "alpha", alpha) if info is not None else None
    if mapped is not None:
        table["opacity"] = mapped
    elif alpha < 1.0:
        table["opacity"] = alpha


def _emitter(ctx: GltfImport, entry: dict, pointer: str, double_sided: bool) -> dict | None:
    doc = ctx.doc
    factor = doc.numbers(entry, "emissiveFactor", pointer, 3, [0.0, 0.0, 0.0])
    if any(value < 0.0 for value in factor):
        raise doc.fail(f"{pointer}/emissiveFactor", "must not be negative")
    strength_table = doc.extension(entry, "KHR_materials_emissive_strength", pointer) or {}
    where = f"{pointer}/extensions/KHR_materials_emissive_strength"
    strength = doc.number(strength_table, "emissiveStrength", where, 1.0) if strength_table else 1.0
    if strength < 0.0:
        raise doc.fail(f"{where}/emissiveStrength", "must not be negative")
    if max(factor) == 0.0 or strength == 0.0:
        return None
    scale = strength / photometric_scale()
    radiance: dict | None = None
    if "emissiveTexture" in entry:
        radiance = texture(ctx, entry["emissiveTexture"], f"{pointer}/emissiveTexture", "emissive", factor)
    emitter: dict = {"radiance": radiance or {"rgb": factor}, "scale": scale}
    if double_sided:
        emitter["two_sided"] = True
    return emitter


def _interior(ctx: GltfImport, entry: dict, pointer: str, table: dict) -> dict | None:
    """KHR_materials_volume's absorption as the medium filling the mesh: a colour c reached after the distance d
    (Beer-Lambert) is σa = −ln(c) / d per scene unit, an `rgb` σa (a smooth spectrum through those three values).
    A volume of thickness 0 is thin-walled (no medium), and one without an attenuationDistance absorbs nothing."""
    doc = ctx.doc
    volume = doc.extension(entry, "KHR_materials_volume", pointer)
    if volume is None:
        return None
    where = f"{pointer}/extensions/KHR_materials_volume"
    thickness = doc.number(volume, "thicknessFactor", where, 0.0)
    if thickness <= 0.0 or "attenuationDistance" not in volume:
        return None
    distance = doc.number(volume, "attenuationDistance", where)
    if distance <= 0.0:
        raise doc.fail(f"{where}/attenuationDistance", "must be > 0")
    colour = doc.numbers(volume, "attenuationColor", where, 3, [1.0, 1.0, 1.0])
    if not all(0.0 <= c <= 1.0 for c in colour):
        raise doc.fail(f"{where}/attenuationColor", "must lie in [0, 1]")
    if min(colour) == 1.0:
        return None
    # a colour of 0 would be an infinite σa: 10⁻⁶ after the distance is as black
    sigma_a = [-math.log(max(c, 1e-6)) / distance for c in colour]
    if "opacity" in table:
        ctx.warn(
            f"{pointer}/alphaMode", "the alpha of a material with a volume is not imported (media fill opaque shapes)"
        )
        del table["opacity"]
    return {"sigma_a": {"rgb": sigma_a}}
