"""What the stochastic layered materials share (`coatedconductor`, `coateddiffuse`: pbrt-v4's LayeredBxDF, a
dielectric coat over a base with a slab of medium between, evaluated by a random walk, kernels/layered.cl): the
coat's and the slab's parameters, their row fields, and their pbrt-v4 keys."""

import numpy as np

from spectrace.core.contract import IOR_CONSTANT
from spectrace.core.parameters import Parameter, Range, reflectance, roughness
from spectrace.materials.opaque import Opaque, smooth_everywhere
from spectrace.spectral import spectrum_input
from spectrace.spectral.glasses import glass
from spectrace.spectral.spectrum import Spectrum
from spectrace.spectral.spectrum_input import SpectrumLike
from spectrace.spectral.table import SpectrumTable
from spectrace.textures import number_or_texture

# A coat this close to index 1 passes light straight (kernels/layered.cl, layered_top_smooth).
INDEX_MATCHED = 1e-4
IOR = Parameter(
    "ior",
    "float",
    "dimensionless",
    default=1.5,
    range=Range(1.0, 4.0),
    doc="index of refraction of the coat relative to the outside (1: no interface, light passes straight in)",
)
ROUGHNESS = roughness(0.0, "GGX α of the coat's interface; 0 = smooth")
THICKNESS = Parameter(
    "thickness",
    "float",
    "mean free paths",
    default=0.01,
    range=Range(0.0),
    doc="thickness of the slab between coat and base, in units of its mean free path (σt = 1): light crossing it "
    "at θ is attenuated by exp(−thickness / |cos θ|) where `albedo` is 0",
)
ALBEDO = reflectance(
    None,
    "single-scattering albedo of the slab (0: it only absorbs)",
    name="albedo",
    default_doc="0",
)
G = Parameter(
    "g",
    "float",
    "dimensionless",
    default=0.0,
    range=Range(-1.0, 1.0, low_open=True, high_open=True),
    doc="Henyey-Greenstein mean cosine of the slab's scattering",
)
MAX_DEPTH = Parameter(
    "max_depth", "int", default=10, range=Range(1.0, 100.0), doc="scattering events a random walk may take"
)
SAMPLES = Parameter(
    "samples", "int", default=1, range=Range(1.0, 64.0), doc="random walks each evaluation of the BSDF averages"
)
# The coat's and slab's keys, after each material's base keys.
COAT_PARAMETERS = (IOR, ROUGHNESS, THICKNESS, ALBEDO, G, MAX_DEPTH, SAMPLES)
_PARAMETER = {p.name: p for p in COAT_PARAMETERS}


class LayeredMaterial(Opaque):
    """A layered material: besides its base's fields, the coat's and slab's (COAT_PARAMETERS: `ior`, `roughness`,
    `thickness`, `albedo` (None: 0), `g`, `max_depth`, `samples`), and whether its base is smooth (a subclass
    states base_is_smooth)."""

    ior: float
    roughness: float  # or a one-channel texture
    thickness: float
    albedo: Spectrum | None
    g: float
    max_depth: int
    samples: int

    @property
    def base_is_smooth(self) -> bool:
        raise NotImplementedError

    @property
    def coat_is_smooth(self) -> bool:
        """A delta lobe everywhere: smooth at every point, or index-matched (light passes straight)."""
        return smooth_everywhere(self.roughness) or abs(self.ior - 1.0) < INDEX_MATCHED

    @property
    def is_delta(self) -> bool:
        # Only delta lobes: smooth coat, smooth base and a slab that does not scatter (kernels/layered.cl).
        return self.coat_is_smooth and self.base_is_smooth and self.albedo is None

    @property
    def mixes_delta_and_non_delta(self) -> bool:
        # A coat's reflection that is a delta lobe somewhere beside what the base or the slab spreads (SPPM refuses
        # it), as kernels/layered.cl's flags state it.
        textured = not isinstance(self.roughness, (int, float))
        return (self.coat_is_smooth or textured) and not self.is_delta


def layers_from_spec(spec, resolver, key: str) -> dict:
    """The coat's and slab's fields of a layered material from its scene table."""
    albedo = resolver.spectrum(spec.albedo, f"{key}.albedo", emission=False) if spec.albedo is not None else None
    roughness = resolver.number_or_texture(spec.roughness, f"{key}.roughness", ROUGHNESS)
    return _layers(spec.ior, roughness, spec.thickness, albedo, spec.g, spec.max_depth, spec.samples)


def make_layers(
    ior: float, roughness, thickness: float, albedo: SpectrumLike | None, g: float, max_depth, samples
) -> dict:
    """The API's coat and slab keys checked against their ranges (a SpectraceError naming the key)."""
    numbers = {
        name: _PARAMETER[name].check(value) for name, value in (("ior", ior), ("thickness", thickness), ("g", g))
    }
    counts = {n: int(_PARAMETER[n].check(value)) for n, value in (("max_depth", max_depth), ("samples", samples))}
    spectrum = spectrum_input.reflectance(albedo, "albedo") if albedo is not None else None
    return _layers(albedo=spectrum, roughness=number_or_texture(roughness, ROUGHNESS), **numbers, **counts)


def _layers(ior, roughness, thickness, albedo, g, max_depth, samples) -> dict:
    # An albedo of 0 is the slab that only absorbs: no spectrum in the row, and the walk's cheaper branch.
    if albedo is not None and not np.any(albedo.values > 0.0):
        albedo = None
    roughness = float(roughness) if isinstance(roughness, (int, float)) else roughness
    return {
        "ior": float(ior),
        "roughness": roughness,
        "thickness": float(thickness),
        "albedo": albedo,
        "g": float(g),
        "max_depth": int(max_depth),
        "samples": int(samples),
    }


def write_layers(row: np.ndarray, material: LayeredMaterial, table: SpectrumTable, base_roughness: float = 0.0) -> None:
    """The coat's and slab's fields of a layered material's row (kernels/bsdf_coatedconductor.cl lists them); a
    textured roughness is in the row's roughness_texture, its largest α in `alpha` (materials.material_row)."""
    row["ior_model"] = IOR_CONSTANT
    row["ior"] = material.ior
    row["alpha"] = material.roughness
    if material.albedo is not None:
        row["transmittance_offset"] = table.add(material.albedo)
    row["ior_coefficients_b"] = (material.thickness, material.g, base_roughness, 0.0)
    row["ior_coefficients_c"] = (float(material.max_depth), float(material.samples), 0.0, 0.0)


def pbrt_layers(context, material, eta_key: str) -> dict:
    """The coat's and slab's keys of a pbrt-v4 coated material, pbrt-v4's defaults where absent: `eta_key` (a
    number, or a named glass at 550 nm: the coat's index is one number here), thickness, albedo, g, maxdepth,
    nsamples."""
    table: dict = {"ior": 1.5}
    if (parameter := material.find(eta_key, "float", "spectrum", "rgb")) is not None:
        spectrum = context.spectrum(material, eta_key, "unbounded") or {}
        if "value" in spectrum:
            table["ior"] = spectrum["value"]
        elif "glass" in spectrum:
            table["ior"] = round(float(glass(spectrum["glass"]).ior(550.0)), 6)
            context.warn(parameter.location, f'"{parameter.label()}": the coat takes one index, the glass\'s at 550 nm')
        else:
            raise context.error(
                parameter.location, f'"{parameter.label()}": a coat\'s index is a number or a named glass'
            )
    if table["ior"] == 0.0:  # pbrt-v4 reads an index of 0 as 1
        table["ior"] = 1.0
    if problem := IOR.range_problem(table["ior"]):
        raise context.error(material.location, f"{material.label()}: {eta_key}: {problem}")
    table["thickness"] = context.one(material, "thickness", 0.01)
    if (albedo := context.spectrum(material, "albedo", "albedo")) is not None and albedo != {"value": 0.0}:
        table["albedo"] = albedo
    table["g"] = context.one(material, "g", 0.0)
    table["max_depth"] = context.integer(material, "maxdepth", 10, low=1)
    table["samples"] = context.integer(material, "nsamples", 1, low=1)
    for key in ("thickness", "g", "max_depth", "samples"):
        if problem := _PARAMETER[key].range_problem(table[key]):
            raise context.error(material.location, f"{material.label()}: {problem}")
    return table
