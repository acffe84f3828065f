"""`wrinkled`: pbrt-v4's turbulence (Pharr, Jakob & Humphreys, 4th ed., 10.6.3 "Noise Idioms and Spectral
Synthesis"), a solid texture: Σ_{i<octaves} ω^i |noise(1.99^i p)| + 0.2 ω^octaves of Perlin noise at the point p in
the texture's space (textures/solid.py), a number in [0, about 2] (ω ½), the same at every wavelength: a mix's
amount, or a number wherever its range fits. docs/textures.md."""

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

NAME = "wrinkled"
API_NAME = "wrinkled_texture"
COMPOSITE = False
SOLID = True
PARAMETERS = (OCTAVES, ROUGHNESS, TRANSFORM)
MITSUBA_PLUGINS: tuple[str, ...] = ()
MITSUBA_NONE = "Mitsuba 3 has no procedural textures"
PBRT_TEXTURES = ("wrinkled",)


@dataclass(frozen=True, eq=False)
class WrinkledTexture(SolidTexture):
    source: str = "wrinkled"

    def value_range(self) -> tuple[float, float]:
        return 0.0, NOISE_BOUND * octave_sum(self.roughness, self.octaves) + 0.2 * self.roughness**self.octaves


MODEL = WrinkledTexture


def from_spec(spec, resolver, key: str) -> WrinkledTexture:
    return WrinkledTexture(spec.octaves, spec.roughness, spec_matrix(spec, resolver, key))


def make(*, octaves: int = 8, roughness: float = 0.5, transform=()) -> WrinkledTexture:
    """pbrt-v4's wrinkled: turbulence of `octaves` octaves of |Perlin noise|, each ω = `roughness` times the weight
    of the one before, in the space `transform` (steps as a scene file writes them) places."""
    return WrinkledTexture(
        int(checked(octaves, OCTAVES, "octaves")),
        float(checked(roughness, ROUGHNESS, "roughness")),
        to_texture_matrix(transform, None),
    )


def device_solid(texture: WrinkledTexture, table) -> object:
    return device_floats(texture)


def from_pbrt(context, texture, uv) -> dict:
    """pbrt-v4's `wrinkled` (a float texture): its octaves, roughness and declaring transform."""
    return pbrt_solid(context, texture, NAME)
