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

The build fits one z slice of all three channels' (u, v) planes at a time, walking out from the middle slice;
each slice starts from the polynomial in z through the three solved before it (coefficients * sqrt(z), smooth at
both ends). Each slice is solved by Levenberg-Marquardt under a coarse rule (`_coarse_rule`: the reflectance on
5 nm knots, interpolated, against the 1 nm weights; a fifth of the work per colour), then checked and finished
under the exact 1 nm colorimetry (`_fit`), so that a node meets `_BUILD_DELTA_E` (or is the best fit the model
allows) in the colorimetry `uplift.py` fits; the few nodes too steep for the coarse rule (the darkest saturated
ones, some corners) are solved under the exact rule throughout. That costs about 3.7 evaluations of a 95-point
spectrum and 1.3 of a 471-point one per node, about 7 CPU-seconds for 3 x 64^3 nodes (the former all-exact solve
took 110) and 40 MB. The result does not depend on the number of threads. The table is cached on disk all the same
(`table_path`, 9.4 MB), checked on load (format, the colorimetry it was built for, a SHA-256 of its values, all
finite), and rebuilt when the file is missing or damaged.
"""

from __future__ import annotations

import hashlib
import json
import warnings
from dataclasses import dataclass
from functools import cache
from pathlib import Path

import numpy as np

from spectrace.cache_folder import cache_root
from spectrace.io.atomic import write_atomically
from spectrace.spectral.colorimetry import XYZ_TO_LINEAR_SRGB
from spectrace.spectral.grid import GRID_MAX_NM, GRID_MIN_NM, GRID_NM
from spectrace.spectral.uplift import _CENTRE_NM, _HALF_SPAN_NM, _d65_colorimetry

TABLE_RESOLUTION = 64  # nodes per axis: 3 x 64^3 colours, 9.4 MB of float32 coefficients

_FORMAT = 3  # 3: the coarse-rule build (same layout; other bits, so cached results keyed on it go)
_MAGIC = b"spectrace rgb uplift table\n"
_BUILD_DELTA_E = 1e-6  # each node is fitted as tightly as `uplift.py` fits one colour
_MAX_ITERATIONS = 300
_LEAST_DAMPING = 1e-12  # of Levenberg-Marquardt: no more than rounding, yet no singular system
_COARSE_KNOT_NM = 5.0
_COARSE_ORDER = 10
_COARSE_ITERATIONS = 20  # beyond this the coarse rule cannot resolve the sigmoid: the exact solve takes over
_EXACT_STEPS = 3  # Newton steps on the exact residual before a colour is solved exactly
# Multiply-adds per matrix product in `_xyz`: OpenBLAS runs products up to 2^18 on one thread, and its threads,
# waiting beside a busy machine, cost more CPU than they save; the temporaries (under 700 kB) stay in the CPU's cache.
_PRODUCT_SIZE = 1 << 18


def z_nodes(resolution: int) -> np.ndarray:
    """Brightness nodes in [0, 1], packed towards both ends: smoothstep(smoothstep(k / (n - 1)))."""
    s = np.linspace(0.0, 1.0, resolution)
    for _ in range(2):
        s = s * s * (3.0 - 2.0 * s)
    return s


# ---------------------------------------------------------------- batched CIELAB model and solver
#
# Colours are columns here: coefficients (3, N), XYZ and Lab (3, N), Jacobians (3 outputs, 3 coefficients, N), so
# that the 3 x 3 algebra of every colour at once is a few operations on long rows, and each colour's result
# depends on its own column alone.


def _lab_columns(xyz: np.ndarray, jacobian: np.ndarray | None = None):
    """CIELAB (3, N) of XYZ (3, N); with d XYZ / d coefficients (3, 3, N), also d Lab / d coefficients."""
    model = _d65_colorimetry()
    delta = model._DELTA
    ratio = xyz / model.white_xyz[:, None]
    # `uplift.py`'s f and f' together, from one cube root.
    cube_root = np.cbrt(np.maximum(ratio, delta**3))
    linear = ratio <= delta**3
    lab = model._LAB_MATRIX @ np.where(linear, ratio / (3 * delta**2) + 4.0 / 29.0, cube_root)
    lab -= model._LAB_OFFSET[:, None]
    if jacobian is None:
        return lab
    slope = np.where(linear, 1.0 / (3 * delta**2), 1.0 / (3 * cube_root**2)) / model.white_xyz[:, None]
    return lab, np.einsum("ij,jkn->ikn", model._LAB_MATRIX, slope[:, None, :] * jacobian)


def target_lab(rgb: np.ndarray) -> np.ndarray:
    """CIELAB (D65 white) of linear sRGB colours (N, 3), through the exact inverse of the lecture's matrix."""
    return _lab_columns(_d65_colorimetry().linear_srgb_to_xyz @ np.asarray(rgb, dtype=np.float64).T).T


@dataclass(frozen=True)
class _Rule:
    """A quadrature for the XYZ under D65 of S(a t^2 + b t + c): the quadratic's basis at its m nodes (m, 3), half
    its weights (3, m), half the XYZ of a perfect white under it (3, 1), and half the weights times the basis
    (9, m), ordered (XYZ j, coefficient k), so that d XYZ / d coefficients is one product with S'(x)."""

    basis: np.ndarray
    half_weights: np.ndarray
    half_white: np.ndarray
    half_slope_weights: np.ndarray

    @staticmethod
    def of(nodes_nm: np.ndarray, weights: np.ndarray) -> _Rule:
        t = (nodes_nm - _CENTRE_NM) / _HALF_SPAN_NM
        basis = np.stack([t * t, t, np.ones_like(t)], axis=1)
        slope_weights = (weights.T[:, None, :] * basis.T[None, :, :]).reshape(9, len(t))
        return _Rule(basis, 0.5 * weights.T.copy(), 0.5 * weights.sum(axis=0)[:, None], 0.5 * slope_weights)


@cache
def _exact_rule() -> _Rule:
    """The renderer's colorimetry: the trapezoid rule on the 1 nm grid, as `uplift.py` fits one colour."""
    return _Rule.of(GRID_NM, _d65_colorimetry().xyz_weights)


@cache
def _coarse_rule() -> _Rule:
    """The renderer's colorimetry applied to the reflectance interpolated from knots every `_COARSE_KNOT_NM` (by the
    polynomial through the `_COARSE_ORDER` knots around each grid wavelength): a fifth of the work per colour. At
    the table's fits it is within Delta E 1e-6 of the exact rule for 83 % of the nodes (the median is 1e-9), and off
    by up to 0.035 where a sigmoid is steep."""
    knots = np.arange(GRID_MIN_NM, GRID_MAX_NM + 0.5 * _COARSE_KNOT_NM, _COARSE_KNOT_NM)
    return _Rule.of(knots, _interpolation_matrix(knots, GRID_NM, _COARSE_ORDER).T @ _d65_colorimetry().xyz_weights)


def _interpolation_matrix(knots: np.ndarray, points: np.ndarray, order: int) -> np.ndarray:
    """(points, knots): row p gives the value at p of the polynomial through the `order` (evenly spaced) knots
    centred on p's interval, shifted inwards at the ends."""
    spacing = knots[1] - knots[0]
    interval = np.clip(((points - knots[0]) // spacing).astype(np.int64), 0, len(knots) - 2)
    first = np.clip(interval - (order // 2 - 1), 0, len(knots) - order)
    used = first[:, None] + np.arange(order)  # (points, order)
    matrix = np.zeros((len(points), len(knots)))
    for k in range(order):
        others = np.delete(used, k, axis=1)
        weight = np.prod((points[:, None] - knots[others]) / (knots[used[:, k : k + 1]] - knots[others]), axis=1)
        matrix[np.arange(len(points)), used[:, k]] = weight
    return matrix


def _xyz(rule: _Rule, coefficients: np.ndarray, jacobian: bool) -> tuple[np.ndarray, np.ndarray | None]:
    """XYZ (3, N) of S(basis @ coefficients), coefficients (3, N), under `rule`; with `jacobian`, also
    d XYZ / d coefficients (3, 3, N).

    Tens to hundreds of colours at a time (`_PRODUCT_SIZE`), in the same two buffers: temporaries that stay in the
    CPU's cache, where whole-batch ones would each be a fresh allocation streamed through memory.
    S(x) = 1/2 + y / 2 with y = x / sqrt(1 + x^2), and S'(x) = (1 + x^2)^(-3/2) / 2.
    """
    m, n = len(rule.basis), coefficients.shape[1]
    columns = max(1, _PRODUCT_SIZE // (m * (9 if jacobian else 3)))
    xyz = np.empty((3, n))
    d_xyz = np.empty((9, n if jacobian else 0))
    x_buffer, y_buffer = np.empty(m * columns), np.empty(m * columns)
    for first in range(0, n, columns):
        chunk = slice(first, min(first + columns, n))
        size = m * (chunk.stop - first)
        x, y = x_buffer[:size].reshape(m, -1), y_buffer[:size].reshape(m, -1)
        np.matmul(rule.basis, coefficients[:, chunk], out=x)
        np.multiply(x, x, out=y)
        y += 1.0
        np.sqrt(y, out=y)
        if jacobian:
            np.divide(1.0, y, out=y)
            x *= y
            np.matmul(rule.half_weights, x, out=xyz[:, chunk])
            np.multiply(y, y, out=x)
            x *= y
            np.matmul(rule.half_slope_weights, x, out=d_xyz[:, chunk])
        else:
            np.divide(x, y, out=y)
            np.matmul(rule.half_weights, y, out=xyz[:, chunk])
    xyz += rule.half_white
    return xyz, d_xyz.reshape(3, 3, n) if jacobian else None


def _lab_under(rule: _Rule, coefficients: np.ndarray, jacobian: bool = False):
    xyz, d_xyz = _xyz(rule, coefficients, jacobian)
    return _lab_columns(xyz, d_xyz)


def lab_of_coefficients(coefficients: np.ndarray, jacobian: bool = False):
    """CIELAB under D65 (the renderer's 1 nm colorimetry) of the reflectances S(a t^2 + b t + c), coefficients
    (N, 3) dimensionless; with `jacobian`, also d Lab / d coefficients (N, 3, 3)."""
    result = _lab_under(_exact_rule(), np.asarray(coefficients, dtype=np.float64).T.copy(), jacobian)
    if not jacobian:
        return result.T
    return result[0].T, result[1].transpose(2, 0, 1)


def _dot(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Column-wise dot products of (3, N) arrays."""
    return np.einsum("in,in->n", u, v)


def _squared_norms(columns: np.ndarray) -> np.ndarray:
    return _dot(columns, columns)


def _damped_step(jacobian: np.ndarray, residual: np.ndarray, damping: np.ndarray | float) -> np.ndarray:
    """The Levenberg-Marquardt step of each colour, (J^T J + damping diag(J^T J)) step = -J^T r, by Cramer's rule
    on the system scaled to a unit diagonal. A colour whose system is singular gets a step of NaN or infinity,
    which the callers reject, as they reject any step that does not lower the error."""
    columns = [jacobian[:, k] for k in range(3)]
    scale = [1.0 / np.sqrt(_dot(column, column) + 1e-300) for column in columns]
    b, c, e = (_dot(columns[p], columns[q]) * scale[p] * scale[q] for p, q in ((0, 1), (0, 2), (1, 2)))
    a = d = f = 1.0 + damping
    g = [_dot(column, residual) * s for column, s in zip(columns, scale)]
    adjugate_00, adjugate_11, adjugate_22 = d * f - e * e, a * f - c * c, a * d - b * b
    adjugate_01, adjugate_02, adjugate_12 = c * e - b * f, b * e - c * d, b * c - a * e
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        factor = -1.0 / (a * adjugate_00 + b * adjugate_01 + c * adjugate_02)
        return np.stack(
            [
                (adjugate_00 * g[0] + adjugate_01 * g[1] + adjugate_02 * g[2]) * factor * scale[0],
                (adjugate_01 * g[0] + adjugate_11 * g[1] + adjugate_12 * g[2]) * factor * scale[1],
                (adjugate_02 * g[0] + adjugate_12 * g[1] + adjugate_22 * g[2]) * factor * scale[2],
            ]
        )


def solve(
    target: np.ndarray,
    start: np.ndarray,
    delta_e: float = _BUILD_DELTA_E,
    max_iterations: int = _MAX_ITERATIONS,
    rule: _Rule | None = None,
) -> np.ndarray:
    """Levenberg-Marquardt on the CIELAB residual for each row of `target` (N, 3 Lab), from `start` (N, 3
    dimensionless coefficients), with a damping of its own per colour; the batched twin of `uplift.py`'s solve,
    under `rule` (by default the exact colorimetry)."""
    return _solve_columns(
        np.asarray(target, dtype=np.float64).T,
        np.asarray(start, dtype=np.float64).T,
        delta_e,
        max_iterations,
        rule or _exact_rule(),
    )[0].T


def _solve_columns(
    target: np.ndarray, start: np.ndarray, delta_e: float, max_iterations: int, rule: _Rule
) -> tuple[np.ndarray, np.ndarray]:
    """`solve` on columns; also says which colours converged (to within `delta_e`)."""
    coefficients = np.array(start, dtype=np.float64)
    lab, jacobian = _lab_under(rule, coefficients, jacobian=True)
    residual = lab - target
    error = _squared_norms(residual)
    # The colours still being solved, packed: index, coefficients, Jacobian, residual, error, damping, target.
    index = np.flatnonzero(error >= delta_e**2)
    c, j, r, t = coefficients[:, index], jacobian[..., index], residual[:, index], target[:, index]
    e, damping = error[index], np.full(index.size, 1e-3)
    for _ in range(max_iterations):
        if index.size == 0:
            break
        trial = c + _damped_step(j, r, damping)
        trial_lab, trial_jacobian = _lab_under(rule, trial, jacobian=True)
        trial_residual = trial_lab - t
        trial_error = _squared_norms(trial_residual)
        better = trial_error < e
        for kept, tried in ((c, trial), (j, trial_jacobian), (r, trial_residual), (e, trial_error)):
            np.copyto(kept, tried, where=better)
        damping = np.where(better, np.maximum(damping * 0.1, _LEAST_DAMPING), damping * 10.0)
        # Converged, or no descent direction left (the best fit the model allows).
        going = (e >= delta_e**2) & (damping <= 1e12)
        if not going.all():
            coefficients[:, index[~going]], error[index[~going]] = c[:, ~going], e[~going]
            index, c, j, r, t, e, damping = (
                index[going],
                c[:, going],
                j[..., going],
                r[:, going],
                t[:, going],
                e[going],
                damping[going],
            )
    coefficients[:, index] = c
    return coefficients, error < delta_e**2


def _fit(target: np.ndarray, start: np.ndarray) -> np.ndarray:
    """`_solve_columns` under the exact colorimetry (columns of Lab and coefficients), done mostly under the coarse
    rule: solved there, then Newton steps on the exact residual with the coarse rule's Jacobian, which leave most
    colours within `_BUILD_DELTA_E` after none or one (the two rules' Jacobians differ by about as little as their
    colours). The rest are solved under the exact rule: from where the steps got them, or from `start` where the
    coarse rule found no fit (the darkest saturated nodes, some corners: sigmoids too steep for 5 nm knots)."""
    coarse = _coarse_rule()
    coefficients, converged = _solve_columns(target, start, _BUILD_DELTA_E, _COARSE_ITERATIONS, coarse)
    residual = _lab_under(_exact_rule(), coefficients) - target
    error = _squared_norms(residual)
    # Where the coarse rule found no fit, its result can lie in another valley: those start again, exactly.
    coefficients[:, ~converged] = start[:, ~converged]
    error[~converged] = np.inf
    open_ = np.flatnonzero(converged & (error >= _BUILD_DELTA_E**2))
    for _ in range(_EXACT_STEPS):
        if open_.size == 0:
            break
        _, jacobian = _lab_under(coarse, coefficients[:, open_], jacobian=True)
        trial = coefficients[:, open_] + _damped_step(jacobian, residual[:, open_], _LEAST_DAMPING)
        trial_residual = _lab_under(_exact_rule(), trial) - target[:, open_]
        trial_error = _squared_norms(trial_residual)
        better = trial_error < error[open_]
        accepted = open_[better]
        coefficients[:, accepted], residual[:, accepted] = trial[:, better], trial_residual[:, better]
        error[accepted] = trial_error[better]
        open_ = accepted[trial_error[better] >= _BUILD_DELTA_E**2]
    open_ = np.flatnonzero(error >= _BUILD_DELTA_E**2)
    if open_.size:
        coefficients[:, open_], _ = _solve_columns(
            target[:, open_], coefficients[:, open_], _BUILD_DELTA_E, _MAX_ITERATIONS, _exact_rule()
        )
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
    # Solved in the stored variable, coefficients * sqrt(z) (module docstring): smooth in z at both ends, so that
    # extrapolating it from the two previous slices starts each slice close to its solution.
    nodes = z_nodes(resolution)
    scale = np.sqrt(np.maximum(nodes, nodes[1]))
    table = np.zeros((3, resolution, resolution, resolution, 3))
    middle = resolution // 2
    order = [middle, *range(middle + 1, resolution), *range(middle - 1, 0, -1)]
    for z_index in order:
        target = target_lab(node_colours(resolution, z_index).reshape(-1, 3)).T
        step = 1 if z_index > middle else -1
        # The slices solved before this one, nearest first (up to three).
        solved = [k for k in range(z_index - step, z_index - 4 * step, -step) if (k - middle) * step >= 0]
        start = np.zeros(target.shape)
        for k in solved:  # the polynomial in z through them, evaluated here
            weight = np.prod([(nodes[z_index] - nodes[o]) / (nodes[k] - nodes[o]) for o in solved if o != k])
            start += weight * table[:, k].reshape(-1, 3).T
        if solved and nodes[z_index] < 0.5 * nodes[solved[0]]:
            # Towards black each slice is several times darker than the last, and where a colour is not yet on the
            # dark asymptote the extrapolation can overshoot into another fit: the last slice's values, which the
            # asymptote holds constant, compete.
            held = table[:, solved[0]].reshape(-1, 3).T
            coarse = _coarse_rule()
            error_start = _squared_norms(_lab_under(coarse, start / scale[z_index]) - target)
            error_held = _squared_norms(_lab_under(coarse, held / scale[z_index]) - target)
            start = np.where(error_held < error_start, held, start)
        start /= scale[z_index]
        coefficients = _fit(target, start)
        table[:, z_index] = (coefficients.T * scale[z_index]).reshape(3, resolution, resolution, 3)
    table[:, 0] = table[:, 1]
    return table.astype(np.float32)


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
