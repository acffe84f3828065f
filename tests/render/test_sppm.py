"""Stochastic progressive photon mapping (integrator 'sppm') against closed-form radiometry, Snell's law and the path
tracer.

SPPM is consistent, not unbiased: its estimate is the radiance averaged over a disk of radius r around the visible
point, r shrinking as photons arrive. Each check states the bound on that blur's bias for its scene.

- A spot light through a smooth glass slab onto a diffuse screen (the light tracer's scene): the screen's radiance is
  ρ/π · I T² Σ_k R^{2k} / (d − t + (2k + 1) t/n)² near the axis, which the path tracer cannot see at all.
- Two spectral lines through an SF11 prism (the light tracer's dispersion scene) land where Snell's law at both
  faces and the glass's Sellmeier index send them.
- The Cornell box: region means agree with the path tracer's within 5 standard errors of independent renders, plus
  the blur's bias bound.
- The same seed gives the same bits however the render is split into passes.
- What it does not render is refused in one line.
"""

import numpy as np
import pytest
from tests.render.test_light_traced_dispersion import LINES_NM, _leaving, _pixel_column
from tests.render.test_light_traced_dispersion import _scene as _prism_scene
from tests.render.test_light_tracer import DISTANCE, FLOOR_ALBEDO, INTENSITY, IOR, THICKNESS, _slab_scene, _write

import spectrace
from spectrace.engine.renderer import Renderer
from spectrace.errors import SpectraceError
from spectrace.integrators import sppm
from spectrace.resources import resolve_scene_path
from spectrace.spectral.colorimetry import CIE_1931_CMFS
from spectrace.spectral.grid import GRID_NM
from stats_toolkit import assert_within_standard_errors, mean_and_standard_error


def _independent_renders(scene, device, renders: int, spp: int) -> np.ndarray:
    """(renders, height, width, 3) film XYZ of renders with different seeds: SPPM's passes are not independent
    replicas of one render (each pixel's radius and flux carry over), whole renders are."""
    return np.stack(
        [Renderer(scene.with_overrides(seed=1000 + k), device).render(spp=spp).xyz.astype(np.float64) for k in
         range(renders)]
    )  # fmt: skip


@pytest.mark.slow
def test_spot_light_through_a_glass_slab(device, tmp_path):
    """Light through glass onto a screen (L S S D E): the photons alone carry it."""
    reflectance = ((IOR - 1) / (IOR + 1)) ** 2
    transmittance = 1 - reflectance
    k = np.arange(6)
    apparent = DISTANCE - THICKNESS + (2 * k + 1) * THICKNESS / IOR
    irradiance = INTENSITY * np.sum(transmittance**2 * reflectance ** (2 * k) / apparent**2)
    expected = FLOOR_ALBEDO / np.pi * irradiance
    text = _slab_scene(tmp_path, "sppm").read_text().replace("max_depth = -1", "max_depth = 16")
    scene = spectrace.load_scene(_write(tmp_path, text))
    images = _independent_renders(scene, device, 6, 64)[:, 6:10, 6:10, 1]
    mean, standard_error = mean_and_standard_error(images.mean(axis=(1, 2)))
    # The blur's bias: near the axis E(ρ) = E0 (1 − 3ρ²/(2D²) + ...) with D the apparent distance (≥ 0.96), so a
    # disk of radius r averages it to E0 (1 − 3r²/(4D²)); r starts at INITIAL_RADIUS_PIXELS pixel footprints
    # (1.37 cm each at the screen) and only shrinks. The inverse-square terms beyond are smaller.
    r = sppm.INITIAL_RADIUS_PIXELS * 2 * np.tan(np.radians(20)) * 0.3 / 16
    bound = 0.75 * (r / 0.96) ** 2 * expected
    assert_within_standard_errors(mean, expected, standard_error, slack=bound, power=0.05)


def _line_centroid_expected(scene, line_nm: float, sigma_nm: float) -> float:
    """The Y-weighted centroid of where a Gaussian line's wavelengths land (Snell at both faces, Sellmeier n(λ))."""
    wavelengths = np.linspace(line_nm - 5 * sigma_nm, line_nm + 5 * sigma_nm, 201)
    weights = np.exp(-0.5 * ((wavelengths - line_nm) / sigma_nm) ** 2) * np.interp(
        wavelengths, GRID_NM, CIE_1931_CMFS[:, 1]
    )
    axis = _leaving(550.0)
    from tests.render.test_light_traced_dispersion import EXIT, SCREEN_DISTANCE

    centre = EXIT + SCREEN_DISTANCE * axis
    columns = []
    for wavelength in wavelengths:
        leaving = _leaving(float(wavelength))
        t = np.dot(centre - EXIT, axis) / np.dot(leaving, axis)
        columns.append(_pixel_column(scene, EXIT + t * leaving))
    return float(np.sum(np.array(columns) * weights) / weights.sum())


LINE_SIGMA_NM = 2.0


@pytest.mark.slow
def test_spectral_lines_land_where_snells_law_sends_them(device):
    """Every photon of one iteration carries the same wavelengths, and past the prism only the hero: lines 2 nm wide
    are met by a few per cent of the iterations, so this one takes 1024."""
    from spectrace.scene.model import SpotLight
    from spectrace.spectral.spectrum import Spectrum

    scene = _prism_scene()
    lamp = scene.lights[0]
    lines = sum(np.exp(-0.5 * ((GRID_NM - line) / LINE_SIGMA_NM) ** 2) for line in LINES_NM)
    wide = SpotLight(
        position=lamp.position, direction=lamp.direction, intensity=Spectrum(1e6 * lines, name="two lines"),
        cutoff_degrees=lamp.cutoff_degrees, falloff_start_degrees=lamp.falloff_start_degrees,
    )  # fmt: skip
    scene = scene.with_overrides(integrator="sppm", height=4, lights=[wide])
    profile = Renderer(scene, device).render(spp=1024).xyz[..., 1].astype(np.float64).sum(axis=0)
    expected = [_line_centroid_expected(scene, line, LINE_SIGMA_NM) for line in LINES_NM]
    assert abs(expected[0] - expected[1]) > 20
    middle = int(round(0.5 * (expected[0] + expected[1])))
    columns = np.arange(scene.width) + 0.5
    for line, where in zip(LINES_NM, expected, strict=True):
        side = slice(0, middle) if where < middle else slice(middle, scene.width)
        weights = profile[side]
        assert weights.sum() > 0, f"no light at {line} nm"
        centroid = float(np.sum(columns[side] * weights) / weights.sum())
        # The gather disk blurs each line symmetrically (its centroid stays); the beam's own width and the spread of
        # the iterations' wavelengths within a line leave the centroid within half a pixel.
        assert abs(centroid - where) < 0.5, (line, centroid, where)


CORNELL_SIZE = 32


@pytest.mark.slow
def test_cornell_box_agrees_with_the_path_tracer(device, monkeypatch):
    # One pixel footprint at first, so that the blur's bias bound below is small.
    monkeypatch.setattr(sppm, "INITIAL_RADIUS_PIXELS", 1.0)
    scene = spectrace.load_scene(resolve_scene_path("cornell_box")).with_overrides(
        width=CORNELL_SIZE, height=CORNELL_SIZE
    )
    ours = _independent_renders(scene.with_overrides(integrator="sppm"), device, 8, 16)
    theirs = _independent_renders(scene, device, 8, 16)
    block = 8
    n = CORNELL_SIZE // block
    a = ours[..., 1].reshape(8, n, block, n, block).mean(axis=(2, 4))
    b = theirs[..., 1].reshape(8, n, block, n, block).mean(axis=(2, 4))
    difference = a.mean(axis=0) - b.mean(axis=0)
    standard_error = np.sqrt(a.var(axis=0, ddof=1) / 8 + b.var(axis=0, ddof=1) / 8)
    # The blur's bias on a block mean: a smooth gradient cancels over the disk; where the disk reaches past a wall's
    # edge, the part off the wall finds no photons, losing at most half the photon-carried (indirect) light of the
    # pixels within r (one footprint) of an edge: two edges cross a block in at most 2·8 of its 64 pixels, and the
    # indirect light is under half of any pixel's, so 1/4 · 1/2 · 1/2 ≈ 6 % of the block's mean bounds it.
    bound = 0.0625 * np.abs(b.mean(axis=0))
    assert np.all(np.abs(difference) <= 5 * standard_error + bound), np.max(
        (np.abs(difference) - bound) / standard_error
    )


def test_pass_split_gives_the_same_bits(device, tmp_path):
    text = _slab_scene(tmp_path, "sppm").read_text().replace("max_depth = -1", "max_depth = 16")
    scene = spectrace.load_scene(_write(tmp_path, text)).with_overrides(spp=6)
    one_pass = Renderer(scene, device).render(pass_spp=6).xyz
    split = Renderer(scene, device).render(pass_spp=1).xyz
    np.testing.assert_array_equal(one_pass, split)
    renderer = Renderer(scene, device)
    renderer.render(pass_spp=3)
    renderer.reset()
    np.testing.assert_array_equal(one_pass, renderer.render(pass_spp=2).xyz)


@pytest.mark.parametrize(
    ("extra", "match"),
    [
        ("\n[[shapes]]\ntype = \"cube\"\ninterior = { sigma_a = { value = 0.1 }, sigma_s = { value = 0.1 } }\n"
         "transform = [{ scale = 0.2 }, { translate = [0, 0, 0.5] }]\n", "participating media"),
        ('\n[materials.coat]\ntype = "plastic"\nreflectance = { value = 0.5 }\n\n'
         '[[shapes]]\ntype = "cube"\nmaterial = "coat"\n'
         "transform = [{ scale = 0.05 }, { translate = [0.5, 0.5, 0.1] }]\n", "smooth coat"),
    ],
)  # fmt: skip
def test_refusals_in_one_line(device, tmp_path, extra, match):
    path = _write(tmp_path, _slab_scene(tmp_path, "sppm").read_text() + extra)
    with pytest.raises(SpectraceError, match=match):
        Renderer(spectrace.load_scene(path), device)


def test_spectral_output_refused(device, tmp_path):
    scene = spectrace.load_scene(_slab_scene(tmp_path, "sppm"))
    with pytest.raises(SpectraceError, match="spectral bands"):
        Renderer(scene, device, spectral_bins=4)


def test_a_tile_is_refused(device, tmp_path):
    renderer = Renderer(spectrace.load_scene(_slab_scene(tmp_path, "sppm")), device)
    renderer.pixel_range = (0, 8)
    with pytest.raises(SpectraceError, match="whole films"):
        renderer.run_pass(1)


def test_checkpoints_refused(device, tmp_path):
    from spectrace.engine.checkpoint import PeriodicCheckpoints

    renderer = Renderer(spectrace.load_scene(_slab_scene(tmp_path, "sppm")), device)
    with pytest.raises(SpectraceError, match="checkpoints"):
        PeriodicCheckpoints(tmp_path / "state.npz", renderer, 1.0)
    assert not (tmp_path / "state.npz").exists()
