"""`fbm`: pbrt-v4's fractional Brownian motion (Pharr, Jakob & Humphreys, 4th ed., 10.6.3 "Noise Idioms and
Spectral Synthesis"), a solid texture: Σ_{i<octaves} ω^i noise(1.99^i p) of Perlin noise at the point p in the
texture's space (textures/solid.py), a number in about [−2, 2] (ω ½), the same at every wavelength. As a reflectance
or roughness it must stay within their bounds, which its negative values do not: it is meant as a mix's amount (a
`mix` texture's or material's, held to [0, 1] there, as pbrt-v4's mix material holds it). docs/textures.md."""

from dataclasses import dataclass

from spectrace.textures.solid import (
    NOISE_BOUND,
    OCTAVES,
    ROUGHNESS,
    TRANSFORM,
    SolidTexture,
    checked,
    device_floats,
    octave_sum,
    pbrt_solid,
    spec_matrix,
    to_texture_matrix,
)

NAME = "fbm"
API_NAME = "fbm_texture"
COMPOSITE = False
SOLID = True
PARAMETERS = (OCTAVES, ROUGHNESS, TRANSFORM)
MITSUBA_PLUGINS: tuple[str, ...] = ()
MITSUBA_NONE = "Mitsuba 3 has no procedural textures"
PBRT_TEXTURES = ("fbm",)


@dataclass(frozen=True, eq=False)
class FbmTexture(SolidTexture):
    source: str = "fbm"

    def value_range(self) -> tuple[float, float]:
        bound = NOISE_BOUND * octave_sum(self.roughness, self.octaves)
        return -bound, bound


MODEL = FbmTexture


def from_spec(spec, resolver, key: str) -> FbmTexture:
    return FbmTexture(spec.octaves, spec.roughness, spec_matrix(spec, resolver, key))


def make(*, octaves: int = 8, roughness: float = 0.5, transform=()) -> FbmTexture:
    """pbrt-v4's fbm: `octaves` octaves of Perlin noise, each ω = `roughness` times the weight of the one before, in
    the space `transform` (steps as a scene file writes them) places."""
    return FbmTexture(
        int(checked(octaves, OCTAVES, "octaves")),
        float(checked(roughness, ROUGHNESS, "roughness")),
        to_texture_matrix(transform, None),
    )


def device_solid(texture: FbmTexture, table) -> object:
    return device_floats(texture)


def from_pbrt(context, texture, uv) -> dict:
    """pbrt-v4's `fbm` (a float texture): its octaves, roughness and declaring transform."""
    return pbrt_solid(context, texture, NAME)
