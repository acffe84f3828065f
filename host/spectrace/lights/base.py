"""What every light module shares: the scene model's `Light`, what a light module holds (`LightPlugin`, which mypy
checks each module of spectrace.lights.LIGHTS against), the device light types (`DeviceLight`), its Light rows
(kernels/types.h) and the checks of positions and directions."""

import hashlib
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np

from spectrace.core import limits
from spectrace.core.contract import NO_TEXTURE
from spectrace.core.parameters import Parameter
from spectrace.core.registry import Plugin
from spectrace.errors import SpectraceError
from spectrace.spectral.table import SpectrumTable


class Light:
    """A `[[lights]]` light of the scene model: what every light module's MODEL is (a shape's AreaEmitter is not)."""


# The kinds of device light (pbrt-v4's LightType, with its two delta kinds told apart by where they are): which
# functions a light's kernel file defines and which parts of the kernels' shared code (kernels/lights.cl,
# light_emission.cl, bdpt.cl) it goes through.
#  - "area": emits from a surface; its file samples a point on it and states the densities of that point;
#  - "position": at one point (a delta position); its file samples and states directions leaving it;
#  - "infinite": at infinity, a direction toward it sampled (a delta direction, or a distribution over directions).
DEVICE_LIGHT_KINDS = ("area", "position", "infinite")


@dataclass(frozen=True)
class DeviceLight:
    """One type of Light row, a light as the kernels see it: its code (Light.type, LIGHT_<NAME>) is its position
    among every light module's DEVICE_TYPES (spectrace.lights.DEVICE_LIGHTS), its kernel file
    kernels/light_<name>.cl, which defines the functions of its `kind` (kernels/lights.cl says which)."""

    name: str
    kind: str

    def __post_init__(self) -> None:
        if self.kind not in DEVICE_LIGHT_KINDS:
            raise ValueError(f"device light {self.name!r}: kind {self.kind!r} is not one of {DEVICE_LIGHT_KINDS}")

    @property
    def NAME(self) -> str:  # noqa: N802 (a plugin's name, as a module's NAME)
        return self.name

    @property
    def kernel_file(self) -> str:
        return f"light_{self.name}.cl"


class LightSource(Plugin, Protocol):
    """What every module that writes Light rows states: the device light types of its rows. A `[[lights]]` light
    (LightPlugin) and a shape's emitter (spectrace.lights.area) both are one."""

    @property
    def DEVICE_TYPES(self) -> tuple[DeviceLight, ...]: ...  # noqa: N802 (a module constant)


class LightPlugin(LightSource, Protocol):
    """What a `[[lights]]` light module holds: its parameter table, its resolved dataclass (MODEL), `from_spec` (a
    validated scene-file table to the dataclass), `write_rows` (its Light rows and power, through LightRows), whether
    it is an environment (a scene has at most one), its Python API constructor `make` (`spectrace.<API_NAME>`, or
    None where it has none) and its Mitsuba 3 and pbrt-v4 mappings (MITSUBA_PLUGINS with `from_mitsuba`, or
    MITSUBA_NONE saying why there is none; PBRT_LIGHTS, `from_pbrt`). Optional: SPEC_CHECKS (rules spanning several
    keys) and `to_mitsuba` (the export, where Mitsuba can do the same)."""

    @property
    def PARAMETERS(self) -> tuple[Parameter, ...]: ...  # noqa: N802

    @property
    def MODEL(self) -> type[Light]: ...  # noqa: N802

    @property
    def IS_ENVIRONMENT(self) -> bool: ...  # noqa: N802

    @property
    def MITSUBA_PLUGINS(self) -> tuple[str, ...]: ...  # noqa: N802

    @property
    def API_NAME(self) -> str | None: ...  # noqa: N802

    @property
    def make(self) -> Callable[..., Light] | None: ...

    def from_spec(self, spec: Any, resolver: Any, key: str) -> Light: ...

    def write_rows(self, light: Any, out: "LightRows") -> None: ...

    @property
    def PBRT_LIGHTS(self) -> tuple[str, ...]: ...  # noqa: N802

    def from_pbrt(self, context: Any, light: Any, matrix: Any) -> dict | None: ...


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
        self,
        table: SpectrumTable,
        scene_radius: float,
        codes: Mapping[str, int],
        texel_chunks: list[np.ndarray] | None = None,
        textures=None,
    ):
        from spectrace.textures import TextureRows

        self.codes = codes  # each device light type's Light.type code (spectrace.lights.DEVICE_LIGHTS.codes)
        self.table = table
        self.scene_radius = scene_radius
        self.rows: list[tuple] = []
        self.power: list[float] = []
        self.environment_light = -1  # index of the environment's row, or -1
        self.map_cdf = np.zeros(2, np.float32)  # the environment map's sampling CDFs (kernels/light_environment_map.cl)
        # The texel buffer, which material textures share (spectrace.textures.TextureRows): a dummy texel first.
        self.texel_chunks = texel_chunks if texel_chunks is not None else [np.zeros((1, 4), np.float32)]
        # The texture rows of the images area lights show (the scene's, which the materials' textures share).
        self.textures = textures if textures is not None else TextureRows(table, self.texel_chunks)

    def code(self, device: DeviceLight) -> int:
        """The Light.type code of a row of `device`'s type."""
        return self.codes[device.name]

    def add(self, row: tuple, power: float, environment: bool = False) -> None:
        if environment:
            self.environment_light = len(self.rows)
        self.rows.append(row)
        self.power.append(power)

    def add_texels(self, rgb: np.ndarray) -> int:
        """Puts an (height, width, 3) image in the texel buffer (see add_chunk); its offset there."""
        chunk = np.zeros((rgb.shape[0] * rgb.shape[1], 4), np.float32)
        chunk[:, :3] = np.maximum(rgb.reshape(-1, 3), 0.0)
        return self.add_chunk(chunk)

    def add_chunk(self, chunk: np.ndarray) -> int:
        """Puts (n, 4) float32 texels of a light (an image, a sampling table) in the texel buffer unless the same
        numbers are there from a light already; their offset in float4s. A live session's edit writes a light's rows
        again, and so its images and tables: found by their content, they are stored once however often that is,
        and a kernel reading the first copy reads the same bits as from a fresh build."""
        chunk = np.ascontiguousarray(chunk, np.float32)
        key = (chunk.shape, hashlib.blake2b(chunk.tobytes(), digest_size=32).digest())
        stored = self.textures.light_texels
        offset = stored.get(key)
        if offset is None:
            offset = sum(len(c) for c in self.texel_chunks)
            self.texel_chunks.append(chunk)
            stored[key] = offset
        return offset


def vector3(value, what: str) -> tuple[float, float, float]:
    """Three finite numbers given to the Python API, as a tuple; anything else is an error naming `what`."""
    array = np.asarray(value, np.float64)
    if array.shape != (3,) or not np.all(np.isfinite(array)):
        raise SpectraceError(f"expected 3 finite numbers, got {value!r}", where=what)
    return float(array[0]), float(array[1]), float(array[2])


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
