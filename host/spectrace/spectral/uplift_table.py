"""A table of sigmoid-polynomial coefficients over the RGB cube, so that many colours uplift at once.

`uplift.py` fits one colour at a time (~0.3 ms each); a texture has 10^5..10^6 distinct colours. Here the fit
(the same model, colorimetry and CIELAB residual as `uplift.py`) runs once, batched, on a grid over the cube,
and a colour's coefficients are then a trilinear interpolation in that grid (Jakob & Hanika 2019, section 4).

Parametrisation: a colour is filed under its largest channel i (the "brightness" z = rgb[i]) and the other two
channels divided by it, u = rgb[(i + 1) % 3] / z and v = rgb[(i + 2) % 3] / z, both in [0, 1]. For fixed (i, u, v)
the coefficients change smoothly with z except near its ends, where they grow without bound (a reflectance
reaching 0 or 1 needs an infinitely steep sigmoid), so the z nodes are packed towards both ends by a doubled
smoothstep. Towards black the growth has a closed form: far below zero S(x) ~ 1 / (4 x^2), so scaling the
reflectance by k scales every coefficient by 1 / sqrt(k). The table therefore holds coefficients * sqrt(z), which
tends to a constant there, interpolates that and divides by sqrt(z); below the first non-zero node it holds that
node's value, which is the closed form, instead of interpolating towards a black no finite coefficients reach.

The coefficients are stored in the dimensionless t = (lambda - 595 nm) / 235 nm of `uplift.py`'s solve (their
magnitudes are alike, which trilinear interpolation wants) and converted to lambda in nm on the way out.

The u and v nodes are packed towards both ends (Chebyshev-Lobatto): towards 0 for saturated colours, towards 1
for colours near white. With these choices a 64^3 table reproduces colours (CIELAB 1976 Delta E under D65, the
renderer's colorimetry, measured on 10^5 colours per set): random in the cube max 0.089 (99th percentile 0.049),
the cube's edges and corners max 0.072 (0.055), dark (all channels < 0.02) max 0.13 (0.09), near white (all > 0.98)
max 0.15 (0.03), saturated (one channel < 0.01) max 0.11 (0.06), decoded 8-bit codes max 0.13 (0.06). Uniform
u, v nodes and coefficients interpolated without the sqrt(z) factor gave max 3.4 at 32^3 where these give 0.36.

The build is a batched Levenberg-Marquardt solve, one z slice of all three channels' (u, v) planes at a time,
walking out from the middle slice: each slice starts from its neighbours' solutions (extrapolated in z when that
is closer), so most colours converge in a few steps. It costs about 2.5 CPU-minutes (3 x 64^3 fits), so the table
is cached on disk (`table_path`, 9.4 MB), checked on load (format, the colorimetry it was built for, a SHA-256 of
its values, all finite), and rebuilt when the file is missing or damaged.
"""

from __future__ import annotations

import hashlib
import json
import warnings
from functools import cache
from pathlib import Path

import numpy as np

from spectrace.cache_folder import cache_root
from spectrace.io.atomic import write_atomically
from spectrace.spectral.colorimetry import XYZ_TO_LINEAR_SRGB
from spectrace.spectral.grid import GRID_NM, GRID_SIZE
from spectrace.spectral.uplift import _CENTRE_NM, _HALF_SPAN_NM, _d65_colorimetry

TABLE_RESOLUTION = 64  # nodes per axis: 3 x 64^3 colours, 9.4 MB of float32 coefficients

_FORMAT = 2
_MAGIC = b"spectrace rgb uplift table\n"
_BUILD_DELTA_E = 1e-6  # each node is fitted as tightly as `uplift.py` fits one colour
_MAX_ITERATIONS = 300
_CHUNK = 4096  # colours per batch in the solver: (chunk, 471) float64 arrays stay around 15 MB


def z_nodes(resolution: int) -> np.ndarray:
    """Brightness nodes in [0, 1], packed towards both ends: smoothstep(smoothstep(k / (n - 1)))."""
    s = np.linspace(0.0, 1.0, resolution)
    for _ in range(2):
        s = s * s * (3.0 - 2.0 * s)
    return s


# ---------------------------------------------------------------- batched CIELAB model and solver


def _lab(xyz: np.ndarray) -> np.ndarray:
    model = _d65_colorimetry()
    return model._f(xyz / model.white_xyz) @ model._LAB_MATRIX.T - model._LAB_OFFSET


def target_lab(rgb: np.ndarray) -> np.ndarray:
    """CIELAB (D65 white) of linear sRGB colours (N, 3), through the exact inverse of the lecture's matrix."""
    return _lab(rgb @ _d65_colorimetry().linear_srgb_to_xyz.T)


@cache
def _weights() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    model = _d65_colorimetry()
    # d XYZ_j / d coefficient_k = sum over lambda of S'(x) * weight_j(lambda) * basis_k(lambda): one product
    # with these 9 columns, ordered (j, k).
    slope_weights = (model.xyz_weights[:, :, None] * model.basis[:, None, :]).reshape(GRID_SIZE, 9)
    return np.ascontiguousarray(model.basis.T), np.ascontiguousarray(model.xyz_weights), slope_weights


def lab_of_coefficients(coefficients: np.ndarray, jacobian: bool = False):
    """CIELAB under D65 of the reflectances S(a t^2 + b t + c), coefficients (N, 3) dimensionless; with
    `jacobian`, also d Lab / d coefficients (N, 3, 3)."""
    basis, xyz_weights, slope_weights = _weights()
    x = coefficients @ basis
    root = np.sqrt(1.0 + x * x)
    xyz = (0.5 + 0.5 * x / root) @ xyz_weights
    lab = _lab(xyz)
    if not jacobian:
        return lab
    model = _d65_colorimetry()
    d_xyz = ((0.5 / (root * root * root)) @ slope_weights).reshape(-1, 3, 3)
    ratio = xyz / model.white_xyz
    d_lab_d_xyz = model._LAB_MATRIX[None] * (model._f_derivative(ratio) / model.white_xyz)[:, None, :]
    return lab, d_lab_d_xyz @ d_xyz


def solve(
    target: np.ndarray, start: np.ndarray, delta_e: float = _BUILD_DELTA_E, max_iterations: int = _MAX_ITERATIONS
) -> np.ndarray:
    """Levenberg-Marquardt on the CIELAB residual for each row of `target` (N, 3 Lab), from `start` (N, 3
    dimensionless coefficients), with a damping of its own per colour; the batched twin of `uplift.py`'s solve."""
    coefficients = np.array(start, dtype=np.float64)
    for first in range(0, len(target), _CHUNK):
        rows = slice(first, first + _CHUNK)
        coefficients[rows] = _solve_chunk(target[rows], coefficients[rows], delta_e, max_iterations)
    return coefficients


def _solve_chunk(target: np.ndarray, coefficients: np.ndarray, delta_e: float, max_iterations: int) -> np.ndarray:
    coefficients = coefficients.copy()
    lab, jacobian = lab_of_coefficients(coefficients, jacobian=True)
    residual = lab - target
    error = np.einsum("ij,ij->i", residual, residual)
    damping = np.full(len(target), 1e-3)
    active = np.flatnonzero(error >= delta_e**2)
    for _ in range(max_iterations):
        if active.size == 0:
            break
        j, r = jacobian[active], residual[active]
        normal = np.einsum("nki,nkj->nij", j, j)
        diagonal = np.einsum("nii->ni", normal)
        system = normal + (damping[active, None] * diagonal + 1e-300)[:, :, None] * np.eye(3)
        step = np.linalg.solve(system, -np.einsum("nki,nk->ni", j, r)[:, :, None])[:, :, 0]
        trial = coefficients[active] + step
        trial_lab, trial_jacobian = lab_of_coefficients(trial, jacobian=True)
        trial_residual = trial_lab - target[active]
        trial_error = np.einsum("ij,ij->i", trial_residual, trial_residual)
        better = trial_error < error[active]
        accepted = active[better]
        coefficients[accepted] = trial[better]
        jacobian[accepted] = trial_jacobian[better]
        residual[accepted] = trial_residual[better]
        error[accepted] = trial_error[better]
        damping[accepted] = np.maximum(damping[accepted] * 0.1, 1e-12)
        rejected = active[~better]
        damping[rejected] *= 10.0
        # Converged, or no descent direction left (the best fit the model allows).
        active = active[(error[active] >= delta_e**2) & (damping[active] <= 1e12)]
    return coefficients


# ---------------------------------------------------------------- the table


def ratio_nodes(resolution: int) -> np.ndarray:
    """Nodes of u and v in [0, 1], packed towards both ends (Chebyshev-Lobatto): towards 0, where saturated colours
    need steep sigmoids, and towards 1, where a bright colour nears white."""
    return _ratio_of_position(np.linspace(0.0, 1.0, resolution))


def _ratio_of_position(s: np.ndarray) -> np.ndarray:
    return 0.5 - 0.5 * np.cos(np.pi * s)


def _position_of_ratio(u: np.ndarray) -> np.ndarray:
    return np.arccos(np.clip(1.0 - 2.0 * u, -1.0, 1.0)) / np.pi


def node_colours(resolution: int, z_index: int) -> np.ndarray:
    """Linear sRGB of the nodes of one z slice: (3, n, n, 3), indexed [largest channel, v, u, rgb]."""
    z = z_nodes(resolution)[z_index]
    grid = ratio_nodes(resolution)
    v, u = np.meshgrid(grid, grid, indexing="ij")
    colours = np.empty((3, resolution, resolution, 3))
    for largest in range(3):
        colours[largest, :, :, largest] = z
        colours[largest, :, :, (largest + 1) % 3] = u * z
        colours[largest, :, :, (largest + 2) % 3] = v * z
    return colours


def build_table(resolution: int = TABLE_RESOLUTION) -> np.ndarray:
    """Coefficients (dimensionless) times sqrt(z) at every node: (3, n z, n v, n u, 3), fitted in float64, kept in
    float32 (the rounding leaves the Delta E figures of the module docstring unchanged in their 4 digits).

    The slice z = 0 (black, which no finite coefficients reach) repeats the first non-zero slice;
    `coefficients_from_table` never interpolates towards it.
    """
    table = np.zeros((3, resolution, resolution, resolution, 3))
    middle = resolution // 2
    order = [middle, *range(middle + 1, resolution), *range(middle - 1, 0, -1)]
    for z_index in order:
        colours = node_colours(resolution, z_index).reshape(-1, 3)
        step = 1 if z_index > middle else -1
        if z_index == middle:
            start = np.zeros((len(colours), 3))
        elif abs(z_index - middle) == 1:
            start = table[:, z_index - step].reshape(-1, 3)
        else:
            # The neighbours' solutions extrapolated in z; where that lands further from the target than the
            # nearest neighbour's solution (towards the ends, where the coefficients grow fast), the neighbour's.
            nodes = z_nodes(resolution)
            near, far = table[:, z_index - step].reshape(-1, 3), table[:, z_index - 2 * step].reshape(-1, 3)
            ratio = (nodes[z_index] - nodes[z_index - step]) / (nodes[z_index - step] - nodes[z_index - 2 * step])
            extrapolated = near + ratio * (near - far)
            target = target_lab(colours)
            error_near = np.sum((lab_of_coefficients(near) - target) ** 2, axis=1)
            error_extrapolated = np.sum((lab_of_coefficients(extrapolated) - target) ** 2, axis=1)
            start = np.where((error_extrapolated < error_near)[:, None], extrapolated, near)
        table[:, z_index] = solve(target_lab(colours), start).reshape(3, resolution, resolution, 3)
    table[:, 0] = table[:, 1]
    scale = np.sqrt(np.maximum(z_nodes(resolution), z_nodes(resolution)[1]))
    return (table * scale[None, :, None, None, None]).astype(np.float32)


def coefficients_from_table(table: np.ndarray, rgb: np.ndarray) -> np.ndarray:
    """Dimensionless coefficients of linear sRGB colours (N, 3), none of them black, by trilinear interpolation.

    Each colour's result depends on that colour alone (no reductions across colours), so it is the same bits
    whatever else is in the batch.
    """
    resolution = table.shape[1]
    nodes = z_nodes(resolution)
    largest = np.argmax(rgb, axis=1)[:, None]  # ties: the first; the table's fits agree across that seam
    z = np.take_along_axis(rgb, largest, axis=1)[:, 0]
    u = np.take_along_axis(rgb, (largest + 1) % 3, axis=1)[:, 0] / z
    v = np.take_along_axis(rgb, (largest + 2) % 3, axis=1)[:, 0] / z
    # Below the first non-zero node the stored coefficients * sqrt(z) are held constant (the dark asymptote).
    z_clamped = np.maximum(z, nodes[1])
    z_cell = np.clip(np.searchsorted(nodes, z_clamped, side="right") - 1, 1, resolution - 2)
    fz = np.minimum((z_clamped - nodes[z_cell]) / (nodes[z_cell + 1] - nodes[z_cell]), 1.0)
    position_u = _position_of_ratio(u) * (resolution - 1)
    position_v = _position_of_ratio(v) * (resolution - 1)
    u_cell = np.minimum(position_u.astype(np.int64), resolution - 2)
    v_cell = np.minimum(position_v.astype(np.int64), resolution - 2)
    fu, fv = position_u - u_cell, position_v - v_cell
    first_corner = ((largest[:, 0] * resolution + z_cell) * resolution + v_cell) * resolution + u_cell
    corners = first_corner[:, None] + _corner_offsets(resolution)
    along_z, along_v, along_u = (np.stack([1.0 - f, f], axis=1) for f in (fz, fv, fu))
    weights = (along_z[:, :, None, None] * along_v[:, None, :, None] * along_u[:, None, None, :]).reshape(-1, 8)
    interpolated = np.einsum("nk,nkc->nc", weights, table.reshape(-1, 3)[corners])
    return interpolated / np.sqrt(z)[:, None]


@cache
def _corner_offsets(resolution: int) -> np.ndarray:
    """Flat index offsets of a cell's 8 corners from its first, in the order (dz, dv, du) of the weights."""
    return np.array([(dz * resolution + dv) * resolution + du for dz in (0, 1) for dv in (0, 1) for du in (0, 1)])


# ---------------------------------------------------------------- cache file


def _colorimetry_key(resolution: int) -> str:
    """What the table depends on: a change to any of it (grid, CMFs, D65, matrix, nodes, tolerance) rebuilds."""
    model = _d65_colorimetry()
    digest = hashlib.sha256(f"{_FORMAT} {resolution} {_BUILD_DELTA_E} {_CENTRE_NM} {_HALF_SPAN_NM}".encode())
    for array in (GRID_NM, model.xyz_weights, XYZ_TO_LINEAR_SRGB, z_nodes(resolution), ratio_nodes(resolution)):
        digest.update(np.ascontiguousarray(array, dtype="<f8").tobytes())
    return digest.hexdigest()


def table_identity(resolution: int = TABLE_RESOLUTION) -> str:
    """A digest naming the table's contents: results computed from it can be cached under it."""
    return f"{resolution}-{_colorimetry_key(resolution)}"


def table_path(resolution: int = TABLE_RESOLUTION) -> Path:
    return cache_root() / "uplift" / f"rgb-reflectance-{resolution}.bin"


def _serialise(table: np.ndarray, resolution: int) -> bytes:
    data = np.ascontiguousarray(table, dtype="<f4").tobytes()
    header = {
        "format": _FORMAT,
        "resolution": resolution,
        "colorimetry": _colorimetry_key(resolution),
        "sha256": hashlib.sha256(data).hexdigest(),
    }
    return _MAGIC + json.dumps(header, sort_keys=True).encode() + b"\n" + data


def _deserialise(blob: bytes, resolution: int) -> np.ndarray | None:
    """The table in `blob`, or None when it is not a complete, intact table for this colorimetry."""
    if not blob.startswith(_MAGIC):
        return None
    header_end = blob.find(b"\n", len(_MAGIC))
    if header_end < 0:
        return None
    try:
        header = json.loads(blob[len(_MAGIC) : header_end])
    except ValueError:
        return None
    data = blob[header_end + 1 :]
    shape = (3, resolution, resolution, resolution, 3)
    if (
        not isinstance(header, dict)
        or header.get("format") != _FORMAT
        or header.get("resolution") != resolution
        or header.get("colorimetry") != _colorimetry_key(resolution)
        or len(data) != 4 * int(np.prod(shape))
        or header.get("sha256") != hashlib.sha256(data).hexdigest()
    ):
        return None
    table = np.frombuffer(data, dtype="<f4").reshape(shape).astype(np.float32)
    return table if np.all(np.isfinite(table)) else None


def load_or_build_table(resolution: int = TABLE_RESOLUTION) -> np.ndarray:
    """The table from its cache file when that is intact, else built and the file (re)written atomically."""
    path = table_path(resolution)
    try:
        table = _deserialise(path.read_bytes(), resolution)
    except OSError:
        table = None
    if table is None:
        table = build_table(resolution)
        blob = _serialise(table, resolution)
        try:
            write_atomically(path, lambda temporary: temporary.write_bytes(blob))
        except OSError as error:  # an unwritable cache costs a rebuild in the next process, nothing more
            warnings.warn(f"could not cache the RGB uplift table in '{path}': {error}", stacklevel=2)
    table.setflags(write=False)
    return table


@cache
def coefficient_table(resolution: int = TABLE_RESOLUTION) -> np.ndarray:
    """`load_or_build_table`, once per process."""
    return load_or_build_table(resolution)
