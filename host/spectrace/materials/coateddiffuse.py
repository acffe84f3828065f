"""`coateddiffuse`: a dielectric coat over a Lambertian base with a slab of medium between, pbrt-v4's coateddiffuse
and its stochastic layered evaluation (docs/materials.md, kernels/bsdf_coateddiffuse.cl, kernels/layered.cl)."""

from dataclasses import dataclass

import numpy as np

from spectrace.core.parameters import reflectance
from spectrace.materials import layered
from spectrace.materials.layered import LayeredMaterial
from spectrace.spectral.spectrum import Spectrum
from spectrace.spectral.spectrum_input import SpectrumLike
from spectrace.spectral.table import SpectrumTable
from spectrace.textures import reflectance_or_texture

NAME = "coateddiffuse"
MITSUBA_PLUGINS: tuple[str, ...] = ()
MITSUBA_NONE = "Mitsuba 3's coated diffuse is its plastic (a closed form), which plastic.py maps"
PBRT_MATERIALS = ("coateddiffuse",)
PARAMETERS = (
    reflectance(0.5, "albedo of the Lambertian base under the coat", textured=True),
    *layered.COAT_PARAMETERS,
)


@dataclass(frozen=True)
class CoatedDiffuseMaterial(LayeredMaterial):
    """A Lambertian base of albedo `reflectance` under the coat and slab of layered.COAT_PARAMETERS."""

    reflectance: Spectrum  # or a texture (spectrace.textures)
    ior: float = 1.5
    roughness: float = 0.0  # or a one-channel texture
    thickness: float = 0.01
    albedo: Spectrum | None = None
    g: float = 0.0
    max_depth: int = 10
    samples: int = 1

    base_is_smooth = False


MODEL = CoatedDiffuseMaterial


def from_spec(spec, resolver, key: str) -> CoatedDiffuseMaterial:
    return CoatedDiffuseMaterial(
        resolver.spectrum_or_texture(spec.reflectance, f"{key}.reflectance", "spectrum"),
        **layered.layers_from_spec(spec, resolver, key),
    )


def make(
    reflectance: SpectrumLike = 0.5,
    *,
    ior: float = 1.5,
    roughness: float = 0.0,
    thickness: float = 0.01,
    albedo: SpectrumLike | None = None,
    g: float = 0.0,
    max_depth: int = 10,
    samples: int = 1,
) -> CoatedDiffuseMaterial:
    """A Lambertian base of albedo `reflectance` (a reflectance or a texture) under a dielectric coat (pbrt-v4's
    coateddiffuse): the coat of index `ior` and GGX α `roughness`; between them a slab `thickness` mean free paths
    thick of single-scattering `albedo` (none: it only absorbs) and Henyey-Greenstein `g`. The BSDF is a random walk
    of at most `max_depth` events, `samples` walks per evaluation."""
    return CoatedDiffuseMaterial(
        reflectance_or_texture(reflectance, "reflectance"),
        **layered.make_layers(ior, roughness, thickness, albedo, g, max_depth, samples),
    )


def write_row(row: np.ndarray, material: CoatedDiffuseMaterial, table: SpectrumTable) -> None:
    row["reflectance_offset"] = table.add(material.reflectance)
    layered.write_layers(row, material, table)


def from_pbrt(context, material) -> dict | None:
    """pbrt-v4's coateddiffuse: reflectance (default 0.5), `eta`, `roughness` (or u/v), thickness, albedo, g,
    maxdepth, nsamples, each with pbrt-v4's default; the roughness (a number or a float texture) remapped as pbrt
    remaps it."""
    table: dict = {"type": NAME, "reflectance": context.reflectance(material, "reflectance", 0.5)}
    return table | layered.pbrt_layers(context, material, "eta") | context.rough(material)
