"""Colour (RGB) albedo grids of heterogeneous media (docs/media.md): each voxel's colour uplifted to a smooth
spectrum, the spectra interpolated at the path's wavelengths; checked against the homogeneous medium of the uplifted
albedo and the scene keys."""

import numpy as np
import pytest

from scene_text import CAMERA_FILM_GREY
from spectrace.engine.meters import RadianceMeter, measure
from spectrace.errors import SpectraceError
from spectrace.geometry import primitives
from spectrace.geometry.grid_volume import box_matrix, make_grid, vol_bytes
from spectrace.scene import load_scene
from spectrace.scene.model import Camera, ConstantEnvironment, Medium, Scene, Shape
from spectrace.spectral.grid import GRID_NM
from spectrace.spectral.spectrum import Spectrum
from spectrace.spectral.uplift import uplift_reflectance
from stats_toolkit import assert_within_standard_errors

LANES_NM = np.array([430.0, 510.0, 590.0, 660.0])
RGB = (0.95, 0.6, 0.4)


def _scene(medium: Medium) -> Scene:
    return Scene(
        camera=Camera((0.0, 0.0, -1.0), (0.0, 0.0, 0.0)),
        width=1,
        height=1,
        shapes=[Shape(mesh=primitives.cube(), material=None, interior=medium)],
        lights=[ConstantEnvironment(Spectrum.constant(1.0))],
        max_depth=16,
    )


@pytest.mark.slow
def test_a_constant_colour_albedo_grid_renders_as_the_homogeneous_medium_of_that_colour(device):
    """A cube of density 1 whose albedo grid holds one colour everywhere gives, all bounces, the radiance of the
    homogeneous medium σs(λ) = a(λ) σt, σa(λ) = (1 − a(λ)) σt with a(λ) = s S(λ), S the uplifted spectrum of the
    colour over s = 2 × its largest channel (Mitsuba 3's gridvolume form), evaluated on the host (the grid's
    spectra are evaluated in the kernel from per-voxel coefficients), within 4 standard errors of their
    difference; the lanes differ far beyond the noise (the comparison sees the colour)."""
    sigma_t = 1.0
    s = 2.0 * max(RGB)
    a = s * uplift_reflectance(np.array(RGB) / s)[0].evaluate(GRID_NM)
    homogeneous = Medium(Spectrum(sigma_t * (1.0 - a)), Spectrum(sigma_t * a), g=0.3)
    shape = (3, 4, 5)
    grid = make_grid(np.ones(shape, np.float32), box_matrix((-1, -1, -1), (1, 1, 1)), np.broadcast_to(RGB, (*shape, 3)))
    gridded = Medium(Spectrum.zeros(), Spectrum.constant(sigma_t), g=0.3, density=grid)
    readings = [
        measure(
            _scene(medium),
            RadianceMeter((0.3, 0.2, -3.0), (0.0, 0.0, 1.0)),
            wavelengths_nm=LANES_NM,
            streams=32,
            samples_per_item=2048,
            device=device,
        )
        for medium in (homogeneous, gridded)
    ]
    expected, got = readings
    se = np.hypot(expected.spectral_standard_error, got.spectral_standard_error)
    assert_within_standard_errors(got.spectral, expected.spectral, se, power=0.05, what="colour albedo grid")
    # the albedo's lanes differ by far more than the noise: a grey albedo could not pass
    assert np.ptp(expected.spectral) > 20 * se.max()


def _scene_text(albedo: str) -> str:
    density = f"{{ values = [1, 1], resolution = [1, 1, 2], {albedo} }}"
    return (
        CAMERA_FILM_GREY
        + f"""
[[shapes]]
type = "cube"
interior = {{ sigma_s = {{ value = 1.0 }}, density = {density} }}
"""
    )


def test_scene_file_reads_colour_albedo_from_three_values_a_voxel_and_a_colour_vol(tmp_path):
    colours = np.array([[[[0.2, 0.4, 0.6]]], [[[0.9, 0.5, 0.1]]]], np.float32)
    (tmp_path / "albedo.vol").write_bytes(vol_bytes(colours))
    for albedo in (f"albedo_values = {colours.ravel().tolist()}", 'albedo_file = "albedo.vol"'):
        (tmp_path / "s.toml").write_text(_scene_text(albedo))
        grid = load_scene(tmp_path / "s.toml").shapes[0].interior.density
        assert grid.albedo.shape == (2, 1, 1, 3)
        assert np.array_equal(grid.albedo, colours)


@pytest.mark.parametrize(
    ("albedo", "message"),
    [
        ("albedo_values = [0.5, 0.5, 0.5, 0.5]", "need 2 or 6 for a colour"),
        ("albedo_values = [0.5, 0.5, 1.5, 0.5, 0.5, 0.5]", "above 1"),
    ],
)
def test_bad_colour_albedo_is_one_line_naming_the_key(tmp_path, albedo, message):
    (tmp_path / "s.toml").write_text(_scene_text(albedo))
    with pytest.raises(SpectraceError, match=message) as caught:
        load_scene(tmp_path / "s.toml")
    assert "\n" not in str(caught.value) and "density" in str(caught.value)
