"""glTF material extensions that move the principled material's index and lobe shape rather than add a lobe:
KHR_materials_specular (the dielectric reflectance), KHR_materials_dispersion (the index's dependence on λ) and
KHR_materials_anisotropy (the specular lobe's stretch and direction); KHR_materials_iridescence is named, as
spectrace has no thin-film layer. docs/materials.md's mapping table and docs/gltf.md give each row.

Called after the index, the transmission and the roughness are in the table, which they read."""

from __future__ import annotations

import math

import numpy as np

from spectrace.interop.gltf.context import GltfImport
from spectrace.interop.gltf.textures import texture

SPECULAR = "KHR_materials_specular"
DISPERSION = "KHR_materials_dispersion"
ANISOTROPY = "KHR_materials_anisotropy"
IRIDESCENCE = "KHR_materials_iridescence"
EXTENSIONS = (SPECULAR, DISPERSION, ANISOTROPY, IRIDESCENCE)
# KHR_materials_dispersion's n(λ) = n_d + (n_d − 1)/V_d · (523655 nm² / λ² − 1.5168): Cauchy's a + b/λ² with λ
# in µm once its terms are collected
DISPERSION_B_UM2 = 0.523655
DISPERSION_OFFSET = 1.5168
ETA_MAX = 4.0  # the principled material's largest index
ETA_MIN = 1.0001  # its index exceeds 1; this one reflects nothing short of grazing
REC709_Y = (0.2126, 0.7152, 0.0722)


def apply(ctx: GltfImport, table: dict, entry: dict, pointer: str, roughness: float) -> None:
    """The four extensions of glTF material `entry` into its principled `table`; `roughness` is its
    roughnessFactor (the anisotropy's mapping depends on it)."""
    _specular(ctx, table, entry, pointer)
    _dispersion(ctx, table, entry, pointer)
    _anisotropy(ctx, table, entry, pointer, roughness)
    if ctx.doc.extension(entry, IRIDESCENCE, pointer) is not None:
        ctx.warn(
            f"{pointer}/extensions/{IRIDESCENCE}",
            f"{IRIDESCENCE} (thin-film interference) is not imported: spectrace has no thin-film layer, so the "
            "surface renders without its colours",
        )


def _eta(table: dict) -> float:
    eta = table.get("eta", 1.5)
    return float(eta) if isinstance(eta, (int, float)) else 1.5


def eta_from_f0(f0: float) -> float:
    """The index whose normal-incidence Fresnel reflectance ((η − 1)/(η + 1))² is f0, within principled's range."""
    root = math.sqrt(min(max(f0, 0.0), 1.0))
    eta = (1.0 + root) / (1.0 - root) if root < 1.0 else math.inf
    return min(ETA_MAX, max(ETA_MIN, eta))


def _specular(ctx: GltfImport, table: dict, entry: dict, pointer: str) -> None:
    """glTF's dielectric F0 = min(R0(η) · specularColorFactor, 1) · specularFactor, R0 = ((η − 1)/(η + 1))², with
    F90 = specularFactor: the index whose R0 is that F0's luminance (a grey colour and a factor of 0 or 1 are
    exact; a coloured F0 and a factor between 0 and 1, whose grazing reflectance glTF lowers too, approximated and
    named). A transmitting material keeps its index for the refraction, so there the extension is named instead."""
    doc = ctx.doc
    extension = doc.extension(entry, SPECULAR, pointer)
    if extension is None:
        return
    where = f"{pointer}/extensions/{SPECULAR}"
    factor = doc.number(extension, "specularFactor", where, 1.0)
    if not 0.0 <= factor <= 1.0:
        raise doc.fail(f"{where}/specularFactor", f"must lie in [0, 1], got {factor:g}")
    colour = doc.numbers(extension, "specularColorFactor", where, 3, [1.0, 1.0, 1.0])
    for i, value in enumerate(colour):
        if not (value >= 0.0 and math.isfinite(value)):
            raise doc.fail(f"{where}/specularColorFactor/{i}", f"must be a number ≥ 0, got {value:g}")
    info = extension.get("specularTexture")
    colour_info = extension.get("specularColorTexture")
    if info is None and colour_info is None and factor == 1.0 and colour == [1.0, 1.0, 1.0]:
        return
    if "spec_trans" in table:
        ctx.warn(where, f"{SPECULAR} on a transmitting material is not imported (its ior sets the refraction)")
        return
    r0 = ((_eta(table) - 1.0) / (_eta(table) + 1.0)) ** 2
    f0 = factor * sum(w * min(r0 * c, 1.0) for w, c in zip(REC709_Y, colour, strict=True))
    if 0.0 < factor < 1.0 or max(colour) - min(colour) > 1e-6 or colour_info is not None:
        ctx.warn(
            where,
            f"{SPECULAR} is approximated by the index of its F0's luminance (a coloured F0, and a specularFactor's "
            "lower grazing reflectance, are not modelled)",
        )
    level = f0 / 0.08  # principled's specular level: its F0 is 0.08 specular
    mapped = None
    if colour_info is not None:
        mapped = _specular_colour(ctx, colour_info, f"{where}/specularColorTexture", factor, r0, colour)
        # the level's other factor, specularTexture's A, multiplies in as a scale texture's factor
        level = 1.0 if mapped is not None else level
    if info is not None:
        # F0 = A · f0 per texel is principled's specular level 12.5 F0, the index that level gives per hit
        # (bsdf_principled.cl); above the level 1 (F0 0.08, an index of 1.8) it is clipped.
        at = f"{where}/specularTexture"
        alpha = texture(ctx, info, at, "alpha", curve=(f"specular{level:.6g}", lambda a: level * a))
        if alpha is not None and level > 1.0:
            ctx.warn(at, f"{SPECULAR}'s F0 above 0.08 (an index above 1.8) is clipped there in the texture")
        if alpha is not None:
            mapped = alpha if mapped is None else {"texture": "scale", "tex": mapped, "scale": alpha}
    if mapped is not None:
        table.pop("eta", None)
        table["specular"] = mapped
        return
    table["eta"] = eta_from_f0(f0)


def _specular_colour(ctx: GltfImport, info, at: str, factor: float, r0: float, colour: list[float]) -> dict | None:
    """specularColorTexture (sRGB) as a grey texture of principled's specular level, texel by texel the luminance
    of glTF's F0 = specularFactor · min(R0 · specularColorFactor · texel, 1) over 0.08 (clipped at 1, F0 0.08):
    what the factor alone maps to, with the texel's colour in it. The hue, which principled's tint (toward the
    base colour) cannot carry, is left out with the warning above."""
    weights = np.asarray(REC709_Y) * factor / 0.08
    scale = r0 * np.asarray(colour)

    def level(codes: np.ndarray) -> np.ndarray:
        c = np.where(codes <= 0.04045, codes / 12.92, ((codes + 0.055) / 1.055) ** 2.4)
        return (np.minimum(scale * c, 1.0) @ weights)[..., None]

    name = f"specular_colour{factor:.6g}_{r0:.6g}_" + "_".join(f"{c:.6g}" for c in colour)
    mapped = texture(ctx, info, at, "rgb", curve=(name, level))
    if mapped is not None and float(np.minimum(scale, 1.0) @ weights) > 1.0:  # a white texel's level
        ctx.warn(at, f"{SPECULAR}'s F0 above 0.08 (an index above 1.8) is clipped where the texture reaches it")
    return mapped


def _dispersion(ctx: GltfImport, table: dict, entry: dict, pointer: str) -> None:
    """dispersion D = 20/V_d (V_d the Abbe number): the extension's n(λ) = n_d + (n_d − 1)/V_d (523655/λ² − 1.5168),
    λ in nm, is the Cauchy index a + b/λ² (λ in µm) with b = 0.523655 (n_d − 1)/V_d and a = n_d − 1.5168 (n_d − 1)/
    V_d, exactly. Without transmission nothing refracts and the index stays a number."""
    doc = ctx.doc
    extension = doc.extension(entry, DISPERSION, pointer)
    if extension is None:
        return
    where = f"{pointer}/extensions/{DISPERSION}"
    dispersion = doc.number(extension, "dispersion", where, 0.0)
    if not (dispersion >= 0.0 and math.isfinite(dispersion)):
        raise doc.fail(f"{where}/dispersion", f"must be a number ≥ 0, got {dispersion:g}")
    if dispersion == 0.0:
        return
    if "spec_trans" not in table:
        ctx.note(f"{DISPERSION} on a material that does not transmit changes nothing (nothing refracts)")
        return
    n_d = _eta(table)
    spread = (n_d - 1.0) * dispersion / 20.0  # (n_d − 1)/V_d
    table["eta"] = {"cauchy": [n_d - DISPERSION_OFFSET * spread, DISPERSION_B_UM2 * spread]}


def anisotropic_weight(strength, roughness: float):
    """principled's `anisotropic` a for glTF's anisotropyStrength s (a number or an array) at perceptual roughness
    r: glTF stretches the tangent's α alone, α_t = mix(α, 1, s²), α_b = α (α = r²); principled stretches both ways,
    α_x / α_y = 1/(1 − 0.9 a). The same ratio α_t/α_b gives a (at most 1, a ratio of 10)."""
    alpha = max(0.001, roughness * roughness)
    ratio = (alpha + np.square(strength) * (1.0 - alpha)) / alpha
    weight = np.minimum(1.0, (1.0 - 1.0 / ratio) / 0.9)
    return float(weight) if np.ndim(weight) == 0 else weight


def _anisotropy(ctx: GltfImport, table: dict, entry: dict, pointer: str, roughness: float) -> None:
    """The strength (anisotropyStrength times the texture's B) becomes principled's `anisotropic`, a texture baked
    texel by texel where the file has one; the direction turns the lobe by `anisotropic_rotation`
    (anisotropyRotation) and, per texel, by `anisotropic_direction` (the texture's RG, raw)."""
    doc = ctx.doc
    extension = doc.extension(entry, ANISOTROPY, pointer)
    if extension is None:
        return
    where = f"{pointer}/extensions/{ANISOTROPY}"
    strength = doc.number(extension, "anisotropyStrength", where, 0.0)
    if not 0.0 <= strength <= 1.0:
        raise doc.fail(f"{where}/anisotropyStrength", f"must lie in [0, 1], got {strength:g}")
    rotation = doc.number(extension, "anisotropyRotation", where, 0.0)
    if not math.isfinite(rotation):
        raise doc.fail(f"{where}/anisotropyRotation", "must be a finite number of radians")
    if strength == 0.0:
        return
    weight: float | dict = anisotropic_weight(strength, roughness)
    if (info := extension.get("anisotropyTexture")) is not None:
        at = f"{where}/anisotropyTexture"
        curve = (f"anisotropy{strength:.6g}_{roughness:.6g}", lambda b: anisotropic_weight(strength * b, roughness))
        mapped = texture(ctx, info, at, "blue", curve=curve)
        if mapped is not None:
            weight = mapped
            # RG: the direction per texel, turned by anisotropyRotation (kernels/anisotropy_direction.cl)
            if (direction := texture(ctx, info, at, "rgb")) is not None:
                table["anisotropic_direction"] = direction
    table["anisotropic"] = weight
    degrees = math.fmod(math.degrees(rotation), 360.0)
    if degrees != 0.0:
        table["anisotropic_rotation"] = degrees
    ctx.warn(
        where,
        f"{ANISOTROPY} is approximated: principled's lobe stretches along and across its direction (the ratio of "
        "the two roughnesses is glTF's), turned from dp/du by anisotropyRotation",
    )
