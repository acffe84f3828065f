"""What every light module shares: the scene model's `Light`, its Light rows (kernels/types.h) and the checks of
positions and directions."""

import numpy as np

from spectrace.core import limits
from spectrace.core.contract import NO_TEXTURE
from spectrace.errors import SpectraceError
from spectrace.spectral.table import SpectrumTable


class Light:
    """A `[[lights]]` light of the scene model: what every light module's MODEL is (a shape's AreaEmitter is not)."""


def light_row(
    light_type: int,
    spectrum_offset: int,
    *,
    triangle: int = -1,
    area: float = 0.0,
    two_sided: bool = False,
    position=(0.0, 0.0, 0.0),
    direction=(0.0, 0.0, 1.0),
    direction_w: float = 0.0,
    scale: float = 1.0,
    cos_falloff_start: float = 1.0,
    cos_cutoff: float = 1.0,
    map_fields=(0, 0, 0, 0),
    texel_offset: int = 0,
    texture: int = NO_TEXTURE,
    linear_falloff: bool = False,
) -> tuple:
    """One Light row as a tuple in LIGHT_DTYPE's field order; pmf is filled in once every light's power is known."""
    return (
        (*position, 1.0),
        (*direction, direction_w),
        light_type,
        triangle,
        spectrum_offset,
        scale,
        0.0,
        area,
        int(two_sided),
        cos_falloff_start,
        cos_cutoff,
        *map_fields,
        texel_offset,
        texture,
        int(linear_falloff),
    )


class LightRows:
    """The rows the lights write, each with an estimate of the power it emits (for picking lights in proportion to
    it), and the buffers they share: the spectrum table and one texel buffer for every image a light shows."""

    def __init__(
        self, table: SpectrumTable, scene_radius: float, texel_chunks: list[np.ndarray] | None = None, textures=None
    ):
        from spectrace.textures import TextureRows

        self.table = table
        self.scene_radius = scene_radius
        self.rows: list[tuple] = []
        self.power: list[float] = []
        self.environment_light = -1  # index of the environment's row, or -1
        self.map_cdf = np.zeros(2, np.float32)  # the environment map's sampling CDFs (kernels/environment.cl)
        # The texel buffer, which material textures share (spectrace.textures.TextureRows): a dummy texel first.
        self.texel_chunks = texel_chunks if texel_chunks is not None else [np.zeros((1, 4), np.float32)]
        # The texture rows of the images area lights show (the scene's, which the materials' textures share).
        self.textures = textures if textures is not None else TextureRows(table, self.texel_chunks)

    def add(self, row: tuple, power: float, environment: bool = False) -> None:
        if environment:
            self.environment_light = len(self.rows)
        self.rows.append(row)
        self.power.append(power)

    def add_texels(self, rgb: np.ndarray) -> int:
        """Appends an (height, width, 3) image to the texel buffer; its offset there."""
        offset = sum(len(c) for c in self.texel_chunks)
        chunk = np.zeros((rgb.shape[0] * rgb.shape[1], 4), np.float32)
        chunk[:, :3] = np.maximum(rgb.reshape(-1, 3), 0.0)
        self.texel_chunks.append(chunk)
        return offset


def unit_direction(
    vector, where: str | None, message: str = "direction must not be zero"
) -> tuple[float, float, float]:
    v = np.asarray(vector, float)
    norm = np.linalg.norm(v)
    if not norm > 0:
        raise SpectraceError(message, where=where)
    x, y, z = v / norm
    return float(x), float(y), float(z)


def check_position(position, where: str) -> None:
    """A position's coordinates within the renderer's limits (core/limits.py)."""
    if problem := limits.coordinates_problem(position):
        raise SpectraceError(f"position has {problem}", where=where)
