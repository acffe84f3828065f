"""BSDFs: the dispatch to each material's own mapping (spectrace.materials.<name>: MITSUBA_PLUGINS,
`from_mitsuba`), the wrappers spectrace represents as keys of the wrapped material (twosided, and the surface-detail
adapters normalmap, bumpmap, mask), and what the rough BSDFs share (roughness, distribution, named indices of
refraction).

Without `twosided`, a reflecting BSDF is one-sided in Mitsuba, black from the back: its material takes
two_sided = false. Mitsuba's rectangle and PLY texture coordinates run v up where spectrace's run down: a textured
BSDF on those shapes is imported with its textures' v flipped, as a material of its own.
"""

from __future__ import annotations

import math
import tempfile
from pathlib import Path

import numpy as np

from spectrace.core.parameters import DISTRIBUTIONS, ROUGHNESS_RANGE
from spectrace.interop.mitsuba.context import ImportContext, Properties, unique_name
from spectrace.interop.mitsuba.plugins import BSDF_MODULES, SPECTRUM_PLUGINS, SURFACE_DETAIL_WRAPPERS
from spectrace.interop.mitsuba.textures import checked_textures, scalar_texture, texture
from spectrace.interop.mitsuba.tree import Element, shown
from spectrace.materials import MATERIALS

# Mitsuba BSDFs whose spectrace counterparts are being written; until then they are reported as unsupported.
PLANNED_BSDFS: tuple[str, ...] = ()
# Mitsuba BSDFs refused for want of their data, with the reason the error gives.
UNAVAILABLE_BSDFS = {
    "measured_polarized": " (its measured pBRDF files, Baek et al. 2020, are published only on the authors' lab site, "
    "not in a public repository, and spectrace has no reader for them)",
}
# Mitsuba 3's named indices of refraction (its documentation's table, at about 589 nm), for int_ior / ext_ior.
NAMED_IOR = {
    "vacuum": 1.0,
    "helium": 1.000036,
    "hydrogen": 1.000132,
    "air": 1.000277,
    "carbon dioxide": 1.00045,
    "water": 1.333,
    "acetone": 1.36,
    "ethanol": 1.361,
    "carbon tetrachloride": 1.461,
    "glycerol": 1.4729,
    "benzene": 1.501,
    "silicone oil": 1.52045,
    "bromine": 1.661,
    "water ice": 1.31,
    "fused quartz": 1.458,
    "pyrex": 1.470,
    "acrylic glass": 1.49,
    "polypropylene": 1.49,
    "bk7": 1.5046,
    "sodium chloride": 1.544,
    "amber": 1.55,
    "pet": 1.575,
    "diamond": 2.419,
}


def material(
    ctx: ImportContext, element: Element | None, owner: str, flip_v: bool = False, emits: bool = False
) -> str | None:
    """The name of the spectrace material for a (possibly referenced) bsdf, defining it on first use. flip_v:
    for a shape whose v runs up (V_UP_SHAPES); a textured bsdf then becomes a material of its own, with its
    textures' v flipped. Without a bsdf, Mitsuba's default: diffuse 0.5, one-sided as its plain diffuse is,
    and black on a shape that emits (measured: Mitsuba 3's emitter without a bsdf reflects nothing)."""
    if element is None:
        name, reflectance = ("default_emitter", 0.0) if emits else ("default", 0.5)
        if name not in ctx.materials:
            ctx.materials[name] = {"type": "diffuse", "reflectance": {"value": reflectance}}
            if not emits:
                ctx.materials[name]["two_sided"] = False
        return name
    bsdf = ctx.resolve(element)
    if (id(bsdf), flip_v) in ctx.material_of_element:
        return ctx.material_of_element[(id(bsdf), flip_v)]
    base = ctx.attribute(bsdf, "id") or f"{owner}_bsdf"
    name = unique_name(base, ctx.materials)
    saved = ctx.flip_v, ctx.used_texture
    ctx.flip_v, ctx.used_texture = flip_v, False
    try:
        table = material_table(ctx, bsdf)
        textured = ctx.used_texture
    finally:
        ctx.flip_v, ctx.used_texture = saved[0], saved[1] or ctx.used_texture
    if table is None:
        return None
    if textured and flip_v:
        name = unique_name(f"{base}_flipped_v", ctx.materials)
        ctx.notes.append(
            f"{ctx.at(bsdf)}: {bsdf.label()} on a rectangle or PLY shape: their texture coordinates run v up "
            f"in Mitsuba and down in spectrace, so it is imported as material '{name}' with its textures' v "
            "flipped"
        )
    ctx.materials[name] = table
    ctx.material_of_element[(id(bsdf), flip_v)] = name
    if not textured:  # the same material whichever way v runs
        ctx.material_of_element[(id(bsdf), not flip_v)] = name
    ctx.origins[f"materials.{name}"] = bsdf
    for key, value in table.items():
        # What the loader says of a texture a key takes (a normal map read as colours) is told at the texture.
        if isinstance(value, dict) and list(value) == ["texture"]:
            ctx.origins[f"materials.{name}.{key}"] = ctx.texture_elements[value["texture"]]
    return name


def material_table(ctx: ImportContext, bsdf: Element, two_sided: bool = False) -> dict | None:
    """two_sided: the bsdf is inside a `twosided` wrapper. Outside one, Mitsuba's reflecting BSDFs are black
    from the back of the surface, so their materials take two_sided = false; those that transmit have two
    sides by nature."""
    with ctx.converting(bsdf):
        return _material_table(ctx, bsdf, two_sided)


def _material_table(ctx: ImportContext, bsdf: Element, two_sided: bool) -> dict | None:
    kind = ctx.kind(bsdf) if bsdf.tag == "bsdf" else None
    properties = ctx.properties(bsdf)
    if kind == "twosided":
        nested = ctx.nested(properties, "bsdf")
        if len(nested) != 1:
            ctx.unsupported_plugin(bsdf, " with two different sides")
            return None
        return material_table(ctx, nested[0], two_sided=True)
    if kind in SURFACE_DETAIL_WRAPPERS:
        return surface_detail(ctx, bsdf, kind, properties, two_sided)
    if kind in BSDF_MODULES:
        table = BSDF_MODULES[kind].from_mitsuba(ctx, bsdf, properties)
        # A module may import a plugin as another material (conductor "none" as mirror): that one's table counts.
        if table is None or not checked_textures(ctx, table, MATERIALS[table["type"]]):
            return None
        if not two_sided and not MATERIALS[table["type"]].MODEL.has_transmission:
            table["two_sided"] = False
        return table
    ctx.unsupported_object(
        bsdf, " (not yet in spectrace)" if kind in PLANNED_BSDFS else UNAVAILABLE_BSDFS.get(kind or "", "")
    )
    return None


def surface_detail(
    ctx: ImportContext, bsdf: Element, kind: str, properties: Properties, two_sided: bool
) -> dict | None:
    """The material of the one bsdf that a normalmap, bumpmap or mask adapter wraps, with the adapter's key
    added: normal_map (its `normalmap` texture), bump_map and bump_scale (its one texture, `scale`), opacity
    (`opacity`, Mitsuba's default 0.5). Mitsuba's bumpmap displaces by scale · h along the normal (its tangents
    are dp/du + scale · ∂h/∂u · n), which is spectrace's bump_scale. A normal or bump map's
    `use_shadowing_function` (Mitsuba's default true) is spectrace's shadowing_function."""
    nested = ctx.nested(properties, "bsdf")
    properties.understood(*properties.keys())  # each key is judged below
    if len(nested) != 1:
        raise ctx.fail(bsdf, f"{bsdf.label()} needs exactly one nested bsdf, got {len(nested)}")
    expected = {"normalmap": "normalmap", "bumpmap": "scale", "mask": "opacity"}[kind]
    textures = [key for key, child in properties.items() if ctx.resolve(child).tag == "texture"]
    shadowing = kind != "mask"
    for key, child in properties.items():
        if shadowing and key == "use_shadowing_function":
            continue
        # A bumpmap's texture may have any name.
        if key != expected and ctx.resolve(child).tag != "bsdf" and not (kind == "bumpmap" and key in textures):
            ctx.unsupported_plugin(bsdf, f" with {shown(key)}")
            return None
    detail: dict = {}
    if kind == "normalmap":
        map_element = ctx.resolve(ctx.child(properties, "normalmap", bsdf))
        if map_element.tag == "texture" and ctx.kind(map_element) == "rawconstant":
            constant = constant_normal_map(ctx, map_element)
            if constant is None:
                return None
            if constant:  # the unturned normal (0, 0, 1) needs no map
                detail["normal_map"] = constant
        elif map_element.tag != "texture" or ctx.kind(map_element) != "bitmap":
            ctx.unsupported_plugin(map_element, " as normalmap (spectrace's normal maps are bitmaps or rawconstant)")
            return None
        else:
            detail["normal_map"] = texture(ctx, map_element, "normal_map")
    elif kind == "bumpmap":
        if len(textures) != 1:
            raise ctx.fail(bsdf, f"{bsdf.label()} needs exactly one nested texture, got {len(textures)}")
        map_element = ctx.resolve(properties[textures[0]])
        if ctx.kind(map_element) in SPECTRUM_PLUGINS:  # a constant height: no gradient, nothing to import
            ctx.unsupported_plugin(map_element, " as a bump map (spectrace's bump maps are bitmaps or checkerboards)")
            return None
        detail["bump_map"] = scalar_texture(ctx, map_element, "bump_map")
        if "scale" in properties:
            detail["bump_scale"] = ctx.number(properties["scale"])
    else:
        detail["opacity"] = opacity(ctx, properties["opacity"]) if "opacity" in properties else 0.5
    if any(value is None for value in detail.values()):
        return None
    if shadowing and detail:
        switch = properties.get("use_shadowing_function")
        detail["shadowing_function"] = True if switch is None else ctx.boolean(switch)
    table = material_table(ctx, nested[0], two_sided)
    if table is None:
        return None
    one_of = ("opacity",) if "opacity" in detail else ("normal_map", "bump_map")
    taken = [key for key in one_of if key in table]
    if taken:
        ctx.unsupported_plugin(
            bsdf,
            f" around a bsdf with a {taken[0].replace('_', ' ')} already (a spectrace material takes one "
            f"{'opacity' if one_of == ('opacity',) else 'normal map or bump map'})",
        )
        return None
    return table | detail


def constant_normal_map(ctx: ImportContext, texture: Element) -> dict | None:
    """A `rawconstant` texture as a normal map: one tangent-space normal 2 c − 1 everywhere. The unturned normal
    (c = (0.5, 0.5, 1)) is an empty dict (no map); any other is a 1 x 1 float OpenEXR of c written beside the
    TOML, read raw. None when it is no normal (recorded)."""
    properties = ctx.properties(texture)
    value = ctx.resolve(ctx.child(properties, "value", texture))
    if value.tag not in ("vector", "rgb", "float"):
        ctx.unsupported_plugin(texture, " as normalmap (its value is a vector, an rgb or a float)")
        return None
    numbers = ctx.vector(value) if value.tag == "vector" else ctx.numbers(value)
    if len(numbers) not in (1, 3):
        raise ctx.fail(value, f"a rawconstant normal map needs 1 or 3 numbers, got {len(numbers)}", "value")
    c = np.resize(np.asarray(numbers, np.float64), 3)
    if not np.linalg.norm(2.0 * c - 1.0) > 0.0:
        raise ctx.fail(value, "a rawconstant normal map of value 0.5, 0.5, 0.5 holds no direction", "value")
    if np.allclose(c, (0.5, 0.5, 1.0), rtol=0.0, atol=1e-6):
        return {}
    from spectrace.io.exr import write_exr

    with tempfile.TemporaryDirectory(prefix="spectrace-normal-") as folder:
        path = Path(folder) / "normal.exr"
        write_exr(path, np.tile(c, (1, 1, 1)), None, {})
        data = path.read_bytes()
    name = f"{ctx.side_stem}.normal_map_{sum(key.endswith('.exr') for key in ctx.side_files) + 1}.exr"
    ctx.side_files[name] = data
    texture_name = unique_name(ctx.attribute(texture, "id") or "normal_map_constant", ctx.textures)
    ctx.textures[texture_name] = {"type": "bitmap", "file": name, "raw": True}
    ctx.texture_elements[texture_name] = texture
    ctx.origins[f"textures.{texture_name}"] = texture
    ctx.notes.append(
        f"{ctx.at(texture)}: the rawconstant normal map is a 1 x 1 image written to {name} beside the scene"
    )
    return {"texture": texture_name}


def opacity(ctx: ImportContext, element: Element) -> float | dict | None:
    """A mask's opacity: a number in [0, 1] or a texture."""
    resolved = ctx.resolve(element)
    if resolved.tag == "texture":
        return scalar_texture(ctx, resolved, "opacity")
    if resolved.tag != "float":
        ctx.unsupported_plugin(resolved, " as opacity (spectrace's opacity is a number or a texture)")
        return None
    value = ctx.number(resolved)
    if not 0.0 <= value <= 1.0:
        raise ctx.fail(resolved, f"opacity must lie in [0, 1], got {value:g}", "value")
    return value


def roughness(ctx: ImportContext, bsdf: Element, properties: dict[str, Element]) -> float | dict | None:
    """Microfacet α of a rough Mitsuba BSDF (its default 0.1), or a texture reference for a textured `alpha`; None
    when spectrace cannot represent it (recorded). An anisotropic α (alpha_u ≠ alpha_v) becomes the isotropic
    sqrt(alpha_u alpha_v) with a warning: the BSDFs that call this have isotropic lobes (the conductor, whose lobe
    may be anisotropic, calls roughnesses)."""
    if "alpha_u" not in properties and "alpha_v" not in properties:
        return _alpha(ctx, bsdf, properties["alpha"]) if "alpha" in properties else 0.1
    alphas = roughnesses(ctx, bsdf, properties)
    if alphas is None:
        return None
    alpha_u, alpha_v = alphas
    if alpha_u == alpha_v:
        return alpha_u
    if not isinstance(alpha_u, float) or not isinstance(alpha_v, float):
        ctx.unsupported_plugin(bsdf, " with a textured alpha_u or alpha_v (anisotropic roughness)")
        return None
    # The geometric mean keeps the distribution's peak D(0) = 1 / (π αu αv), so the highlight's height, and
    # loses its stretch.
    alpha = math.sqrt(alpha_u * alpha_v)
    ctx.warnings.append(
        f"{shown(str(bsdf.file or ctx.xml_path), 200)}:{bsdf.line}: {bsdf.label()}: anisotropic "
        f"roughness alpha_u = {alpha_u:g}, alpha_v = {alpha_v:g} approximated by the isotropic "
        f"alpha = sqrt(alpha_u alpha_v) = {alpha:.4g} (spectrace's {ctx.kind(bsdf)} lobe is isotropic)"
    )
    return alpha


def roughnesses(
    ctx: ImportContext, bsdf: Element, properties: dict[str, Element]
) -> tuple[float | dict, float | dict] | None:
    """Microfacet α along u and along v of a rough Mitsuba BSDF, each a number or a texture reference: alpha_u and
    alpha_v (either one alone standing for both, as in Mitsuba), else `alpha` (default 0.1) for both; None when
    spectrace cannot represent one (recorded)."""
    if "alpha_u" not in properties and "alpha_v" not in properties:
        alpha = _alpha(ctx, bsdf, properties["alpha"]) if "alpha" in properties else 0.1
        return None if alpha is None else (alpha, alpha)
    u_element = properties.get("alpha_u", properties.get("alpha_v"))
    v_element = properties.get("alpha_v", properties.get("alpha_u"))
    assert u_element is not None and v_element is not None  # one of them is given, standing for both
    alpha_u = _alpha(ctx, bsdf, u_element)
    alpha_v = alpha_u if v_element is u_element else _alpha(ctx, bsdf, v_element)
    if alpha_u is None or alpha_v is None:
        return None
    return alpha_u, alpha_v


def _alpha(ctx: ImportContext, bsdf: Element, element: Element) -> float | dict | None:
    """One α property: a number in the range spectrace takes, or a texture reference (whose values are checked
    against the range when the scene loads, as any roughness texture's are); None when not representable."""
    element = ctx.resolve(element)
    alpha = scalar_texture(ctx, element, "roughness") if element.tag == "texture" else ctx.number(element)
    if alpha is None:
        return None
    if isinstance(alpha, dict) and list(alpha) == ["value"]:  # a spectrum plugin standing for a number
        alpha = float(alpha["value"])
    if isinstance(alpha, float) and not ROUGHNESS_RANGE.contains(alpha):
        raise ctx.fail(bsdf, f"alpha must lie in {ROUGHNESS_RANGE} for spectrace, got {alpha:g}")
    return alpha


def distribution(ctx: ImportContext, bsdf: Element, properties: dict[str, Element]) -> str:
    """The microfacet distribution of a rough Mitsuba BSDF (its default: beckmann)."""
    if "distribution" not in properties:
        return "beckmann"
    element = ctx.resolve(properties["distribution"])
    value = ctx.text(element)
    if value not in DISTRIBUTIONS:
        raise ctx.fail(element, f"unknown distribution '{shown(value)}' (Mitsuba's: ggx, beckmann)", "value")
    return value


def ior(ctx: ImportContext, bsdf: Element, properties: dict[str, Element], key: str, default: float) -> float:
    """An index of refraction property (int_ior, ext_ior): a number or one of Mitsuba's names."""
    if key not in properties:
        return default
    element = ctx.resolve(properties[key])
    if element.tag == "string":
        name = ctx.text(element)
        if name.lower() not in NAMED_IOR:
            raise ctx.fail(element, f"unknown {key} '{shown(name)}' (Mitsuba names: {', '.join(NAMED_IOR)})", "value")
        return NAMED_IOR[name.lower()]
    value = ctx.number(element)
    if not value > 0.0:
        raise ctx.fail(element, f"{key} must be > 0, got {value:g}", "value")
    return value
