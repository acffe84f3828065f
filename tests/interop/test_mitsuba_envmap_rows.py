"""Mitsuba 3's envmap puts its first and last texel rows on the poles, π / (height − 1) apart, and interpolates
between them; spectrace's map splits the sphere into height bands. The import says `rows = "poles"`, which reads
the map as the height − 1 bands between neighbouring rows, each the interpolation's mean over its solid angle.
Checked against the closed form of that interpolation and against Mitsuba 3 rendering the same XML, with a
grey map (so that Mitsuba's spectral lookup, which interpolates its uplift's spectra and scales apart, is exact)
whose light falls steeply from a bright zenith: read as height bands, its irradiance on a level plane is 10 %
too high."""

import numpy as np
import pytest

from replica_agreement import assert_renders_like_mitsuba
from scene_text import mitsuba_envmap_over_plate
from spectrace.errors import SpectraceError
from spectrace.interop.mitsuba import load_mitsuba_scene, mitsuba_scene_data
from spectrace.lights.envmap import pole_rows_as_bands

HEIGHT, WIDTH = 33, 8
ALBEDO = 0.5


def _rows() -> np.ndarray:
    """Each row's radiance: a glow around the zenith over a dim sky, sampled at Mitsuba's row angles."""
    theta = np.arange(HEIGHT) * np.pi / (HEIGHT - 1)
    return 0.5 + 8.0 * np.exp(-((theta / 0.4) ** 2))


def _xml(folder, size: int):
    from spectrace.io.exr import write_exr

    image = np.repeat(np.repeat(_rows()[:, None, None], WIDTH, axis=1), 3, axis=2).astype(np.float32)
    write_exr(folder / "glow.exr", image, None, {})
    path = folder / "level_plane.xml"
    path.write_text(mitsuba_envmap_over_plate("glow.exr", f"{ALBEDO}", size))
    return path


def _level_irradiance(radiance_of_theta) -> float:
    """E = 2π ∫ L(θ) cos θ sin θ dθ over the upper hemisphere, for a map that does not vary with azimuth."""
    theta = np.linspace(0.0, np.pi / 2, 200_001)
    return float(2 * np.pi * np.trapezoid(radiance_of_theta(theta) * np.cos(theta) * np.sin(theta), theta))


def test_pole_rows_become_bands_holding_the_interpolations_mean():
    """Each band's value is ∫ L sin θ dθ / ∫ sin θ dθ of the linear interpolation over it (quadrature)."""
    rows = np.random.default_rng(7).uniform(0.0, 5.0, (7, 2, 3))
    bands = pole_rows_as_bands(rows)
    assert bands.shape == (6, 2, 3)
    angles = np.arange(7) * np.pi / 6
    for band in range(6):
        theta = np.linspace(angles[band], angles[band + 1], 20_001)
        for column in range(2):
            for channel in range(3):
                radiance = np.interp(theta, angles, rows[:, column, channel])
                mean = np.trapezoid(radiance * np.sin(theta), theta) / np.trapezoid(np.sin(theta), theta)
                assert bands[band, column, channel] == pytest.approx(mean, rel=1e-6)


def test_imported_map_gives_the_level_irradiance_of_mitsubas_interpolation(tmp_path):
    """The import's bands, looked up as spectrace does (the nearest band), give the irradiance of Mitsuba's
    interpolated map within 0.2 % (the light's change within a band); the map's rows read as bands would give 10 %
    more."""
    data, _ = mitsuba_scene_data(_xml(tmp_path, 4))
    assert data["lights"][0]["rows"] == "poles"
    (light,) = load_mitsuba_scene(_xml(tmp_path, 4)).lights
    assert light.rgb.shape == (HEIGHT - 1, WIDTH, 3)
    angles = np.arange(HEIGHT) * np.pi / (HEIGHT - 1)
    exact = _level_irradiance(lambda theta: np.interp(theta, angles, _rows()))
    bands = light.rgb[:, 0, 1]
    imported = _level_irradiance(lambda theta: bands[np.minimum((theta / np.pi * (HEIGHT - 1)).astype(int), 31)])
    as_bands = _level_irradiance(lambda theta: _rows()[np.minimum((theta / np.pi * HEIGHT).astype(int), HEIGHT - 1)])
    assert imported == pytest.approx(exact, rel=2e-3)
    assert as_bands / exact > 1.08  # what the test below would catch


def test_rows_in_a_scene_file(tmp_path):
    """`rows = "poles"` reads a map of height rows as height − 1 bands; another word is refused, naming the key."""
    from spectrace.io.exr import write_exr
    from spectrace.scene import load_scene

    write_exr(tmp_path / "sky.exr", np.ones((4, 8, 3), np.float32), None, {})
    scene = tmp_path / "scene.toml"
    for rows, height in (("bands", 4), ("poles", 3)):
        scene.write_text(
            "[camera]\norigin = [0, 0, -1]\ntarget = [0, 0, 0]\nfov = 40\n[film]\nwidth = 1\nheight = 1\n"
            f'[materials]\n[[lights]]\ntype = "envmap"\nfile = "sky.exr"\nrows = "{rows}"\n'
        )
        (light,) = load_scene(scene).lights
        assert light.rgb.shape == (height, 8, 3)
        np.testing.assert_allclose(light.rgb, 1.0, rtol=1e-6)  # a uniform sky stays uniform
    scene.write_text(scene.read_text().replace('"poles"', '"edges"'))
    with pytest.raises(SpectraceError, match=r"lights\[0\]\.rows.*bands, poles"):
        load_scene(scene)


@pytest.mark.peer
def test_level_plane_under_a_glowing_zenith_renders_like_mitsuba(tmp_path, device, mitsuba_scalar_spectral):
    """Both renderers, spectral, 8 replicas each; 4 x 4-pixel block means and the image mean agree within 5
    standard errors (tests/replica_agreement.py)."""
    mi = mitsuba_scalar_spectral
    replicas, replica_spp, size, block = 8, 64, 8, 4
    by_mitsuba = assert_renders_like_mitsuba(mi, _xml(tmp_path, size), device, replicas, replica_spp, block)
    angles = np.arange(HEIGHT) * np.pi / (HEIGHT - 1)
    expected = ALBEDO / np.pi * _level_irradiance(lambda theta: np.interp(theta, angles, _rows()))
    # Mitsuba itself renders the closed form (its 4σ, from the replicas' spread).
    means = by_mitsuba.mean(axis=(1, 2, 3))
    assert abs(means.mean() - expected) < 4 * means.std(ddof=1) / np.sqrt(len(means)) + 1e-3 * expected
