"""The ΔE map's reference white is the scene's own: CIELAB is relative to the white the eye adapts to, so a dim
scene (the display booths, film Y ~1e-4) must not be measured against a white of film Y = 1, which puts every pixel
near L* = 0 where all colours meet."""

import numpy as np
import pytest
from PIL import Image as PILImage

from cli_runner import run_spectrace
from spectrace.film.response import FilmResponse, scene_white_y
from spectrace.resources import scenes_dir

colour = pytest.importorskip("colour")

_PAIR = ("CIE 1931 2°", "CIE 1964 10°")


def test_the_scene_white_is_the_brightest_area_not_a_firefly():
    rng = np.random.default_rng(5)
    film_y = rng.uniform(0.0, 2e-5, (40, 60))
    film_y[10:14, 20:24] = 7e-5  # a white patch, 4 x 4 pixels
    film_y[30, 50] = 3e-3  # one firefly, 40 times brighter
    film_y[2, 2:4] = 1e-3  # two bright pixels side by side
    assert scene_white_y(film_y) == pytest.approx(7e-5)
    assert scene_white_y(np.zeros((3, 3))) == 1.0


def test_the_map_against_the_scene_white_does_not_depend_on_the_light_level():
    """CIELAB of XYZ / Y_n with Y_n the scene's white: scaling every radiance by k scales Y_n by k, so the map is
    the same; against a fixed white Y = 1 it changes (and at Y ~ 1e-4 nearly vanishes)."""
    rng = np.random.default_rng(3)
    first = rng.uniform(0.05, 1.0, (12, 16, 3))
    second = first * rng.uniform(0.9, 1.1, (12, 16, 3))
    response = FilmResponse(observers=_PAIR, delta_e_pair=_PAIR)
    fixed = FilmResponse(observers=_PAIR, delta_e_pair=_PAIR, delta_e_white_y=1.0)
    names = response.channel_names

    def delta_e(film: FilmResponse, scale: float) -> np.ndarray:
        responses = np.concatenate([first, second], axis=-1) * scale
        assert len(names) == 6
        return film.outputs(first[..., :3] * scale, responses.astype(np.float32))[1]["deltaE00"]

    bright, dim = delta_e(response, 1.0), delta_e(response, 1e-4)
    np.testing.assert_allclose(dim, bright, rtol=2e-3, atol=2e-3)
    assert bright.mean() > 1.0
    assert delta_e(fixed, 1e-4).mean() < 0.05 * bright.mean()


@pytest.mark.slow
@pytest.mark.subprocess
def test_the_booth_scene_map_is_measured_against_its_own_white(tmp_path):
    """The two display booths seen by the 2° and the 10° observer: against the booths' own white the mean ΔE2000 is
    of order 1 (against film Y = 1 it was 0.002), and the map is also a false-colour picture with its scale."""
    text = (scenes_dir() / "display_lcd_vs_led.toml").read_text()
    text = text.replace("[film]\n", f'[film]\nobservers = ["{_PAIR[0]}", "{_PAIR[1]}"]\n', 1)
    (tmp_path / "booths.toml").write_text(text)
    out = tmp_path / "booths.exr"
    arguments = ["--width", "96", "--height", "48", "--spp", "16", "--delta-e-map"]
    result = run_spectrace("render", str(tmp_path / "booths.toml"), "-o", str(out), *arguments)
    assert result.returncode == 0, result.stderr
    from spectrace.io.exr import read_exr

    channels, _ = read_exr(out)
    assert 0.3 < float(np.mean(channels["deltaE00"])) < 5.0
    picture = tmp_path / "booths.deltaE00.png"
    with PILImage.open(picture) as map_image:
        assert map_image.width > 96 and map_image.height > 48  # the map with its title and colour bar
    assert "white Y_n" in result.stdout + result.stderr
