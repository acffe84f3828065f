"""Homogeneous media inside closed shapes (docs/media.md), against closed-form transport and numpy quadrature.

The validation cases `medium-furnace` and `beer-lambert` (tests/render/test_validation.py runs them) check energy
conservation of the random walk and Beer–Lambert through whole renders; here the free-flight sampler and the
phase function are checked on their own, and shadow rays through index-matched boundaries against quadrature.
"""

import textwrap

import numpy as np
import pytest

import spectrace
from scene_text import CAMERA_FILM_GREY
from spectrace.core.contract import MEDIUM_DTYPE
from spectrace.engine.meters import IrradianceMeter, RadianceMeter, measure
from spectrace.errors import SpectraceError
from spectrace.geometry import primitives
from spectrace.geometry.transforms import apply_transform, transform_matrix
from spectrace.scene import load_scene
from spectrace.scene.model import AreaEmitter, Camera, ConstantEnvironment, DiffuseMaterial, Medium, Scene, Shape
from spectrace.spectral.colorimetry import reflectance_to_xyz, xyz_to_linear_srgb
from spectrace.spectral.grid import GRID_NM
from spectrace.spectral.illuminants import d65_normalised
from spectrace.spectral.media_presets import coefficient_spectrum, medium_presets
from spectrace.spectral.spectrum import Spectrum
from spectrace.spectral.table import SpectrumTable
from stats_toolkit import assert_chi_square_fits, assert_within_standard_errors, mean_and_standard_error

LANES_NM = np.array([420.0, 500.0, 580.0, 680.0])


def _wavy(mean: float, phase: float = 0.0) -> Spectrum:
    return Spectrum(mean * (1.0 + 0.7 * np.sin((GRID_NM - 360.0) / 40.0 + phase)))


# ---------------------------------------------------------------- the free-flight sampler


@pytest.mark.parametrize("hero_only", [0, 1])
def test_free_flight_weights_give_each_lane_its_own_transport(kernel_runner, hero_only):
    """Whatever lane's σt drew the distance, each lane's expected weight is its own: E[weight · 1(reached the
    surface)] = exp(−σt t_s) and E[weight · 1(scattered)] = σs/σt (1 − exp(−σt t_s))."""
    sigma_a, sigma_s = _wavy(0.8, 1.0), _wavy(2.0)
    table = SpectrumTable()
    table.add(Spectrum.zeros())  # a non-zero offset exercises the indexing
    medium = np.zeros(1, MEDIUM_DTYPE)
    medium["sigma_a_offset"], medium["sigma_s_offset"] = table.add(sigma_a), table.add(sigma_s)
    runner = kernel_runner("testing/medium_sampling.cl")
    n, t_surface = 200_000, 0.7
    scattered = np.empty((n, 4), np.float32)
    surface = np.empty((n, 4), np.float32)
    args = [
        runner.buffer(table.data),
        runner.buffer(medium),
        LANES_NM.astype(np.float32),
        np.float32(t_surface),
        np.int32(hero_only),
        np.uint32(3),
        runner.buffer(scattered, True),
        runner.buffer(surface, True),
    ]
    runner.run("free_flights", n, args, {6: scattered, 7: surface})
    sa, ss = sigma_a.evaluate(LANES_NM), sigma_s.evaluate(LANES_NM)
    st = sa + ss
    alive = np.array([1.0, 0.0, 0.0, 0.0]) if hero_only else np.ones(4)
    reached, scattered_share = np.exp(-st * t_surface), ss / st * (1 - np.exp(-st * t_surface))
    for weights, expected in ((surface, reached), (scattered, scattered_share)):
        mean, se = mean_and_standard_error(weights)
        assert_within_standard_errors(mean, alive * expected, se, slack=1e-6)
        assert np.all(se[alive > 0] < 0.02 * expected[alive > 0])  # tight enough to mean something


@pytest.mark.parametrize("g", [-0.6, 0.0, 0.3, 0.85])
def test_phase_sampling_follows_henyey_greenstein(kernel_runner, g):
    """Sampled cos θ against the Henyey–Greenstein CDF (chi-square over bins of equal probability), uniform φ,
    mean cosine g, and the phase value the kernel reports against the formula."""
    runner = kernel_runner("testing/medium_sampling.cl")
    n = 100_000
    directions = np.empty((n, 4), np.float32)
    phase = np.empty(n, np.float32)
    runner.run(
        "phase_samples",
        n,
        [np.float32(g), np.uint32(5), runner.buffer(directions, True), runner.buffer(phase, True)],
        {2: directions, 3: phase},
    )
    d = directions[:, :3].astype(np.float64)
    assert np.allclose(np.linalg.norm(d, axis=1), 1.0, atol=1e-5)
    mu = d[:, 2]

    def cdf(x):
        if abs(g) < 1e-3:
            return (x + 1) / 2
        return (1 - g * g) / (2 * g) * ((1 + g * g - 2 * g * x) ** -0.5 - 1 / (1 + g))

    edges = np.linspace(-1.0, 1.0, 41)
    expected = np.diff(cdf(edges)) * n
    assert_chi_square_fits(np.histogram(mu, edges)[0], expected, 1e-4, what="cos θ")
    phi_counts = np.histogram(np.arctan2(d[:, 1], d[:, 0]), np.linspace(-np.pi, np.pi, 17))[0]
    assert_chi_square_fits(phi_counts, np.full(16, n / 16), 1e-4, what="φ")
    mu_mean, mu_se = mean_and_standard_error(mu)
    assert_within_standard_errors(mu_mean, g, mu_se, what="mean cosine")
    formula = (1 - g * g) / (4 * np.pi * (1 + g * g - 2 * g * mu) ** 1.5)
    assert np.allclose(phase, formula, rtol=2e-4)


# ---------------------------------------------------------------- whole renders


def _scene(shapes, lights=(), max_depth=-1):
    return Scene(
        camera=Camera((0.0, 0.0, -1.0), (0.0, 0.0, 0.0)),
        width=1,
        height=1,
        shapes=list(shapes),
        lights=list(lights),
        max_depth=max_depth,
    )


@pytest.mark.parametrize(
    ("sigma_s", "max_depth"), [(0.0, -1), (0.4, 1)], ids=["pure-absorber", "scattering-medium-unscattered-part"]
)
def test_light_through_an_absorbing_medium_follows_beer_lambert(device, sigma_s, max_depth):
    """Looking through the centre of an index-matched sphere of radius 1 (its mesh has a vertex at each pole, so the
    chord is exactly 2) at an environment of radiance k: a pure absorber passes L = k exp(−σa · 2) at every
    depth; a scattering one, with emitters-only depth (no scattered light counted), passes its unscattered part
    k exp(−σt · 2). Per lane, the σ's varying over the spectrum."""
    k, chord = 1.0, 2.0
    medium = Medium(sigma_a=_wavy(0.4), sigma_s=_wavy(sigma_s, 2.0) if sigma_s else Spectrum.zeros(), g=0.5)
    sphere = Shape(mesh=primitives.sphere(3), material=None, interior=medium)
    scene = _scene([sphere], [ConstantEnvironment(Spectrum.constant(k))], max_depth=max_depth)
    reading = measure(
        scene,
        RadianceMeter((0.0, 0.0, -3.0), (0.0, 0.0, 1.0)),
        wavelengths_nm=LANES_NM,
        streams=32,
        samples_per_item=4096 if sigma_s else 8,
        device=device,
    )
    sigma_t = medium.sigma_a.evaluate(LANES_NM) + medium.sigma_s.evaluate(LANES_NM)
    expected = k * np.exp(-sigma_t * chord)
    # slack: float32 transmittance along the chord (the pure absorber's reading has no noise)
    assert_within_standard_errors(
        reading.spectral, expected, reading.spectral_standard_error, slack=1e-4 * expected, what=sigma_s, power=0.05
    )


def _slab(half_width: float, bottom: float, thickness: float):
    return apply_transform(
        primitives.cube(),
        transform_matrix(
            [{"scale": [half_width, thickness / 2, half_width]}, {"translate": [0.0, bottom + thickness / 2, 0.0]}],
            where="test",
        ),
    )


def _path_length_in_slab(dx, dy, dz, half_width, bottom, thickness):
    """Length of the ray origin + t·d (origin at 0, below the slab) inside the box, per direction."""
    with np.errstate(divide="ignore"):
        t_in = bottom / dy
        t_out = np.minimum.reduce([(bottom + thickness) / dy, half_width / np.abs(dx), half_width / np.abs(dz)])
    return np.maximum(t_out - t_in, 0.0)


def test_shadow_rays_through_an_index_matched_absorber_carry_its_transmittance(device):
    """Irradiance under an absorbing slab in a uniform environment: E = ∫ k exp(−σa L(ω)) cos θ dω (midpoint
    quadrature over the hemisphere). Next-event estimation sees the slab through its transmittance and MIS
    weighs it against the cosine-sampled rays; a blocking slab would lose the light-sampled share."""
    k, half_width, bottom, thickness = 1.0, 1.5, 0.2, 0.3
    sigma_a = _wavy(2.0)
    slab = Shape(
        mesh=_slab(half_width, bottom, thickness),
        material=None,
        interior=Medium(sigma_a=sigma_a, sigma_s=Spectrum.zeros()),
    )
    scene = _scene([slab], [ConstantEnvironment(Spectrum.constant(k))])
    wavelengths = LANES_NM[:2]
    reading = measure(
        scene,
        IrradianceMeter((0.0, 0.0, 0.0), (0.0, 1.0, 0.0)),
        wavelengths_nm=wavelengths,
        streams=64,
        samples_per_item=64,
        device=device,
    )
    mu = (np.arange(1000) + 0.5) / 1000
    phi = (np.arange(1000) + 0.5) / 1000 * 2 * np.pi
    mu, phi = np.meshgrid(mu, phi, indexing="ij")
    sin = np.sqrt(1 - mu**2)
    length = _path_length_in_slab(sin * np.cos(phi), mu, sin * np.sin(phi), half_width, bottom, thickness)
    for i, sa in enumerate(sigma_a.evaluate(wavelengths)):
        expected = k * np.mean(np.exp(-sa * length) * mu) * 2 * np.pi
        assert abs(reading.spectral[i] - expected) <= 4 * reading.spectral_standard_error[i] + 1e-3 * expected, (
            reading.spectral[i],
            expected,
            reading.spectral_standard_error[i],
        )
        assert expected < 0.8 * np.pi * k  # the slab matters


def test_an_area_light_behind_an_absorber_is_attenuated_for_both_strategies(device):
    """Irradiance from a square light (radiance Le, facing down) above an absorbing slab: E = ∫_A Le exp(−σa L)
    cos θ cos θ_light / r² dA, by midpoint quadrature over the light."""
    radiance, light_half, height = 2.0, 0.5, 1.0
    half_width, bottom, thickness = 1.5, 0.3, 0.25
    sigma_a = _wavy(1.5, 1.0)
    lamp_mesh = apply_transform(
        primitives.rectangle(),
        transform_matrix(
            [{"rotate": {"axis": [1, 0, 0], "angle": 90}}, {"scale": light_half}, {"translate": [0.0, height, 0.0]}],
            where="test",
        ),
    )
    lamp = Shape(
        mesh=lamp_mesh, material=DiffuseMaterial(Spectrum.zeros()), emitter=AreaEmitter(Spectrum.constant(radiance))
    )
    slab = Shape(
        mesh=_slab(half_width, bottom, thickness),
        material=None,
        interior=Medium(sigma_a=sigma_a, sigma_s=Spectrum.zeros()),
    )
    wavelengths = LANES_NM[2:]
    reading = measure(
        _scene([lamp, slab]),
        IrradianceMeter((0.0, 0.0, 0.0), (0.0, 1.0, 0.0)),
        wavelengths_nm=wavelengths,
        streams=64,
        samples_per_item=64,
        device=device,
    )
    grid = (np.arange(400) + 0.5) / 400 * 2 * light_half - light_half
    x, z = np.meshgrid(grid, grid, indexing="ij")
    r = np.sqrt(x**2 + z**2 + height**2)
    cos = height / r  # at the meter and at the light alike
    length = _path_length_in_slab(x / r, cos, z / r, half_width, bottom, thickness)
    area = (2 * light_half) ** 2
    for i, sa in enumerate(sigma_a.evaluate(wavelengths)):
        expected = radiance * np.mean(np.exp(-sa * length) * cos * cos / r**2) * area
        assert abs(reading.spectral[i] - expected) <= 4 * reading.spectral_standard_error[i] + 1e-3 * expected, (
            reading.spectral[i],
            expected,
            reading.spectral_standard_error[i],
        )


def test_a_null_boundary_costs_no_path_segment(device):
    """At max_depth 2 (direct light only), a diffuse plane of albedo ρ in a uniform environment k reflects ρk,
    also when seen through an index-matched box of vacuum (σa = σs = 0) that also hangs between it and half of
    its sky: crossing the boundaries adds no segment and blocks nothing."""
    plane = Shape(mesh=primitives.rectangle(), material=DiffuseMaterial(Spectrum.constant(0.5)))
    box = apply_transform(
        primitives.cube(), transform_matrix([{"scale": 0.5}, {"translate": [0, 0, 0.7]}], where="test")
    )
    vacuum = Shape(mesh=box, material=None, interior=Medium(Spectrum.zeros(), Spectrum.zeros()))
    light = ConstantEnvironment(Spectrum.constant(1.0))
    meter = RadianceMeter((0.0, 0.0, 2.0), (0.0, 0.0, -1.0))
    readings = [
        measure(
            _scene(shapes, [light], max_depth=2),
            meter,
            wavelengths_nm=[550.0],
            streams=16,
            samples_per_item=16,
            device=device,
        )
        for shapes in ([plane], [plane, vacuum])
    ]
    for reading in readings:
        assert abs(reading.spectral[0] - 0.5) <= 4 * reading.spectral_standard_error[0], reading.spectral
        assert reading.spectral_standard_error[0] < 0.01


# ---------------------------------------------------------------- scene files, presets, API

SCENE = (
    CAMERA_FILM_GREY
    + """
[[shapes]]
type = "sphere"
"""
)


def _load(tmp_path, shape: str):
    path = tmp_path / "scene.toml"
    path.write_text(SCENE + textwrap.dedent(shape) + "\n")
    return load_scene(path)


def test_interior_coefficients_load_in_inverse_scene_units(tmp_path):
    scene = _load(
        tmp_path, "interior = { sigma_a = { value = 0.5 }, sigma_s = { rgb = [1, 2, 3] }, scale = 10, g = 0.4 }"
    )
    shape = scene.shapes[0]
    assert shape.material is None
    assert shape.interior.sigma_a.values == pytest.approx(5.0)
    assert shape.interior.g == 0.4
    # rgb coefficients are unbounded: their colour is the triple's (times the scale)
    xyz = reflectance_to_xyz(shape.interior.sigma_s.values / 30.0, d65_normalised())
    assert xyz_to_linear_srgb(xyz) == pytest.approx(np.array([1, 2, 3]) / 3.0, abs=1e-3)


def test_presets_reproduce_the_published_table(tmp_path):
    scene = _load(tmp_path, 'material = "grey"\ninterior = { preset = "skin1", scale = 2.0 }')
    skin = medium_presets()["skin1"]
    assert skin.sigma_a_per_mm == (0.032, 0.17, 0.48) and skin.sigma_s_prime_per_mm == (0.74, 0.88, 1.01)
    interior = scene.shapes[0].interior
    for spectrum, rgb in ((interior.sigma_a, skin.sigma_a_per_mm), (interior.sigma_s, skin.sigma_s_prime_per_mm)):
        rendered = xyz_to_linear_srgb(reflectance_to_xyz(spectrum.values / 2.0, d65_normalised()))
        assert rendered == pytest.approx(np.array(rgb), rel=1e-3, abs=1e-5)
    assert set(medium_presets()) >= {"skin1", "skin2", "marble", "wholemilk", "skimmilk", "ketchup", "apple"}


@pytest.mark.parametrize(
    "shape, key, message",
    [
        ("", "shapes[0]", "needs material"),
        ('interior = { preset = "marbel" }', "shapes[0].interior.preset", "unknown medium preset 'marbel'"),
        ('interior = { preset = "marble", sigma_a = { value = 1 } }', "shapes[0].interior", "either preset or"),
        ("interior = { scale = 2 }", "shapes[0].interior", "either preset or"),
        ('interior = { preset = "marble", g = 1.0 }', "shapes[0].interior.g", "must be < 1"),
        ('interior = { preset = "marble", scale = 0 }', "shapes[0].interior.scale", "must be > 0"),
        ('interior = { preset = "marble", sigma = 1 }', "shapes[0].interior.sigma", "unknown key 'sigma'"),
        ("interior = { sigma_a = { value = -1 } }", "shapes[0].interior.sigma_a", "negative"),
        ("interior = { sigma_s = { blackbody = 3000 } }", "shapes[0].interior.sigma_s", "medium coefficient"),
    ],
)
def test_bad_interiors_are_reported_with_their_key_path(tmp_path, shape, key, message):
    with pytest.raises(SpectraceError) as error:
        _load(tmp_path, shape)
    assert error.value.where.endswith(f"scene.toml: {key}"), error.value.where
    assert message in error.value.message


def test_a_rectangle_cannot_have_an_interior(tmp_path):
    path = tmp_path / "scene.toml"
    path.write_text((SCENE + 'interior = { preset = "marble" }\n').replace('"sphere"', '"rectangle"'))
    with pytest.raises(SpectraceError, match="encloses no volume"):
        load_scene(path)


def test_api_builds_the_same_medium_as_a_scene_file(tmp_path):
    from_file = _load(tmp_path, 'interior = { preset = "wholemilk", scale = 5, g = 0.2 }').shapes[0].interior
    from_api = spectrace.medium(preset="wholemilk", scale=5, g=0.2)
    assert from_api.sigma_a == from_file.sigma_a and from_api.sigma_s == from_file.sigma_s and from_api.g == 0.2
    # a preset keeps its reduced scattering coefficient σs' = σs (1 − g)
    isotropic = spectrace.medium(preset="wholemilk", scale=5)
    assert from_api.sigma_s.values * (1 - 0.2) == pytest.approx(isotropic.sigma_s.values)
    custom = spectrace.medium(sigma_a=0.1, sigma_s=(1.0, 2.0, 3.0), scale=2.0)
    assert custom.sigma_a.values == pytest.approx(0.2)
    assert custom.sigma_s == coefficient_spectrum((1.0, 2.0, 3.0)).scaled(2.0)
    shape = spectrace.shape("sphere", interior=custom)
    assert shape.material is None and shape.interior is custom
    with pytest.raises(SpectraceError, match="needs a material"):
        spectrace.shape("sphere")
    with pytest.raises(SpectraceError, match="g must lie"):
        spectrace.medium(preset="marble", g=-1.0)


def test_spectra_listing_shows_coefficients_as_written(tmp_path):
    from spectrace.scene.spectra_index import scene_spectra

    _load(tmp_path, "interior = { sigma_a = { value = 0.25 }, sigma_s = { rgb = [1, 2, 3] }, scale = 4 }")
    spectra = scene_spectra(tmp_path / "scene.toml")
    assert spectra["shapes[0].interior.sigma_a"].values == pytest.approx(0.25)
    assert spectra["shapes[0].interior.sigma_s"] == coefficient_spectrum((1, 2, 3))
