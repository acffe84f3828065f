"""`windy`: pbrt-v4's windy waves (Pharr, Jakob & Humphreys, 4th ed., 10.6.3 "Noise Idioms and Spectral
Synthesis"), a solid texture: |fbm(p / 10, ω ½, 3 octaves)| · fbm(p, ω ½, 6 octaves) at the point p in the
texture's space (textures/solid.py): the wind's strength varying slowly, the waves' height quickly; a number in
about [−3.4, 3.4], the same at every wavelength, meant as a mix's amount. No octaves or roughness of its own.
docs/textures.md."""

from dataclasses import dataclass

from spectrace.textures.solid import (
    NOISE_BOUND,
    TRANSFORM,
    SolidTexture,
    device_floats,
    octave_sum,
    pbrt_solid,
    spec_matrix,
    to_texture_matrix,
)

NAME = "windy"
API_NAME = "windy_texture"
COMPOSITE = False
SOLID = True
PARAMETERS = (TRANSFORM,)
MITSUBA_PLUGINS: tuple[str, ...] = ()
MITSUBA_NONE = "Mitsuba 3 has no procedural textures"
PBRT_TEXTURES = ("windy",)


@dataclass(frozen=True, eq=False)
class WindyTexture(SolidTexture):
    source: str = "windy"

    def value_range(self) -> tuple[float, float]:
        bound = NOISE_BOUND**2 * octave_sum(0.5, 3) * octave_sum(0.5, 6)
        return -bound, bound


MODEL = WindyTexture


def from_spec(spec, resolver, key: str) -> WindyTexture:
    return WindyTexture(to_texture=spec_matrix(spec, resolver, key))


def make(*, transform=()) -> WindyTexture:
    """pbrt-v4's windy waves in the space `transform` (steps as a scene file writes them) places."""
    return WindyTexture(to_texture=to_texture_matrix(transform, None))


def device_solid(texture: WindyTexture, table) -> object:
    return device_floats(texture)


def from_pbrt(context, texture, uv) -> dict:
    """pbrt-v4's `windy` (a float texture): its declaring transform."""
    return pbrt_solid(context, texture, NAME)
