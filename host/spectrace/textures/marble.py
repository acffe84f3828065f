"""`marble`: pbrt-v4's marble (Pharr, Jakob & Humphreys, 4th ed., 10.6.5 "Marble"), a solid texture of
reflectance: at the point p in the texture's space (textures/solid.py) times `scale`, t = ½ + ½ sin(p_y + variation
· fbm(p)) picks a place on a cubic Bézier spline through nine fixed greys and blues, 1.5 × the book's colours (in
[0.3, 0.9]). The spline blends the colours' spectra (each uplifted from its sRGB as any reflectance is), where
pbrt-v4 blends their RGB and uplifts the blend: the colours are near grey, where the two agree closely.
docs/textures.md."""

from dataclasses import dataclass

import numpy as np

from spectrace.core.parameters import Parameter, Range
from spectrace.textures.solid import (
    OCTAVES,
    ROUGHNESS,
    TRANSFORM,
    SolidTexture,
    checked,
    device_floats,
    pbrt_solid,
    spec_matrix,
    to_texture_matrix,
)

NAME = "marble"
API_NAME = "marble_texture"
COMPOSITE = False
SOLID = True
SCALE = Parameter(
    "scale",
    "float",
    default=1.0,
    range=Range(0.0, None, low_open=True),
    doc="multiplies the point in the texture's space: the veins' frequency",
)
VARIATION = Parameter(
    "variation",
    "float",
    default=0.2,
    range=Range(0.0, None),
    doc="how far the fbm bends the veins (its weight in the sine's argument)",
)
PARAMETERS = (OCTAVES, ROUGHNESS, SCALE, VARIATION, TRANSFORM)
MITSUBA_PLUGINS: tuple[str, ...] = ()
MITSUBA_NONE = "Mitsuba 3 has no procedural textures"
PBRT_TEXTURES = ("marble",)
# The book's spline colours (sRGB), which the texture scales by 1.5 "to increase variation among colors".
COLOURS = (
    (0.58, 0.58, 0.6), (0.58, 0.58, 0.6), (0.58, 0.58, 0.6), (0.5, 0.5, 0.5), (0.6, 0.59, 0.58),
    (0.58, 0.58, 0.6), (0.58, 0.58, 0.6), (0.2, 0.2, 0.33), (0.58, 0.58, 0.6),
)  # fmt: skip
COLOUR_SCALE = 1.5


def colour_spectra() -> list:
    """The nine spline colours as reflectance spectra (1.5 × the book's sRGB, uplifted)."""
    from spectrace.spectral import spectrum_input

    return [spectrum_input.reflectance(tuple(COLOUR_SCALE * c for c in rgb), "marble") for rgb in COLOURS]


@dataclass(frozen=True, eq=False)
class MarbleTexture(SolidTexture):
    scale: float = 1.0
    variation: float = 0.2
    source: str = "marble"
    channels = 3

    def value_range(self) -> tuple[float, float]:
        values = np.array([spectrum.values for spectrum in colour_spectra()])
        return float(values.min()), float(values.max())


MODEL = MarbleTexture


def _scaled(matrix: np.ndarray, scale: float) -> np.ndarray:
    return np.diag([scale, scale, scale, 1.0]) @ matrix


def from_spec(spec, resolver, key: str) -> MarbleTexture:
    matrix = _scaled(spec_matrix(spec, resolver, key), spec.scale)
    return MarbleTexture(spec.octaves, spec.roughness, matrix, scale=spec.scale, variation=spec.variation)


def make(*, octaves: int = 8, roughness: float = 0.5, scale: float = 1.0, variation: float = 0.2,
         transform=()) -> MarbleTexture:  # fmt: skip
    """pbrt-v4's marble: veins along y, bent by an fbm of `octaves` octaves and ω = `roughness` weighted by
    `variation`, at the point times `scale` in the space `transform` (steps as a scene file writes them) places."""
    scale = float(checked(scale, SCALE, "scale"))
    return MarbleTexture(
        int(checked(octaves, OCTAVES, "octaves")),
        float(checked(roughness, ROUGHNESS, "roughness")),
        _scaled(to_texture_matrix(transform, None), scale),
        scale=scale,
        variation=float(checked(variation, VARIATION, "variation")),
    )


def device_solid(texture: MarbleTexture, table) -> object:
    """Its floats, the nine colours added to the spectrum table."""
    return device_floats(texture, texture.variation, [table.add(spectrum) for spectrum in colour_spectra()])


def from_pbrt(context, texture, uv) -> dict:
    """pbrt-v4's `marble` (a spectrum texture): octaves, roughness, scale (default 1), variation (default 0.2) and
    its declaring transform."""
    table = pbrt_solid(context, texture, NAME)
    table["scale"] = float(context.one(texture, "scale", 1.0))
    table["variation"] = float(context.one(texture, "variation", 0.2))
    return table
