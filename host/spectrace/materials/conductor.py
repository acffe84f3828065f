"""`conductor`: a metal of complex index η + ik, smooth or GGX-rough (docs/materials.md,
kernels/bsdf_conductor.cl)."""

from dataclasses import dataclass

import numpy as np

from spectrace.core.contract import MICROFACET_DISTRIBUTIONS
from spectrace.core.parameters import (
    DEFAULT_DISTRIBUTION,
    ROUGHNESS_RANGE,
    Parameter,
    Range,
    check_distribution,
    distribution,
    roughness,
    specular_tint,
)
from spectrace.errors import SpectraceError
from spectrace.materials.opaque import RoughOpaque, smooth_everywhere
from spectrace.spectral import spectrum_input
from spectrace.spectral.metals import COMMON_METALS, METALS, metal_ior, metal_names_doc
from spectrace.spectral.spectrum import Spectrum
from spectrace.spectral.spectrum_input import SpectrumLike
from spectrace.spectral.table import SpectrumTable
from spectrace.textures import number_or_texture, reflectance_or_texture

NAME = "conductor"
MITSUBA_PLUGINS = ("conductor", "roughconductor")
PBRT_MATERIALS = ("conductor",)
ROUGHNESS = roughness(0.0, "microfacet α (along the surface's dp/du when `roughness_v` is given); 0 = polished")
# The second width of an anisotropic lobe: its Material row keeps it in `ior` and its texture in
# `transmittance_offset`, fields a conductor has no other use for (kernels/bsdf_conductor.cl).
ROUGHNESS_V = Parameter(
    "roughness_v",
    "float",
    default=None,
    default_doc="`roughness`",
    range=ROUGHNESS_RANGE,
    doc="microfacet α along the bitangent n × t, t the surface's dp/du (or the mesh file's tangent): with "
    "`roughness` ≠ `roughness_v` the lobe is anisotropic (Mitsuba's `alpha_v`, pbrt's `vroughness`)",
    textured=True,
    texture_field="transmittance_offset",
)
DISTRIBUTION = distribution()
PARAMETERS = (
    Parameter(
        "metal",
        "metal",
        default=None,
        default_doc="—",
        type_doc=metal_names_doc(),
        doc="measured complex index of refraction η + ik (`spectra/metals/`): every conductor name of Mitsuba 3 "
        '(`"none"`: η = 0, k = 1, a perfect mirror); give `metal` or both `eta` and `k`',
    ),
    Parameter(
        "eta",
        "spectrum",
        "dimensionless",
        default=None,
        range=Range(0.0),
        doc="real part η(λ) of the metal's index of refraction relative to the outside (η = 0, k = 1 reflects "
        'everything at every angle: Mitsuba\'s material "none")',
    ),
    Parameter(
        "k",
        "spectrum",
        "dimensionless",
        default=None,
        range=Range(0.0),
        doc="imaginary part k(λ) (extinction coefficient)",
    ),
    ROUGHNESS,
    ROUGHNESS_V,
    DISTRIBUTION,
    specular_tint("multiplies the Fresnel reflectance (an artistic control; physical metals leave it out)"),
)


@dataclass(frozen=True)
class ConductorMaterial(RoughOpaque):
    """Metal of complex index of refraction η(λ) + i k(λ) relative to the outside, smooth or rough (GGX or
    Beckmann microfacets); the Fresnel reflectance is multiplied by `specular_tint` when given."""

    eta: Spectrum
    k: Spectrum
    roughness: float = ROUGHNESS.number_default  # or a one-channel texture
    specular_tint: Spectrum | None = None  # or a texture
    distribution: str = DEFAULT_DISTRIBUTION
    roughness_v: float | None = None  # or a texture; None: isotropic, `roughness` along both axes

    @property
    def is_anisotropic(self) -> bool:
        return self.roughness_v is not None

    @property
    def is_delta(self) -> bool:
        return smooth_everywhere(self.roughness) and (self.roughness_v is None or smooth_everywhere(self.roughness_v))


MODEL = ConductorMaterial


def source_problem(metal, eta, k) -> str | None:
    """Why the given metal / eta / k do not name one index of refraction, or None."""
    if metal is not None and (eta is not None or k is not None):
        return "give either metal or eta and k, not both"
    if metal is None and (eta is None or k is None):
        return f"give metal ({', '.join(COMMON_METALS)}, ...: spectra/metals/) or both eta and k"
    return None


def anisotropic_roughness(roughness, roughness_v):
    """`roughness_v` where it differs from `roughness` (an anisotropic lobe), else None: an isotropic lobe keeps
    the isotropic kernel code, and so its renders."""
    if roughness_v is None or roughness_v is roughness:
        return None
    if isinstance(roughness_v, (int, float)) and isinstance(roughness, (int, float)) and roughness_v == roughness:
        return None
    return roughness_v


def check_spec(spec) -> None:
    if problem := source_problem(spec.metal, spec.eta, spec.k):
        raise ValueError(problem)


SPEC_CHECKS = (check_spec,)


def from_spec(spec, resolver, key: str) -> ConductorMaterial:
    if spec.metal is not None:
        eta, k = metal_ior(spec.metal, where=resolver.where(f"{key}.metal"))
    else:
        eta = resolver.optical_constant(spec.eta, f"{key}.eta", positive=False)
        k = resolver.optical_constant(spec.k, f"{key}.k", positive=False)
    tint = (
        resolver.spectrum_or_texture(spec.specular_tint, f"{key}.specular_tint", "spectrum")
        if spec.specular_tint is not None
        else None
    )
    roughness = resolver.number_or_texture(spec.roughness, f"{key}.roughness", ROUGHNESS)
    roughness_v = (
        resolver.number_or_texture(spec.roughness_v, f"{key}.roughness_v", ROUGHNESS_V)
        if spec.roughness_v is not None
        else None
    )
    return ConductorMaterial(
        eta,
        k,
        roughness=roughness,
        specular_tint=tint,
        distribution=spec.distribution,
        roughness_v=anisotropic_roughness(roughness, roughness_v),
    )


def make(
    metal: str | None = None,
    *,
    eta: SpectrumLike | None = None,
    k: SpectrumLike | None = None,
    roughness: float = ROUGHNESS.number_default,
    distribution: str = DISTRIBUTION.default,  # type: ignore[assignment]
    specular_tint: SpectrumLike | None = None,
    roughness_v: float | None = None,
) -> ConductorMaterial:
    """A metal: `metal` ("Au", "Ag", "Cu", "Al" or any other conductor name of Mitsuba 3: measured η and k) or
    explicit `eta` and `k` spectra (complex index of refraction η + ik relative to the outside, dimensionless);
    `roughness` is the microfacet α (0 = smooth mirror-like metal; a number or a grey texture) of the
    `distribution` ("ggx" or "beckmann");
    `specular_tint` (a reflectance or a texture) multiplies the Fresnel term; `roughness_v` (a number or a grey
    texture) makes the lobe anisotropic, `roughness` then its α along the surface's dp/du and `roughness_v` along
    the bitangent."""
    if problem := source_problem(metal, eta, k):
        raise SpectraceError(problem)
    if metal is not None:
        eta_spectrum, k_spectrum = metal_ior(metal, where="metal")
    else:
        assert eta is not None and k is not None  # source_problem has refused every other combination
        eta_spectrum = spectrum_input.optical_constant(spectrum_input.spectrum(eta), False, "eta")
        k_spectrum = spectrum_input.optical_constant(spectrum_input.spectrum(k), False, "k")
    tint = reflectance_or_texture(specular_tint, "specular_tint") if specular_tint is not None else None
    alpha = number_or_texture(roughness, ROUGHNESS)
    alpha_v = number_or_texture(roughness_v, ROUGHNESS_V) if roughness_v is not None else None
    return ConductorMaterial(
        eta_spectrum,
        k_spectrum,
        roughness=alpha,
        specular_tint=tint,
        distribution=check_distribution(distribution),
        roughness_v=anisotropic_roughness(alpha, alpha_v),
    )


def write_row(row: np.ndarray, material: ConductorMaterial, table: SpectrumTable) -> None:
    row["eta_offset"] = table.add(material.eta)
    row["k_offset"] = table.add(material.k)
    if material.specular_tint is not None:
        row["reflectance_offset"] = table.add(material.specular_tint)
    row["alpha"] = material.roughness
    row["distribution"] = MICROFACET_DISTRIBUTIONS.index(material.distribution)
    if material.roughness_v is not None:
        # The frame along dp/du that orients the lobe (kernels/material.cl, material_frame); α along it in `alpha`.
        row["tangent_frame"] = 1
        row["ior"] = material.roughness_v


def from_mitsuba(importer, bsdf, properties) -> dict | None:
    """A conductor (or, for Mitsuba's material "none", a mirror) table; None when not representable (recorded)."""
    tint = None
    if "specular_reflectance" in properties:
        tint = importer.spectrum(properties["specular_reflectance"], "specular_reflectance")
        if tint is None:
            return None
    alphas = importer.roughnesses(bsdf, properties) if importer.kind(bsdf) == "roughconductor" else (0.0, 0.0)
    if alphas is None:
        return None
    roughness, roughness_v = alphas
    if roughness_v == roughness:
        roughness_v = None
    if "eta" in properties or "k" in properties:
        if "eta" not in properties or "k" not in properties:
            raise importer.fail(bsdf, "a conductor needs both eta and k")
        eta, k = importer.spectrum(properties["eta"], "eta"), importer.spectrum(properties["k"], "k")
        if eta is None or k is None:
            return None
        if "rgb" in eta or "rgb" in k:
            eta, k = _rgb_optical_constants(importer, bsdf, eta, k)
        table = {"type": "conductor", "eta": eta, "k": k}
    else:
        material = importer.text(properties["material"]) if "material" in properties else "none"
        if material == "none":  # Mitsuba's default: η = 0, k = 1, whose Fresnel term is 1 at every angle
            if roughness == 0.0 and roughness_v is None:  # a perfect mirror scaled by specular_reflectance
                return {"type": "mirror", "reflectance": tint or {"value": 1.0}}
            table = {"type": "conductor", "eta": {"value": 0.0}, "k": {"value": 1.0}}
        elif material not in METALS:
            importer.unsupported_plugin(bsdf, f" with material '{material}' (spectrace has {', '.join(METALS)})")
            return None
        else:
            table = {"type": "conductor", "metal": material}
    if roughness != 0.0 or roughness_v is not None:  # a number above 0, or a texture
        table["roughness"] = roughness
        if roughness_v is not None:  # Mitsuba's u is the surface's dp/du, as spectrace's frame
            table["roughness_v"] = roughness_v
        if (kind := importer.distribution(bsdf, properties)) != DEFAULT_DISTRIBUTION:
            table["distribution"] = kind
    if tint is not None:
        table["specular_tint"] = tint
    return table


def from_pbrt(context, material) -> dict | None:
    """pbrt-v4's conductor by eta and k (default: copper); a named metal spectrace has is written as `metal`."""
    if (reflectance := material.find("reflectance")) is not None:
        raise context.error(
            reflectance.location, 'a conductor given by "reflectance": spectrace\'s conductor takes eta and k'
        )
    eta = context.spectrum(material, "eta", "unbounded") or {"spectrum": "metals/Cu:eta"}
    k = context.spectrum(material, "k", "unbounded") or {"spectrum": "metals/Cu:k"}
    if "rgb" in eta or "rgb" in k:
        # As the Mitsuba import takes <rgb> η and k (docs/mitsuba.md, "Conductors given in RGB").
        context.notes.append(
            f"{material.location}: a conductor's eta and k given as rgb are uplifted to smooth spectra"
        )
        eta, k = uplifted_optical_constants(eta, k, str(material.location))
    table: dict[str, object] = {"type": "conductor"}
    metals = {s.get("spectrum", "").split(":")[0] for s in (eta, k)}
    metal = next(iter(metals)).removeprefix("metals/") if len(metals) == 1 else ""
    if metal in COMMON_METALS:  # pbrt's other named metals (CuZn, MgO, TiO2) stay spectra, as pbrt names them
        table["metal"] = metal
    else:
        table |= {"eta": eta, "k": k}
    if "glass" in eta or "glass" in k:
        raise context.error(material.location, "a glass's index given as a conductor's eta or k")
    return table | context.rough_anisotropic(material)


# Wavelengths at which an uplifted η or k is written into the imported scene (smooth curves: 5 nm loses nothing).
_UPLIFT_STEP_NM = 5.0


def _rgb_optical_constants(importer, bsdf, eta: dict, k: dict) -> tuple[dict, dict]:
    """η and k given as <rgb> (Mitsuba's RGB variants use them per channel) as spectra (uplifted_optical_constants),
    with a note."""
    importer.notes.append(
        f"{importer.at(bsdf)}: {bsdf.label()}: eta and k given as rgb are uplifted to smooth spectra "
        "(docs/mitsuba.md, 'Conductors given in RGB')"
    )
    return uplifted_optical_constants(eta, k, importer.where(bsdf))


def uplifted_optical_constants(eta: dict, k: dict, where: str | None) -> tuple[dict, dict]:
    """A conductor's η and k where either is an rgb, as tabulated spectra: with both an rgb or a number,
    `conductor_from_rgb` (the normal-incidence colour an RGB renderer shows, exactly); one beside a measured
    spectrum is uplifted alone (`uplift_unbounded`). The Mitsuba and the pbrt importer share it."""
    from spectrace.spectral.grid import GRID_MAX_NM, GRID_MIN_NM
    from spectrace.spectral.uplift import conductor_from_rgb, uplift_unbounded

    def triple(spectrum: dict) -> list[float] | None:
        if "rgb" in spectrum:
            return spectrum["rgb"]
        return [spectrum["value"]] * 3 if list(spectrum) == ["value"] else None

    wavelengths = np.arange(GRID_MIN_NM, GRID_MAX_NM + 0.5, _UPLIFT_STEP_NM)
    eta_rgb, k_rgb = triple(eta), triple(k)
    spectra: tuple
    if eta_rgb is not None and k_rgb is not None:
        spectra = conductor_from_rgb(eta_rgb, k_rgb, where=where)
    else:
        spectra = tuple(
            uplift_unbounded(spectrum["rgb"], where) if "rgb" in spectrum else None for spectrum in (eta, k)
        )
    tables = [
        original if spectrum is None else {"values": [[float(w), float(spectrum.evaluate(w))] for w in wavelengths]}
        for original, spectrum in zip((eta, k), spectra)
    ]
    return tables[0], tables[1]


def to_mitsuba(material: ConductorMaterial, exporter) -> dict:
    """Mitsuba's `conductor` or `roughconductor` with the same η, k (as spectra on spectrace's grid), α (αu and αv
    of an anisotropic lobe) and distribution, sampling visible normals as Mitsuba does by default; `twosided`
    because spectrace's conductor reflects on both faces and Mitsuba's is black from behind."""
    from spectrace.textures import is_texture

    entry: dict = {"eta": exporter.spectrum(material.eta), "k": exporter.spectrum(material.k)}
    if material.specular_tint is not None:
        entry["specular_reflectance"] = exporter.spectrum(material.specular_tint)
    if is_texture(material.roughness) or is_texture(material.roughness_v):
        raise exporter.refuse("a conductor with textured roughness is not exported yet")
    if material.is_delta:
        entry["type"] = "conductor"
    else:
        entry.update(type="roughconductor", distribution=material.distribution)
        if material.roughness_v is None:
            entry["alpha"] = float(material.roughness)
        else:  # Mitsuba's u is dp/du, as spectrace's frame
            entry.update(alpha_u=float(material.roughness), alpha_v=float(material.roughness_v))
    return {"type": "twosided", "bsdf": entry}
