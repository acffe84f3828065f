"""What the solid textures share (fbm, wrinkled, windy, marble: pbrt-v4's 3D textures, Pharr, Jakob & Humphreys,
4th ed., 10.6.3 and 10.6.5; kernels/texture_solid.cl): values defined throughout space, looked up at the surface
point. A `transform` places the texture's space in the scene as a shape's places the shape (pbrt-v4's
TextureMapping3D: the point is taken into texture space by the inverse of the transform in effect where the
texture was declared), so the texture moves with it; the octaves' count and weight ratio ω (`roughness`).

Device form (TextureRows.add): the Texture row's data_offset points at SOLID_FLOATS floats of the texel buffer,
laid out as kernels/texture_solid.cl states."""

from collections.abc import Iterable
from dataclasses import dataclass, field

import numpy as np

from spectrace.core.parameters import Parameter, Range
from spectrace.errors import SpectraceError
from spectrace.textures.mapping import to_texture_matrix
from spectrace.textures.shared import Placement

SOLID_FLOATS = 28  # TEXTURE_SOLID_FLOATS
MARBLE_COLOURS_AT = 16  # SOLID_MARBLE_COLOURS
# Perlin noise lies in [−1, 1] (Perlin 2002; tests/textures/test_procedural_textures.py checks the reference).
NOISE_BOUND = 1.0

TRANSFORM = Parameter(
    "transform",
    "transform",
    default=(),
    doc="places the texture's space in the scene, as a shape's transform places the shape: the texture is looked "
    "up at the surface point taken back through it",
    type_doc="list of transform steps",
    default_doc="`[]`",
)
OCTAVES = Parameter(
    "octaves",
    "int",
    default=8,
    range=Range(1, 32),
    doc="how many octaves of noise are summed, each of 1.99 × the frequency of the one before",
)
ROUGHNESS = Parameter(
    "roughness", "float", default=0.5, range=Range(0.0, 1.0), doc="ω: each octave's weight is ω × the one before"
)


@dataclass(frozen=True, eq=False)
class SolidTexture:
    """A solid texture: `to_texture` (4 × 4) takes a world-space point into texture space."""

    octaves: int = 8
    roughness: float = 0.5
    to_texture: np.ndarray = field(default_factory=lambda: np.eye(4))
    source: str = "solid"
    placement: Placement = Placement()  # unused: a solid texture is not placed by uv

    channels = 1  # the noise textures are numbers, the same at every wavelength

    def value_range(self) -> tuple[float, float]:
        raise NotImplementedError


def octave_sum(omega: float, octaves: int) -> float:
    """Σ_{i<octaves} ω^i: the most that many octaves of noise in [−1, 1] can add up to."""
    return float(sum(omega**i for i in range(octaves)))


def spec_matrix(spec, resolver, key: str) -> np.ndarray:
    return to_texture_matrix(
        [step.model_dump(exclude_none=True) for step in spec.transform], resolver.where(f"{key}.transform")
    )


def checked(value, parameter: Parameter, where: str | None):
    """A number of the API checked against its parameter's range."""
    return parameter.check(value, where or parameter.name)


def device_floats(texture: SolidTexture, variation: float = 0.0, colour_offsets: Iterable[int] = ()) -> np.ndarray:
    """The SOLID_FLOATS floats kernels/texture_solid.cl reads: the world-to-texture matrix's three rows, the octave
    count, ω, marble's variation, and marble's colour offsets as int bits."""
    values = np.zeros(SOLID_FLOATS, np.float32)
    values[:12] = np.asarray(texture.to_texture, np.float64)[:3].ravel()
    values[12:15] = (texture.octaves, texture.roughness, variation)
    offsets = np.asarray(list(colour_offsets), np.int32)
    values.view(np.int32)[MARBLE_COLOURS_AT : MARBLE_COLOURS_AT + len(offsets)] = offsets
    return values


def pbrt_solid(context, texture, name: str) -> dict:
    """A pbrt-v4 solid texture's table: its `octaves` and `roughness` (pbrt's defaults 8 and 0.5) and the transform
    in effect where it was declared (pbrt-v4's TextureMapping3D looks the texture up at that transform's inverse of
    the point)."""
    table: dict = {"texture": name}
    if name != "windy":
        table["octaves"] = context.integer(texture, "octaves", 8, low=1)
        table["roughness"] = float(context.one(texture, "roughness", 0.5))
    declared = next(t for t in context.scene.textures.values() if t.entity is texture)
    matrix = np.asarray(declared.world_from_texture, np.float64)
    if not np.allclose(matrix, np.eye(4)):
        table["transform"] = [{"matrix": matrix.tolist()}]
    return table


def refuse_solid(texture, what: str, where: str | None) -> None:
    """A use that has no surface point to look a solid texture up at."""
    if isinstance(texture, SolidTexture):
        raise SpectraceError(
            f"{what} takes no {texture.source} texture (a solid texture is looked up at the surface point)", where
        )
