"""`coatedconductor`: a dielectric coat over a metal with a slab of medium between, pbrt-v4's coatedconductor and its
stochastic layered evaluation (docs/materials.md, kernels/bsdf_coatedconductor.cl, kernels/layered.cl)."""

from dataclasses import dataclass

import numpy as np

from spectrace.core.parameters import ROUGHNESS_RANGE, Parameter, Range, reflectance
from spectrace.errors import SpectraceError
from spectrace.materials import layered
from spectrace.materials.layered import LayeredMaterial
from spectrace.materials.opaque import smooth_everywhere
from spectrace.spectral import spectrum_input
from spectrace.spectral.metals import COMMON_METALS, metal_ior, metal_names_doc
from spectrace.spectral.spectrum import Spectrum
from spectrace.spectral.spectrum_input import SpectrumLike
from spectrace.spectral.table import SpectrumTable
from spectrace.textures import number_or_texture

NAME = "coatedconductor"
MITSUBA_PLUGINS: tuple[str, ...] = ()
MITSUBA_NONE = "Mitsuba 3 has no layered BSDF over a conductor"
PBRT_MATERIALS = ("coatedconductor",)
DEFAULT_METAL = "Cu"  # pbrt-v4's default conductor
# pbrt-v4 clamps a reflectance below 1, where its k = 2√r / √(1 − r) is finite.
MAX_REFLECTANCE = 0.9999
# Its texture's index is in the row's reflectance_texture, which a coated conductor's reflectance (turned into η and
# k on the host) leaves free.
CONDUCTOR_ROUGHNESS = Parameter(
    "conductor_roughness",
    "float",
    default=0.0,
    range=ROUGHNESS_RANGE,
    doc="GGX α of the metal under the coat",
    textured=True,
    texture_field="reflectance_texture",
)
PARAMETERS = (
    Parameter(
        "metal",
        "metal",
        default=None,
        default_doc=f'`"{DEFAULT_METAL}"` where no `eta`, `k` or `reflectance` is given',
        type_doc=metal_names_doc(),
        doc="the metal's measured complex index of refraction (`spectra/metals/`); give one of `metal`, `eta` and "
        "`k`, or `reflectance`",
    ),
    Parameter(
        "eta",
        "spectrum",
        "dimensionless",
        default=None,
        range=Range(0.0),
        doc="real part η(λ) of the metal's index relative to the outside (the walk divides it by the coat's `ior`)",
    ),
    Parameter("k", "spectrum", "dimensionless", default=None, range=Range(0.0), doc="imaginary part k(λ)"),
    reflectance(
        None,
        "the metal's normal-incidence reflectance in air instead of η and k: η = 1, k = 2√r / √(1 − r) (pbrt-v4's "
        "mapping; r at most 0.9999)",
        default_doc="—",
    ),
    CONDUCTOR_ROUGHNESS,
    *layered.COAT_PARAMETERS,
)


@dataclass(frozen=True)
class CoatedConductorMaterial(LayeredMaterial):
    """A metal of complex index η(λ) + i k(λ) (relative to the outside), GGX α `conductor_roughness`, under the coat
    and slab of layered.COAT_PARAMETERS."""

    eta: Spectrum
    k: Spectrum
    conductor_roughness: float = 0.0  # or a one-channel texture
    ior: float = 1.5
    roughness: float = 0.0  # or a one-channel texture
    thickness: float = 0.01
    albedo: Spectrum | None = None
    g: float = 0.0
    max_depth: int = 10
    samples: int = 1

    @property
    def base_is_smooth(self) -> bool:
        return smooth_everywhere(self.conductor_roughness)


MODEL = CoatedConductorMaterial


def source_problem(metal, eta, k, colour) -> str | None:
    """Why the given metal / eta / k / reflectance do not name one metal, or None (none given: copper)."""
    given = [
        name
        for name, value in (("metal", metal), ("eta and k", eta if eta is not None else k), ("reflectance", colour))
        if value is not None
    ]
    if len(given) > 1:
        return f"give one of metal, eta and k, or reflectance, not {' and '.join(given)}"
    if (eta is None) != (k is None):
        return "give both eta and k"
    return None


def check_spec(spec) -> None:
    if problem := source_problem(spec.metal, spec.eta, spec.k, spec.reflectance):
        raise ValueError(problem)


SPEC_CHECKS = (check_spec,)


def reflectance_optical_constants(colour: Spectrum) -> tuple[Spectrum, Spectrum]:
    """η = 1 and k = 2√r / √(1 − r): a metal whose normal-incidence reflectance in air is r (pbrt-v4's)."""
    r = np.clip(colour.values, 0.0, MAX_REFLECTANCE)
    source = "k = 2√r/√(1 − r) of a reflectance (pbrt-v4)"
    return Spectrum.constant(1.0), Spectrum(2.0 * np.sqrt(r) / np.sqrt(1.0 - r), name=colour.name, source=source)


def _optical_constants(metal, eta, k, colour, where) -> tuple[Spectrum, Spectrum]:
    if colour is not None:
        return reflectance_optical_constants(colour)
    if eta is not None and k is not None:
        return eta, k
    return metal_ior(metal or DEFAULT_METAL, where=where)


def from_spec(spec, resolver, key: str) -> CoatedConductorMaterial:
    eta = resolver.optical_constant(spec.eta, f"{key}.eta", positive=False) if spec.eta is not None else None
    k = resolver.optical_constant(spec.k, f"{key}.k", positive=False) if spec.k is not None else None
    colour = (
        resolver.spectrum(spec.reflectance, f"{key}.reflectance", emission=False)
        if spec.reflectance is not None
        else None
    )
    eta, k = _optical_constants(spec.metal, eta, k, colour, resolver.where(f"{key}.metal"))
    return CoatedConductorMaterial(
        eta,
        k,
        conductor_roughness=resolver.number_or_texture(
            spec.conductor_roughness, f"{key}.conductor_roughness", CONDUCTOR_ROUGHNESS
        ),
        **layered.layers_from_spec(spec, resolver, key),
    )


def make(
    metal: str | None = None,
    *,
    eta: SpectrumLike | None = None,
    k: SpectrumLike | None = None,
    reflectance: SpectrumLike | None = None,
    conductor_roughness=0.0,
    ior: float = 1.5,
    roughness=0.0,
    thickness: float = 0.01,
    albedo: SpectrumLike | None = None,
    g: float = 0.0,
    max_depth: int = 10,
    samples: int = 1,
) -> CoatedConductorMaterial:
    """A metal under a dielectric coat (pbrt-v4's coatedconductor): the metal as `metal` ("Au", "Ag", "Cu", "Al"
    or another of the conductor's names; none given: copper), `eta` and `k` (relative to the outside) or
    `reflectance` (pbrt's η = 1, k = 2√r/√(1 − r)), of GGX α `conductor_roughness`; the coat of index `ior` and GGX
    α `roughness` (each roughness a number or a grey texture); between them a slab `thickness` mean free paths thick
    of single-scattering `albedo` (none: it only absorbs) and Henyey-Greenstein `g`. The BSDF is a random walk of at
    most `max_depth` events, `samples` walks per evaluation."""
    if problem := source_problem(metal, eta, k, reflectance):
        raise SpectraceError(problem)
    eta_spectrum = (
        spectrum_input.optical_constant(spectrum_input.spectrum(eta), False, "eta") if eta is not None else None
    )
    k_spectrum = spectrum_input.optical_constant(spectrum_input.spectrum(k), False, "k") if k is not None else None
    colour = spectrum_input.reflectance(reflectance, "reflectance") if reflectance is not None else None
    optical = _optical_constants(metal, eta_spectrum, k_spectrum, colour, "metal")
    return CoatedConductorMaterial(
        *optical,
        conductor_roughness=number_or_texture(conductor_roughness, CONDUCTOR_ROUGHNESS),
        **layered.make_layers(ior, roughness, thickness, albedo, g, max_depth, samples),
    )


def write_row(row: np.ndarray, material: CoatedConductorMaterial, table: SpectrumTable) -> None:
    row["eta_offset"] = table.add(material.eta)
    row["k_offset"] = table.add(material.k)
    layered.write_layers(row, material, table, base_roughness=material.conductor_roughness)


def from_pbrt(context, material) -> dict | None:
    """pbrt-v4's coatedconductor: `interface.eta`, `interface.roughness` (or u/v), `conductor.eta` and `conductor.k`
    (default copper) or `reflectance`, `conductor.roughness` (or u/v), thickness, albedo, g, maxdepth, nsamples, each
    with pbrt-v4's default; roughnesses remapped as pbrt remaps them."""
    table: dict = {"type": NAME}
    colour = context.spectrum(material, "reflectance", "albedo")
    eta = context.spectrum(material, "conductor.eta", "unbounded")
    k = context.spectrum(material, "conductor.k", "unbounded")
    if colour is not None:
        if eta is not None or k is not None:
            raise context.error(material.location, "coatedconductor: give conductor.eta and conductor.k or reflectance")
        table["reflectance"] = colour
    else:
        eta = eta or {"spectrum": f"metals/{DEFAULT_METAL}:eta"}
        k = k or {"spectrum": f"metals/{DEFAULT_METAL}:k"}
        if "rgb" in eta or "rgb" in k:
            from spectrace.materials.conductor import uplifted_optical_constants

            context.notes.append(
                f"{material.location}: a conductor's eta and k given as rgb are uplifted to smooth spectra"
            )
            eta, k = uplifted_optical_constants(eta, k, str(material.location))
        metals = {s.get("spectrum", "").split(":")[0] for s in (eta, k)}
        metal = next(iter(metals)).removeprefix("metals/") if len(metals) == 1 else ""
        table |= {"metal": metal} if metal in COMMON_METALS else {"eta": eta, "k": k}
    if conductor := context.rough(material, "conductor."):
        table["conductor_roughness"] = conductor["roughness"]
    return table | layered.pbrt_layers(context, material, "interface.eta") | context.rough(material, "interface.")
