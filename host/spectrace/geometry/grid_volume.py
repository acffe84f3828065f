"""Voxel grids of a heterogeneous medium's density (and albedo): the model (`GridVolume`), Mitsuba's `.vol` files,
and the block the kernels read (kernels/medium_grid.cl).

A grid of nx × ny × nz values, x fastest, fills the unit box [0, 1]³ with one value at each voxel's centre;
`to_world` places that box in the scene. Lookups are trilinear, clamped at the box's faces (Mitsuba 3's
`gridvolume`), and the density is 0 outside the box. The kernels sample free flights against a coarse grid of
per-cell maxima (the majorant grid, pbrt-v4's GridMedium), built here.
"""

from __future__ import annotations

import struct
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Protocol

import numpy as np

from spectrace.core.equality import fields_equal
from spectrace.errors import SpectraceError

if TYPE_CHECKING:
    from numpy.typing import ArrayLike

    from spectrace.spectral.spectrum import Spectrum
    from spectrace.spectral.table import SpectrumTable

# Majorant cells per axis (fewer where the grid has fewer voxels): pbrt-v4's 16³.
MAJORANT_CELLS = 16
# The most voxels one grid may have: its floats go into the device's spectrum table, indexed by 32-bit offsets.
MAX_VOXELS = 256**3

# What a grid holds outside its box (kernels/medium_grid.cl's GRID_OUTSIDE_*): nothing, its faces' values, copies.
GRID_OUTSIDE = ("empty", "clamp", "repeat")
# Room for float32 rounding between the host's bound of a colour voxel's spectrum and the kernel's evaluation of it.
_SPECTRUM_BOUND_MARGIN = 1.0 + 1e-5

_VOL_HEADER = struct.Struct("<3sBiiiii6f")
_VOL_FLOAT32 = 1
_VOL_UINT8 = 3


@dataclass(frozen=True, eq=False)
class GridVolume:
    """density: float32 (nz, ny, nx), ≥ 0, multiplying the medium's coefficients, or shaped (nz, ny, nx, 3) (a
    linear sRGB colour ≥ 0 uplifted per voxel: σt varies with λ voxel by voxel); albedo: None, shaped (nz, ny, nx)
    in [0, 1] (a grey albedo), or (nz, ny, nx, 3) (a linear sRGB albedo in [0, 1], uplifted per voxel), multiplying
    its scattering coefficient; to_world: 4×4 map of the unit box into the scene; outside: what the grid holds
    outside its box (GRID_OUTSIDE: "empty", the medium ends there; "clamp", its faces' values; "repeat", copies of
    itself), where "clamp" and "repeat" make the grid fill all space (an albedo over a homogeneous σt); emission:
    None or (nz, ny, nx) ≥ 0, scaling a glowing medium's emission spectrum per voxel (pbrt-v4's Lescale grid);
    temperature: None or (nz, ny, nx) in kelvin ≥ 0, making its emission a blackbody's normalised to its peak."""

    density: np.ndarray
    to_world: np.ndarray
    albedo: np.ndarray | None = None
    outside: str = "empty"
    emission: np.ndarray | None = None
    temperature: np.ndarray | None = None

    __eq__ = fields_equal


def box_matrix(p0: ArrayLike, p1: ArrayLike) -> np.ndarray:
    """The 4×4 map of the unit box onto the axis-aligned box from corner p0 to corner p1."""
    low, high = np.asarray(p0, np.float64), np.asarray(p1, np.float64)
    matrix = np.diag([*(high - low), 1.0])
    matrix[:3, 3] = low
    return matrix


def grid_problem(values: np.ndarray, what: str, upper: float | None = None, signed: bool = False) -> str | None:
    """Why `values` cannot be a grid of `what` (a message), or None."""
    if values.ndim != 3 or min(values.shape) < 1:
        return f"{what} must be a 3-D grid of at least one voxel, got shape {values.shape}"
    if values.size > MAX_VOXELS:
        return f"{what} has {values.size} voxels, more than the {MAX_VOXELS} a grid may have"
    if not np.all(np.isfinite(values)):
        return f"{what} holds values that are not finite"
    if not signed and np.any(values < 0.0):
        return f"{what} holds negative values (the smallest is {float(values.min()):g})"
    if upper is not None and np.any(values > upper):
        return f"{what} holds values above {upper:g} (the largest is {float(values.max()):g})"
    return None


def make_grid(
    density: np.ndarray,
    to_world: np.ndarray,
    albedo: np.ndarray | None = None,
    where: str | None = None,
    outside: str = "empty",
    emission: np.ndarray | None = None,
    temperature: np.ndarray | None = None,
) -> GridVolume:
    """A checked GridVolume; `where` names the input in the one-line errors."""
    density = np.ascontiguousarray(density, np.float32)
    if outside not in GRID_OUTSIDE:
        raise SpectraceError(f"outside must be one of {', '.join(GRID_OUTSIDE)}, got {outside!r}", where=where)
    if density.ndim == 4 and density.shape[3] == 3:
        for channel in range(3):
            if problem := grid_problem(density[..., channel], "the density"):
                raise SpectraceError(problem, where=where)
    elif problem := grid_problem(density, "the density"):
        raise SpectraceError(problem, where=where)
    voxels = density.shape[:3]
    if albedo is not None:
        albedo = np.ascontiguousarray(albedo, np.float32)
        if albedo.shape not in (voxels, (*voxels, 3)):
            raise SpectraceError(
                f"the albedo grid's shape {albedo.shape} is neither the density's {voxels} nor that with 3"
                " colour channels",
                where=where,
            )
        channels = albedo.reshape(*voxels, -1)
        for channel in range(channels.shape[3]):
            if problem := grid_problem(channels[..., channel], "the albedo", upper=1.0):
                raise SpectraceError(problem, where=where)
    scalars = {}
    for name, grid in (("emission", emission), ("temperature", temperature)):
        if grid is not None:
            grid = np.ascontiguousarray(grid, np.float32)
            if grid.shape != voxels:
                raise SpectraceError(f"the {name} grid's shape {grid.shape} is not the density's {voxels}", where=where)
            # a temperature at or below 0 K (pbrt-v4's offset may take it there) glows nowhere
            if problem := grid_problem(grid, f"the {name}", signed=name == "temperature"):
                raise SpectraceError(problem, where=where)
        scalars[name] = grid
    to_world = np.asarray(to_world, np.float64)
    if to_world.shape != (4, 4) or not np.all(np.isfinite(to_world)) or abs(np.linalg.det(to_world[:3, :3])) < 1e-12:
        raise SpectraceError("the grid's placement must be an invertible 4×4 transform", where=where)
    return GridVolume(density=density, to_world=to_world, albedo=albedo, outside=outside, **scalars)


def read_vol(path: Path, where: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Mitsuba's volume file: 'VOL', version 3, encoding (1 float32, 3 uint8 as value/255), resolution x y z,
    channel count, bounding box (min xyz, max xyz), then the values, x fastest, channels interleaved. Returns the
    values as (nz, ny, nx, channels) float32 and the box's two corners; `where` names the file and key."""
    name = Path(path).name
    try:
        data = Path(path).read_bytes()
    except OSError as exc:
        raise SpectraceError(f"cannot read the volume file '{name}': {exc.strerror or exc}", where=where) from None
    if len(data) < _VOL_HEADER.size or data[:3] != b"VOL":
        raise SpectraceError(
            f"'{name}' is not a Mitsuba volume file (it does not start with 'VOL' and a full header)", where=where
        )
    _, version, encoding, nx, ny, nz, channels, *box = _VOL_HEADER.unpack_from(data)
    if version != 3:
        raise SpectraceError(f"volume file version {version} (spectrace reads version 3)", where=where)
    if encoding not in (_VOL_FLOAT32, _VOL_UINT8):
        raise SpectraceError(f"volume encoding {encoding} (spectrace reads 1: float32 and 3: uint8)", where=where)
    if min(nx, ny, nz, channels) < 1:
        raise SpectraceError(f"volume resolution {nx}×{ny}×{nz} with {channels} channels", where=where)
    count = nx * ny * nz * channels
    if nx * ny * nz > MAX_VOXELS:
        raise SpectraceError(f"the volume has {nx * ny * nz} voxels, more than {MAX_VOXELS}", where=where)
    dtype = np.dtype("<f4") if encoding == _VOL_FLOAT32 else np.dtype("u1")
    expected = _VOL_HEADER.size + count * dtype.itemsize
    if len(data) != expected:
        raise SpectraceError(
            f"the volume file '{name}' has {len(data)} bytes; its header ({nx}×{ny}×{nz}×{channels}) needs {expected}",
            where=where,
        )
    values = np.frombuffer(data, dtype, count, _VOL_HEADER.size).astype(np.float32)
    if encoding == _VOL_UINT8:
        values /= 255.0
    return values.reshape(nz, ny, nx, channels), np.array(box[:3]), np.array(box[3:])


def vol_bytes(values: np.ndarray, p0=(0.0, 0.0, 0.0), p1=(1.0, 1.0, 1.0)) -> bytes:
    """A float32 volume file of `values` shaped (nz, ny, nx) or (nz, ny, nx, channels)."""
    values = np.asarray(values, np.float32)
    if values.ndim == 3:
        values = values[..., None]
    nz, ny, nx, channels = values.shape
    header = _VOL_HEADER.pack(b"VOL", 3, _VOL_FLOAT32, nx, ny, nz, channels, *map(float, (*p0, *p1)))
    return header + values.astype("<f4").tobytes()


def majorant_grid(density: np.ndarray, cells: int = MAJORANT_CELLS) -> np.ndarray:
    """(mz, my, mx) maxima: each cell holds the largest voxel that a trilinear lookup inside the cell reads (the
    voxels whose centres lie within one voxel of it), so it bounds the density everywhere in the cell."""
    shape = density.shape
    counts = [min(cells, n) for n in shape]
    result = np.zeros(counts, np.float32)
    ranges = []
    for n, m in zip(shape, counts, strict=True):
        axis = []
        for c in range(m):
            # Lookup coordinate q = u·n − ½ over the cell's u in [c/m, (c+1)/m], clamped to [0, n − 1].
            low = int(np.clip(np.floor(c * n / m - 0.5), 0, n - 1))
            high = int(np.clip(np.ceil((c + 1) * n / m - 0.5), 0, n - 1))
            axis.append((low, high + 1))
        ranges.append(axis)
    for k, (z0, z1) in enumerate(ranges[0]):
        slab = density[z0:z1]
        for j, (y0, y1) in enumerate(ranges[1]):
            row = slab[:, y0:y1].max(axis=(0, 1))
            for i, (x0, x1) in enumerate(ranges[2]):
                result[k, j, i] = row[x0:x1].max()
    return result


def colour_bound(block: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per voxel of a colour block (albedo_block's form): the largest value its spectrum takes at any wavelength
    of the grid (the sigmoid at the largest value of its quadratic over t in [−1, 1]: an end, or the vertex
    inside; the sigmoid rises monotonically), with a margin for the kernel's float32 rounding, and its s."""
    from spectrace.spectral.uplift import sigmoid

    a, b, c = (block[..., i].astype(np.float64) for i in range(3))
    candidates = [a - b + c, a + b + c]
    with np.errstate(divide="ignore", invalid="ignore"):
        vertex = np.where(a != 0.0, -b / (2.0 * a), 2.0)
    inside = np.abs(vertex) <= 1.0
    candidates.append(np.where(inside, (a * vertex + b) * vertex + c, -np.inf))
    peak = np.maximum.reduce(candidates)
    return (sigmoid(peak) * _SPECTRUM_BOUND_MARGIN).astype(np.float32), block[..., 3]


def grid_majorant(grid: GridVolume, density_block: np.ndarray) -> np.ndarray:
    """The majorant grid of `grid`: per cell, a bound on its density at every wavelength (majorant_grid); a colour
    density's cell takes its largest s times the largest value of its voxels' spectra, since the lookup multiplies
    a mix of the spectra by a mix of the s. A grid that fills all space has one cell, for all of it."""
    cells = MAJORANT_CELLS if grid.outside == "empty" else 1
    nz, ny, nx = grid.density.shape[:3]
    if grid.density.ndim == 3:
        return majorant_grid(grid.density, cells)
    spectrum_peak, scale = colour_bound(density_block.reshape(nz, ny, nx, 4))
    return majorant_grid(spectrum_peak, cells) * majorant_grid(scale, cells)


def albedo_block(albedo: np.ndarray) -> np.ndarray:
    """An albedo (or density) grid as the kernels read it: a grey one as is; a colour one as 4 floats a voxel,
    Mitsuba 3's spectral gridvolume's form: the sigmoid coefficients (dimensionless, fitted as a texture's texels
    are, Jakob & Hanika 2019) of the colour divided by s = 2 × its largest channel, then s. The kernel evaluates the
    eight voxels' spectra at the path's wavelengths, interpolates those values and s apart, and multiplies them, as
    Mitsuba does: a mix of spectra has the mix of their colours, while mixing the coefficients would not (the
    sigmoid is not linear). Dividing by s keeps every fit away from the saturated ends; the spectrum's shape, not
    only its colour, then matches Mitsuba's, which matters after many scatterings (the albedo's powers)."""
    if albedo.ndim == 3:
        return albedo
    from spectrace.spectral.rgb_texture import reflectance_coefficients
    from spectrace.textures.storage import dimensionless

    rgb = albedo.reshape(-1, 3).astype(np.float64)
    scale = 2.0 * rgb.max(axis=1)
    coefficients = dimensionless(reflectance_coefficients(rgb / np.maximum(scale, 1e-8)[:, None]))
    return np.ascontiguousarray(np.concatenate([coefficients, scale[:, None]], axis=1), np.float32)


def add_grid_block(table: SpectrumTable, grid: GridVolume) -> int:
    """Store the grid in the scene's float table (kernels/medium_grid.cl's layout) and return its header's offset."""
    density_block = albedo_block(grid.density)
    density = table.add_block(density_block)
    albedo = table.add_block(albedo_block(grid.albedo)) if grid.albedo is not None else -1
    majorant = grid_majorant(grid, density_block)
    majorant_offset = table.add_block(majorant)
    to_unit = np.linalg.inv(grid.to_world)[:3].astype(np.float32).ravel()
    nz, ny, nx = grid.density.shape[:3]
    mz, my, mx = majorant.shape
    channels = 3 if grid.albedo is not None and grid.albedo.ndim == 4 else 1
    density_channels = 3 if grid.density.ndim == 4 else 1
    outside = GRID_OUTSIDE.index(grid.outside)
    emission, temperature = (table.add_block(g) if g is not None else -1 for g in (grid.emission, grid.temperature))
    ints = np.array(
        [nx, ny, nz, mx, my, mz, density, albedo, majorant_offset, channels, density_channels, outside]
        + [emission, temperature],
        np.int32,
    )
    return table.add_block(np.concatenate([to_unit, ints.view(np.float32)]))


class MediumFields(Protocol):
    """What a medium's device row is made of (spectrace.scene.model.Medium)."""

    @property
    def sigma_a(self) -> Spectrum: ...
    @property
    def sigma_s(self) -> Spectrum: ...
    @property
    def g(self) -> float: ...
    @property
    def density(self) -> GridVolume | None: ...
    @property
    def emission(self) -> Spectrum | None: ...


def medium_row(medium: MediumFields, table: SpectrumTable) -> tuple[int, int, float, int, int]:
    """A medium's device row (MEDIUM_DTYPE): its spectra's offsets, g, its grid's block (-1: homogeneous) and its
    emission spectrum's offset (-1: it does not glow)."""
    sigma_a, sigma_s = table.add(medium.sigma_a), table.add(medium.sigma_s)
    grid = add_grid_block(table, medium.density) if medium.density is not None else -1
    emission = table.add(medium.emission) if medium.emission is not None else -1
    return (sigma_a, sigma_s, float(medium.g), grid, emission)
