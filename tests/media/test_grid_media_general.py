"""Grid media beyond a grey density that ends at its box (docs/media.md): a colour density (σt varying with λ voxel
by voxel, each voxel's RGB uplifted as Mitsuba 3's spectral gridvolume does) and grids that fill all space (their
faces' values clamped, or the grid repeated: an albedo grid over a homogeneous σt). The ratio-tracked
transmittance and the free flights of kernels/medium_grid.cl against a quadrature of the same lookups computed
apart (scipy's interpolation, per-voxel spectra from the uplift's own fit), the majorant's bound, and the keys."""

import numpy as np
import pytest
from scipy import ndimage

from scene_text import CAMERA_FILM_GREY
from spectrace.core.contract import MEDIUM_DTYPE
from spectrace.errors import SpectraceError
from spectrace.geometry.grid_volume import albedo_block, box_matrix, colour_bound, make_grid, medium_row
from spectrace.geometry.transforms import transform_matrix
from spectrace.scene import load_scene
from spectrace.scene.model import Medium
from spectrace.spectral.grid import GRID_NM
from spectrace.spectral.spectrum import Spectrum
from spectrace.spectral.table import SpectrumTable
from spectrace.spectral.uplift import uplift_reflectance
from stats_toolkit import assert_within_standard_errors, mean_and_standard_error

LANES_NM = np.array([420.0, 500.0, 580.0, 680.0])
SIGMA_A, SIGMA_S = 0.3, 0.5


def _device_medium(medium: Medium) -> tuple[np.ndarray, np.ndarray]:
    table = SpectrumTable()
    table.add(Spectrum.zeros())  # a non-zero offset exercises the indexing
    row = np.array([medium_row(medium, table)], MEDIUM_DTYPE)
    return table.data, row


def _colour_density() -> np.ndarray:
    rng = np.random.default_rng(21)
    rgb = (rng.uniform(0.0, 2.0, (3, 4, 5, 3)) * (1.5, 0.7, 0.2)).astype(np.float32)  # reddish: σt varies with λ
    rgb[1, 2] = (1.8, 0.05, 0.1)  # a saturated voxel: its spectrum peaks far above its mean
    return rgb


def _voxel_spectra(rgb: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each voxel's spectrum S at the lanes (the uplift's own fit of rgb / s) and its s = 2 × its largest
    channel: Mitsuba 3's spectral gridvolume form, computed without the grid's device block."""
    flat = rgb.reshape(-1, 3).astype(np.float64)
    scale = 2.0 * flat.max(axis=1)
    spectra = np.array([uplift_reflectance(c / max(s, 1e-8))[0].evaluate(LANES_NM) for c, s in zip(flat, scale)])
    return spectra.reshape(*rgb.shape[:3], 4), scale.reshape(rgb.shape[:3])


def _lookup(values: np.ndarray, unit: np.ndarray, mode: str) -> np.ndarray:
    """scipy's trilinear interpolation of voxel-centred `values` (nz, ny, nx) at unit-box points (n, 3)."""
    nz, ny, nx = values.shape
    coords = np.stack([unit[:, 2] * nz - 0.5, unit[:, 1] * ny - 0.5, unit[:, 0] * nx - 0.5])
    return ndimage.map_coordinates(values.astype(np.float64), coords, order=1, mode=mode)


def _density_along(grid, rgb_or_grey, origin, direction, t):
    """σt's density per lane at origin + t·direction: a colour density the mix of the voxels' spectra times the
    mix of their s; outside the box 0 ("empty"), the faces' values ("clamp") or the wrapped grid ("repeat")."""
    points = origin + t[:, None] * direction
    unit = (np.c_[points, np.ones(len(t))] @ np.linalg.inv(grid.to_world).T)[:, :3]
    mode = {"empty": "nearest", "clamp": "nearest", "repeat": "grid-wrap"}[grid.outside]
    if rgb_or_grey.ndim == 4:
        spectra, scale = _voxel_spectra(rgb_or_grey)
        lanes = np.stack([_lookup(spectra[..., lane], unit, mode) for lane in range(4)], axis=1)
        values = lanes * _lookup(scale, unit, mode)[:, None]
    else:
        values = np.repeat(_lookup(rgb_or_grey, unit, mode)[:, None], 4, axis=1)
    if grid.outside == "empty":
        values *= np.all((unit >= 0.0) & (unit <= 1.0), axis=1)[:, None]
    return values


def _rotated(p0, p1):
    return transform_matrix([{"rotate": {"axis": [1, 2, 0.5], "angle": 35}}], where="t") @ box_matrix(p0, p1)


CASES = {
    # a colour density in a rotated box, crossed obliquely
    "colour": lambda: (_colour_density(), _rotated((-1.0, -0.5, -0.8), (1.2, 0.6, 0.9)), "empty"),
    # a grey grid of half a unit a side repeated along a ray that crosses many copies
    "repeat": lambda: (
        np.random.default_rng(4).uniform(0.0, 1.5, (4, 3, 5)).astype(np.float32),
        _rotated((0.2, 0.1, -0.3), (0.7, 0.6, 0.2)),
        "repeat",
    ),
    # a colour grid clamped: the ray runs mostly outside the box, where the faces' values continue
    "colour-clamp": lambda: (_colour_density() * 0.5, box_matrix((-0.4, -0.4, -0.4), (0.4, 0.4, 0.4)), "clamp"),
}
ORIGIN = np.array([-2.0, -1.5, -1.0])
DIRECTION = np.array([2.0, 1.6, 1.9]) / np.linalg.norm([2.0, 1.6, 1.9])


def _case(name):
    values, to_world, outside = CASES[name]()
    grid = make_grid(values, to_world, outside=outside)
    return values, grid, Medium(Spectrum.constant(SIGMA_A), Spectrum.constant(SIGMA_S), density=grid)


def _depths(name, t_end, points=40_001):
    """The optical depth per lane from 0 to each quadrature point, and those points."""
    values, grid, _ = _case(name)
    t = np.linspace(0.0, t_end, points)
    rho = _density_along(grid, values, ORIGIN, DIRECTION, t) * (SIGMA_A + SIGMA_S)
    depth = np.concatenate([np.zeros((1, 4)), np.cumsum((rho[1:] + rho[:-1]) / 2 * np.diff(t)[:, None], axis=0)])
    return t, rho, depth


@pytest.mark.parametrize("name", CASES)
def test_ratio_tracking_gives_the_transmittance_of_general_grids(kernel_runner, name):
    """The mean of the ratio-tracking estimates is exp(−∫σt(λ, x) dt) for each lane, the integral a quadrature of
    the lookups computed apart; the lanes differ for a colour density (σt varies with λ), and every estimate lies
    in [0, 1] (the majorant bounds σt at every lane: a null coefficient never goes negative)."""
    _, _, medium = _case(name)
    spectra, row = _device_medium(medium)
    runner = kernel_runner("testing/medium_grid_sampling.cl")
    n, length = 100_000, 3.5
    out = np.empty((n, 4), np.float32)
    args = [
        runner.buffer(spectra),
        runner.buffer(row),
        LANES_NM.astype(np.float32),
        np.array([*ORIGIN, 0.0], np.float32),
        np.array([*DIRECTION, 0.0], np.float32),
        np.float32(length),
        np.uint32(11),
        runner.buffer(out, True),
    ]
    runner.run("grid_transmittances", n, args, {7: out})
    expected = np.exp(-_depths(name, length)[2][-1])
    assert np.all(expected < 0.8)  # the ray crosses the medium
    if name.startswith("colour"):
        assert np.ptp(expected) > 0.05  # σt differs between the lanes
    assert np.all(out >= 0.0) and np.all(out <= 1.0 + 1e-6)
    mean, se = mean_and_standard_error(out)
    # slack: the device block's fit of each voxel's colour and the uplift's own differ by ~1e-3 of a spectrum
    assert_within_standard_errors(mean, expected, se, slack=3e-3 * expected, what=name, power=0.05)


@pytest.mark.parametrize("name", CASES)
def test_free_flights_through_general_grids_are_unbiased(kernel_runner, name):
    """Delta tracking: each lane's expected weight for reaching the surface is its transmittance, and for
    scattering within each stretch of the ray ∫ σs(λ, x) T_λ(t) dt, from the quadrature."""
    _, _, medium = _case(name)
    spectra, row = _device_medium(medium)
    runner = kernel_runner("testing/medium_grid_sampling.cl")
    n, t_surface = 200_000, 3.0
    scattered = np.empty((n, 4), np.float32)
    surface = np.empty((n, 4), np.float32)
    distance = np.empty(n, np.float32)
    args = [
        runner.buffer(spectra),
        runner.buffer(row),
        LANES_NM.astype(np.float32),
        np.array([*ORIGIN, 0.0], np.float32),
        np.array([*DIRECTION, 0.0], np.float32),
        np.float32(t_surface),
        np.int32(0),
        np.uint32(5),
        runner.buffer(scattered, True),
        runner.buffer(surface, True),
        runner.buffer(distance, True),
    ]
    runner.run("grid_flights", n, args, {8: scattered, 9: surface, 10: distance})
    t, rho, depth = _depths(name, t_surface)
    transmittance = np.exp(-depth)
    mean, se = mean_and_standard_error(surface)
    assert_within_standard_errors(mean, transmittance[-1], se, slack=3e-3, what="reached the surface")
    integrand = rho * SIGMA_S / (SIGMA_A + SIGMA_S) * transmittance
    cumulative = np.concatenate(
        [np.zeros((1, 4)), np.cumsum((integrand[1:] + integrand[:-1]) / 2 * np.diff(t)[:, None], axis=0)]
    )
    edges = np.linspace(0.0, t_surface, 7)
    expected_bins = np.diff(np.array([np.interp(edges, t, cumulative[:, lane]) for lane in range(4)]).T, axis=0)
    which = np.digitize(distance, edges) - 1
    for b in range(len(edges) - 1):
        mean, se = mean_and_standard_error(np.where((which == b)[:, None], scattered, 0.0))
        assert_within_standard_errors(mean, expected_bins[b], se, slack=3e-3 * expected_bins[b] + 1e-4, what=b)
    assert expected_bins.sum(axis=0).min() > 0.1  # the flights scatter often enough to test the density


def test_a_colour_voxels_bound_is_its_spectrums_largest_value():
    """colour_bound's peak (the sigmoid at its quadratic's largest value over the wavelength grid) is at least
    every value the voxel's spectrum takes on the 1 nm grid, evaluated here from the block's coefficients, and
    at most a hair above the largest: the majorant is sound and tight."""
    block = albedo_block(_colour_density()).reshape(-1, 4).astype(np.float64)
    peak, scale = colour_bound(block)
    t = (GRID_NM - 0.5 * (GRID_NM[0] + GRID_NM[-1])) / (0.5 * (GRID_NM[-1] - GRID_NM[0]))
    x = (block[:, :1] * t + block[:, 1:2]) * t + block[:, 2:3]
    largest = (0.5 + 0.5 * x / np.sqrt(1.0 + x * x)).max(axis=1)
    assert np.all(peak >= largest) and np.all(peak <= largest * (1 + 1e-4) + 1e-6)
    assert np.array_equal(scale, block[:, 3])


def test_scene_keys_for_colour_and_space_filling_grids(tmp_path):
    """Three values a voxel make a colour density; `outside` picks what lies beyond the box; an albedo grid
    alone stands over a density of 1; an unknown `outside` and a short value list are one-line errors naming
    the key."""
    base = CAMERA_FILM_GREY + '\n[[shapes]]\ntype = "cube"\n'
    interior = "interior = { sigma_s = { value = 1.0 }, density = { %s } }"
    cases = {
        "colour": ("values = [1, 0.5, 0.2], resolution = [1, 1, 1]", None),
        "albedo": ('albedo_values = [0.5, 0.2], resolution = [2, 1, 1], outside = "repeat"', None),
        "bad-outside": ('values = [1], resolution = [1, 1, 1], outside = "mirror"', "density.outside"),
        "short": ("values = [1, 2], resolution = [1, 1, 1]", "values"),
    }
    for name, (line, error) in cases.items():
        path = tmp_path / f"{name}.toml"
        path.write_text(base + interior % line + "\n")
        if error is None:
            grid = load_scene(path).shapes[0].interior.density
            if name == "colour":
                assert grid.density.shape == (1, 1, 1, 3) and grid.outside == "empty"
            else:
                assert np.array_equal(grid.density, np.ones((1, 1, 2))) and grid.outside == "repeat"
                assert np.allclose(grid.albedo.ravel(), [0.5, 0.2])
        else:
            with pytest.raises(SpectraceError) as caught:
                load_scene(path)
            text = str(caught.value)
            assert "\n" not in text and error in text and f"{name}.toml" in text, text
