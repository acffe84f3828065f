"""pbrt-v4's `subsurface` material as spectrace's random-walk media: the shape's surface a dielectric of the
material's `eta` (1.33 by default; rough where `roughness`, `uroughness` or `vroughness` is given), its interior a
homogeneous medium (docs/media.md) in one of pbrt's four mutually exclusive forms:

1. `name`: a named measured medium (pbrt-v4's GetMediumScatteringProperties: Jensen et al. 2001 and Narasimhan et
   al. 2006, spectrace's presets of the same numbers), in 1/mm read as 1/scene unit times `scale`; pbrt ignores `g`
   for these and so does the import;
2. `sigma_a` and `sigma_s` (both or neither), in 1/scene unit, times `scale`, with `g`;
3. `reflectance` with `mfp` (mean free path, default 1; a reflectance texture, an `imagemap`, as its image's mean
   colour, with a warning): pbrt builds a medium of extinction σt = 1/mfp whose
   single-scattering albedo α gives that effective (multiple-scattering) albedo under its photon beam diffusion
   profile (Habel, Christensen & Jarosz 2013; Pharr, Jakob & Humphreys, 3rd ed., 15.5): ρ_eff(α) = ∫ 2πr S(r) dr
   with S the profile's single- and multiple-scattering terms for σt = 1, σs = α, g and eta. The import solves
   ρ_eff(α) = reflectance for each of the reflectance's RGB components (pbrt: at each wavelength), so
   σs = α / mfp and σa = (1 − α) / mfp;
4. none of these: pbrt's default, whole milk's coefficients with `g` (as 2).

The random walk is the brute-force transport pbrt's diffusion profile approximates: a `reflectance` medium looks as
pbrt's where diffusion holds (thick, bright); thin or dark parts differ as the walk and the profile differ.
"""

from __future__ import annotations

import math
import re
from functools import cache

import numpy as np

from spectrace.interop.pbrt.context import Context
from spectrace.interop.pbrt.graphics_state import Entity
from spectrace.interop.pbrt.parser import error, shown

PBRT_DEFAULT_ETA = 1.33
# pbrt-v4's medium when a subsurface material names none (its `sigma_a`, `sigma_s` defaults, 1/scene unit).
PBRT_DEFAULT_SIGMA_A = [0.0011, 0.0024, 0.014]
PBRT_DEFAULT_SIGMA_S = [2.55, 3.21, 3.77]


def preset_name(pbrt_name: str) -> str:
    """spectrace's preset name for a pbrt named medium: lower case, words joined by '_' ("Lowfat Milk" ->
    "lowfat_milk", "Skin1" -> "skin1")."""
    return re.sub(r"[^a-z0-9]+", "_", pbrt_name.lower()).strip("_")


def subsurface_table(context: Context, material: Entity, rough: dict) -> dict:
    """The dielectric TOML table of a pbrt subsurface material (`rough` its roughness keys, as every pbrt material
    reads them); its interior is kept in context.material_interiors for the shapes that use it
    (`interior_of_material`)."""
    table: dict = {"type": "dielectric", "ior": _eta(context, material)} | rough
    context.material_interiors[id(material)] = _interior(context, material)
    return table


def interior_of_material(context: Context, reference: Entity | str | None) -> dict | None:
    """The interior a shape's subsurface material gives it, or None (another material, or none)."""
    if isinstance(reference, str):
        reference = context.scene.named_materials.get(reference)
    return None if reference is None else context.material_interiors.get(id(reference))


def _eta(context: Context, material: Entity) -> float:
    parameter = material.find("eta", "float")
    if parameter is None:
        if (other := material.find("eta")) is not None:
            raise error(other.location, f'"{other.label()}": a subsurface material\'s eta is one number (pbrt-v4)')
        return PBRT_DEFAULT_ETA
    eta = float(parameter.values[0])
    if not eta > 0.0:
        raise error(parameter.location, f'"{parameter.label()}" must be > 0, got {eta:g}')
    return eta


def _interior(context: Context, material: Entity) -> dict:
    from spectrace.spectral.media_presets import medium_presets

    scale = context.one(material, "scale", 1.0)
    if not scale > 0.0:
        raise error(material.location, f'subsurface "scale" must be > 0, got {scale:g}')
    g = context.one(material, "g", 0.0)
    if not -1.0 < g < 1.0:
        raise error(material.location, f'subsurface "g" must lie in (-1, 1), got {g:g}')
    for key in ("sigma_a", "sigma_s", "mfp"):
        if (parameter := material.find(key, "texture")) is not None:
            raise error(parameter.location, f'"{parameter.label()}": spectrace imports no textured medium')
    table: dict
    name = context.string(material, "name", "")
    if name:
        preset = preset_name(name)
        if preset not in medium_presets():
            parameter = material.find("name")
            raise error(
                parameter.location if parameter else material.location,
                f"\"string name\" '{shown(name)}' is no named medium pbrt-v4 or spectrace knows "
                f"(spectrace has {', '.join(medium_presets())})",
            )
        if g != 0.0:
            context.warn(material.location, 'non-zero "g" ignored with a named medium (as pbrt-v4)')
        table = {"preset": preset}
        g = 0.0
    elif material.find("sigma_a") is not None or material.find("sigma_s") is not None:
        for key, other in (("sigma_a", "sigma_s"), ("sigma_s", "sigma_a")):
            if material.find(other) is None:
                raise error(material.location, f'subsurface "{key}" given without "{other}" (pbrt-v4 needs both)')
        table = {
            "sigma_a": context.spectrum(material, "sigma_a", "medium"),
            "sigma_s": context.spectrum(material, "sigma_s", "medium"),
        }
    elif material.find("reflectance") is not None:
        table = _from_reflectance(context, material, g)
    else:
        table = {"sigma_a": {"rgb": PBRT_DEFAULT_SIGMA_A}, "sigma_s": {"rgb": PBRT_DEFAULT_SIGMA_S}}
    if scale != 1.0:
        table["scale"] = scale
    if g != 0.0:
        table["g"] = g
    return table


def _components(context: Context, material: Entity, key: str, role: str, default: float) -> list[float]:
    """A `reflectance` or `mfp` as three RGB components (a number is grey); spectra are refused in one line."""
    value = context.spectrum(material, key, role)
    if value is None:
        return [default] * 3
    if "rgb" in value:
        return [float(v) for v in value["rgb"]]
    if "value" in value:
        return [float(value["value"])] * 3
    parameter = material.find(key)
    assert parameter is not None
    raise error(parameter.location, f'"{parameter.label()}": spectrace inverts an rgb or a number here, not a spectrum')


def _image_mean(context: Context, parameter) -> list[float]:
    """The mean linear RGB of the `imagemap` a spectrum texture parameter names, with a warning: a medium is the
    same throughout, where pbrt varies the albedo over the surface."""
    from spectrace.interop.pbrt.textures import texture_table
    from spectrace.io.images import read_texture_image
    from spectrace.textures.bitmap import decoded

    name = str(parameter.values[0])
    texture = context.scene.textures.get(("spectrum", name))
    if texture is None:
        raise error(parameter.location, f"\"{parameter.label()}\" names '{shown(name)}', which no Texture defined")
    table = texture_table(context, texture.entity)
    if "texture" not in table and ("rgb" in table or "value" in table):  # a constant (or a missing image's stand-in)
        return [float(v) for v in table["rgb"]] if "rgb" in table else [float(table["value"])] * 3
    if table.get("texture") != "bitmap" or str(table["file"]).startswith(f"{context.mesh_folder}/"):
        raise error(parameter.location, f'"{parameter.label()}": spectrace takes an imagemap of a file here')
    values, encoded = read_texture_image((context.toml_folder / table["file"]).resolve(), str(texture.entity.location))
    linear = decoded(values, encoded, bool(table.get("raw", False)))
    mean = np.clip(linear.reshape(-1, linear.shape[-1]).mean(axis=0), 0.0, 1.0)
    rgb = [float(v) for v in (np.repeat(mean, 3) if len(mean) == 1 else mean[:3])]
    context.warn(
        parameter.location,
        f'"{parameter.label()}" imported as its image\'s mean colour {[round(v, 4) for v in rgb]} '
        "(spectrace's medium is the same throughout)",
    )
    return rgb


def _from_reflectance(context: Context, material: Entity, g: float) -> dict:
    texture = material.find("reflectance", "texture")
    if texture is not None:
        reflectance = _image_mean(context, texture)
    else:
        reflectance = _components(context, material, "reflectance", "albedo", 0.0)
    mfp = _components(context, material, "mfp", "medium", 1.0)
    if min(mfp) <= 0.0:
        parameter = material.find("mfp")
        raise error(parameter.location if parameter else material.location, f'"mfp" must be > 0, got {mfp}')
    eta = _eta(context, material)
    albedo = [single_scattering_albedo(r, g, eta) for r in reflectance]
    sigma_s = [a / m for a, m in zip(albedo, mfp, strict=True)]
    sigma_a = [(1.0 - a) / m for a, m in zip(albedo, mfp, strict=True)]
    return {"sigma_a": {"rgb": sigma_a}, "sigma_s": {"rgb": sigma_s}}


def single_scattering_albedo(effective_albedo: float, g: float, eta: float) -> float:
    """The albedo α in [0, 1] whose photon beam diffusion effective albedo ρ_eff(α; g, eta) is `effective_albedo`
    (ρ_eff grows with α: Brent's root finding); a reflectance at or above ρ_eff(1) gives α = 1."""
    from scipy.optimize import brentq

    if effective_albedo <= 0.0:
        return 0.0
    if effective_albedo >= effective_albedo_of(1.0, g, eta):
        return 1.0
    return float(brentq(lambda a: effective_albedo_of(a, g, eta) - effective_albedo, 0.0, 1.0, xtol=1e-12))


@cache
def _radii() -> tuple[np.ndarray, np.ndarray]:
    """Radii (in mean free paths) and trapezoid weights of ∫ f(r) dr over [0, ∞): 0, then geometric out to 2·10⁴,
    far past the profile's reach for α up to 1 − 10⁻⁵ (ρ_eff within 3·10⁻⁴ of a grid three times as fine)."""
    r = np.concatenate([[0.0], np.geomspace(1e-4, 2e4, 500)])
    weights = np.zeros_like(r)
    weights[1:] += 0.5 * np.diff(r)
    weights[:-1] += 0.5 * np.diff(r)
    return r, weights


def _fresnel(cos_i: np.ndarray, eta: float) -> np.ndarray:
    """Unpolarised Fresnel reflectance for light arriving at cos_i > 0 on an interface to relative index eta."""
    sin2_t = np.maximum(0.0, 1.0 - cos_i * cos_i) / (eta * eta)
    cos_t = np.sqrt(np.maximum(0.0, 1.0 - sin2_t))
    parallel = (eta * cos_i - cos_t) / (eta * cos_i + cos_t)
    perpendicular = (cos_i - eta * cos_t) / (cos_i + eta * cos_t)
    return np.where(sin2_t >= 1.0, 1.0, 0.5 * (parallel**2 + perpendicular**2))


@cache
def _fresnel_moments(eta: float) -> tuple[float, float]:
    """∫₀¹ F(μ) μ^i dμ, i = 1, 2, for light inside the medium (index eta) meeting its boundary to air."""
    mu = (np.arange(20000) + 0.5) / 20000
    inside = _fresnel(mu, 1.0 / eta)
    return float(np.mean(inside * mu)), float(np.mean(inside * mu * mu))


def _depths(sigma_t: float, count: int = 256) -> np.ndarray:
    """Depths at the midpoints of `count` equal-probability slices of the exponential density σt e^{−σt z}: the mean
    of a function over them is its expectation under that density."""
    return -np.log1p(-(np.arange(count) + 0.5) / count) / sigma_t


@cache
def effective_albedo_of(albedo: float, g: float, eta: float) -> float:
    """ρ_eff = ∫₀^∞ 2πr [S_ss(r) + S_ms(r)] dr of the photon beam diffusion profile of a medium with σt = 1,
    σs = albedo, Henyey–Greenstein g, under a smooth boundary of index eta."""
    r, weights = _radii()
    r = r[:, None]
    sigma_s, sigma_a = albedo, 1.0 - albedo
    # Multiple scattering: a dipole for each depth zr of the beam, zr distributed as the reduced extinction.
    reduced_s = sigma_s * (1.0 - g)
    reduced_t = sigma_a + reduced_s
    reduced_albedo = reduced_s / reduced_t
    diffusion = (2.0 * sigma_a + reduced_s) / (3.0 * reduced_t * reduced_t)  # Grosjean's D
    transport = math.sqrt(max(sigma_a / diffusion, 0.0))
    moment1, moment2 = _fresnel_moments(eta)
    extrapolation = -2.0 * diffusion * (1.0 + 3.0 * moment2) / (1.0 - 2.0 * moment1)
    c_phi, c_e = 0.25 * (1.0 - 2.0 * moment1), 0.5 * (1.0 - 3.0 * moment2)
    z_real = _depths(reduced_t)[None, :]
    z_virtual = 2.0 * extrapolation - z_real
    d_real = np.sqrt(r * r + z_real * z_real)
    d_virtual = np.sqrt(r * r + z_virtual * z_virtual)
    decay_real, decay_virtual = np.exp(-transport * d_real), np.exp(-transport * d_virtual)
    fluence = (decay_real / d_real - decay_virtual / d_virtual) / (4.0 * math.pi * diffusion)
    flux = (
        z_real * (1.0 + transport * d_real) * decay_real / d_real**3
        - z_virtual * (1.0 + transport * d_virtual) * decay_virtual / d_virtual**3
    ) / (4.0 * math.pi)
    kappa = 1.0 - np.exp(-2.0 * reduced_t * (d_real + z_real))
    multiple = np.mean(kappa * reduced_albedo**2 * (c_phi * fluence + c_e * flux), axis=1)
    # Single scattering: along the refracted beam, beyond the depth where the path to r leaves below the critical
    # angle, one scatter toward the exit point (Henyey–Greenstein), transmitted out by Fresnel.
    critical = r * math.sqrt(max(eta * eta - 1.0, 0.0))
    t = critical + _depths(1.0)[None, :]
    distance = np.sqrt(r * r + t * t)
    cos_o = t / distance
    phase = (1.0 - g * g) / (4.0 * math.pi * (1.0 + g * g + 2.0 * g * cos_o) ** 1.5)
    single = np.mean(
        albedo * np.exp(-(distance + critical)) / distance**2 * phase * (1.0 - _fresnel(cos_o, 1.0 / eta)) * cos_o,
        axis=1,
    )
    profile = 2.0 * math.pi * r[:, 0] * (single + multiple)
    return float(np.sum(profile * weights))
