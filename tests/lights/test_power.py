"""A light given by its power: the flux it emits is that power, and a scene file and the Python API turn the same
power into the same intensity, bit for bit (one conversion, in spectrace/lights/point.py)."""

import numpy as np
import pytest

import spectrace
from scene_text import CAMERA_FILM_GREY
from spectrace.errors import SpectraceError
from spectrace.scene.loader import load_scene
from spectrace.spectral.grid import GRID_NM

SPOT = dict(position=(0.0, 2.0, 0.0), target=(0.3, 0.0, 0.1), cutoff_angle=40.0, falloff_start=15.0)


def _scene(tmp_path, light: str):
    path = tmp_path / "scene.toml"
    path.write_text(CAMERA_FILM_GREY + "\n[[lights]]\n" + light, encoding="utf-8")
    return path


def _flux_per_steradian_of_axis(intensity) -> float:
    """∫ I(λ) dλ, W/sr, by numpy's trapezoid rule on the grid."""
    return float(np.trapezoid(intensity.values, GRID_NM))


def test_point_light_power_is_its_flux(tmp_path):
    light = load_scene(
        _scene(tmp_path, 'type = "point"\nposition = [0, 2, 0]\npower = 60\nspectrum = { spectrum = "cie:A" }\n')
    ).lights[0]
    assert 4.0 * np.pi * _flux_per_steradian_of_axis(light.intensity) == pytest.approx(60.0, rel=1e-12)


def test_spot_light_power_is_its_flux():
    light = spectrace.spot_light(**SPOT, power_w=25.0, spectrum="cie:D65")
    # The falloff is a smoothstep in cos θ between the two angles: integrate it over the sphere numerically.
    cos_start, cos_cut = np.cos(np.radians(15.0)), np.cos(np.radians(40.0))
    mu = np.linspace(-1.0, 1.0, 2_000_001)
    t = np.clip((mu - cos_cut) / (cos_start - cos_cut), 0.0, 1.0)
    solid_angle = 2.0 * np.pi * np.trapezoid(t * t * (3.0 - 2.0 * t), mu)
    assert solid_angle * _flux_per_steradian_of_axis(light.intensity) == pytest.approx(25.0, rel=1e-6)


def test_linear_falloff_spot_light_power_is_its_flux():
    light = spectrace.spot_light(**SPOT, power_w=25.0, spectrum="cie:D65", linear_falloff=True)
    # Mitsuba 3's profile, linear in the angle θ between the two cones: integrate it over the sphere numerically.
    theta = np.linspace(0.0, np.pi, 2_000_001)
    falloff = np.clip((np.radians(40.0) - theta) / np.radians(40.0 - 15.0), 0.0, 1.0)
    solid_angle = 2.0 * np.pi * np.trapezoid(falloff * np.sin(theta), theta)
    assert solid_angle * _flux_per_steradian_of_axis(light.intensity) == pytest.approx(25.0, rel=1e-6)


def test_scene_file_and_api_give_the_same_intensity(tmp_path):
    point = load_scene(
        _scene(tmp_path, 'type = "point"\nposition = [0, 2, 0]\npower = 60\nspectrum = { spectrum = "cie:A" }\n')
    ).lights[0]
    assert np.array_equal(
        point.intensity.values, spectrace.point_light((0, 2, 0), power_w=60.0, spectrum="cie:A").intensity.values
    )
    spot = load_scene(
        _scene(
            tmp_path,
            'type = "spot"\nposition = [0, 2, 0]\ntarget = [0.3, 0, 0.1]\n'
            "cutoff_angle = 40\nfalloff_start = 15\npower = 25\n",
        )
    ).lights[0]
    api_spot = spectrace.spot_light(**SPOT, power_w=25.0)
    assert np.array_equal(spot.intensity.values, api_spot.intensity.values)
    assert (spot.direction, spot.cutoff_degrees, spot.falloff_start_degrees) == (
        api_spot.direction,
        api_spot.cutoff_degrees,
        api_spot.falloff_start_degrees,
    )


def test_the_same_rules_refuse_the_same_lights(tmp_path):
    for light, api_call, key, message in [
        (
            'type = "point"\nposition = [0, 2, 0]\npower = 5\nspectrum = { value = 0 }\n',
            lambda: spectrace.point_light((0, 2, 0), power_w=5.0, spectrum=0.0),
            "lights[0]",
            "must not be zero",
        ),
        (
            'type = "point"\nposition = [0, 2, 0]\npower = -5\n',
            lambda: spectrace.point_light((0, 2, 0), power_w=-5.0),
            "lights[0]",
            "power must be >= 0 W",
        ),
        (
            'type = "spot"\nposition = [0, 2, 0]\ntarget = [0, 0, 0]\ncutoff_angle = 20\nfalloff_start = 25\n'
            "power = 1\n",
            lambda: spectrace.spot_light((0, 2, 0), (0, 0, 0), 20.0, 25.0, power_w=1.0),
            "lights[0].falloff_start",
            "falloff_start (25.0) exceeds cutoff_angle (20.0)",
        ),
    ]:
        path = _scene(tmp_path, light)
        with pytest.raises(SpectraceError, match=message.replace("(", r"\(").replace(")", r"\)")) as error:
            load_scene(path)
        assert error.value.where == f"{path}: {key}"
        with pytest.raises(SpectraceError, match=message.replace("(", r"\(").replace(")", r"\)")):
            api_call()
