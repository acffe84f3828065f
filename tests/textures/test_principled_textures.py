"""Every textured parameter of the principled material: a texture of two constant halves renders each half as the
untextured material with that half's value does (region means of the pixel differences within 4 standard errors),
so each weight's texture reaches its lobe through the material's parameter block. Lit by a small sphere light beside
a dim environment, as the roughness halves of test_textured_parameters.py."""

from dataclasses import replace

import numpy as np
import pytest

import spectrace
from spectrace.engine.renderer import Renderer
from stats_toolkit import assert_within_standard_errors, mean_and_standard_error
from textures.test_textured_parameters import HALF, _quad_scene, _sigmoid_spectrum

pytestmark = pytest.mark.slow

# weight: (left, right), the other parameters of the material
HALVES = {
    "roughness": ((0.2, 0.7), {"metallic": 1.0, "base_color": 0.9}),
    "anisotropic": ((0.0, 0.9), {"metallic": 1.0, "base_color": 0.9, "roughness": 0.5}),
    "metallic": ((0.0, 1.0), {"base_color": 0.7, "roughness": 0.4}),
    "spec_trans": ((0.0, 1.0), {"base_color": 0.8, "roughness": 0.4}),
    "spec_tint": ((0.0, 1.0), {"base_color": (0.8, 0.3, 0.1), "roughness": 0.3}),
    "sheen": ((0.0, 1.0), {"base_color": 0.4, "roughness": 0.5}),
    "sheen_tint": ((0.0, 1.0), {"base_color": (0.2, 0.7, 0.3), "roughness": 0.5, "sheen": 1.0}),
    "clearcoat": ((0.0, 1.0), {"base_color": 0.3, "roughness": 0.8}),
    "clearcoat_gloss": ((0.0, 1.0), {"base_color": 0.3, "roughness": 0.8, "clearcoat": 1.0}),
}


def _render(device, material):
    light = spectrace.shape(
        "sphere",
        spectrace.diffuse(0.0),
        emitter=spectrace.area_emitter(20.0),
        transform=[{"scale": 0.25}, {"translate": [0.5, 0.4, 2.0]}],
    )
    scene = _quad_scene(material, lights=[spectrace.constant_environment(0.2)], max_depth=4, spp=16)
    return Renderer(replace(scene, shapes=[*scene.shapes, light]), device).render().xyz


@pytest.mark.parametrize("weight", list(HALVES))
def test_weight_texture_halves_render_as_the_untextured_material(device, weight):
    values, others = HALVES[weight]
    texture = spectrace.bitmap(np.array([list(values)]), filter="nearest")
    textured = _render(device, spectrace.principled(**others, **{weight: texture}))
    for half, value in enumerate(values):
        columns = slice(half * HALF + 1, (half + 1) * HALF - 1)
        plain = _render(device, spectrace.principled(**others, **{weight: value}))
        assert plain[:, columns].mean() > 0.01, "the untextured render must see the material"
        difference = (textured[:, columns] - plain[:, columns]).reshape(-1, 3)
        mean, error = mean_and_standard_error(difference)
        assert_within_standard_errors(mean, 0.0, error, slack=1e-6, what=(weight, value))


def test_textured_halves_differ_where_the_weight_matters(device):
    """The check above can fail: metallic 0 | 1 renders unlike a uniform metallic 0 on the metal half."""
    texture = spectrace.bitmap(np.array([[0.0, 1.0]]), filter="nearest")
    textured = _render(device, spectrace.principled(0.7, roughness=0.4, metallic=texture))
    plain = _render(device, spectrace.principled(0.7, roughness=0.4, metallic=0.0))
    columns = slice(HALF + 1, 2 * HALF - 1)
    mean, error = mean_and_standard_error((textured[:, columns] - plain[:, columns]).reshape(-1, 3))
    assert np.all(np.abs(mean) > 6 * error)


def test_base_color_texture_halves_render_as_the_untextured_material(device):
    """Grey texels, whose uplifted spectra are constants to within their spread (their mean, computed from the
    texture's own coefficients)."""
    texels = np.repeat(np.array([[0.2, 0.8]])[..., None], 3, axis=-1)
    textured = _render(device, spectrace.principled(spectrace.bitmap(texels, filter="nearest"), roughness=0.5))
    for half in range(2):
        columns = slice(half * HALF + 1, (half + 1) * HALF - 1)
        spectrum = _sigmoid_spectrum(texels[0, half])
        spread = np.ptp(spectrum) / spectrum.mean()
        assert spread < 1e-3
        plain = _render(device, spectrace.principled(float(spectrum.mean()), roughness=0.5))
        mean, error = mean_and_standard_error((textured[:, columns] - plain[:, columns]).reshape(-1, 3))
        # The same random numbers: the texel's spectrum differs from its mean by at most its spread.
        slack = spread * plain[:, columns].mean() + 1e-6
        assert_within_standard_errors(mean, 0.0, error, slack=slack, what=spectrum.mean())
