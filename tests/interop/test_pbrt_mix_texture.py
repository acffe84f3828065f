"""pbrt-v4's `mix` texture, (1 − amount) · tex1 + amount · tex2 (its MixTexture; defaults tex1 0, tex2 1, amount
0.5), imported as spectrace's mix texture: operands given as values or as textures (constant ones, images), float
and spectrum mixes, and what spectrace's mix cannot hold (a composite operand) refused at its line."""

from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from spectrace.engine.renderer import Renderer
from spectrace.errors import SpectraceError
from spectrace.interop.pbrt import load_pbrt_scene, pbrt_scene_data
from spectrace.spectral.spectrum import Spectrum
from spectrace.textures.bitmap import BitmapTexture
from spectrace.textures.mix import MixTexture

# A plane filling the view under a constant sky; maxdepth 1 is direct light only, linear in the albedo.
HEADER = """LookAt 0 0 5  0 0 0  0 1 0
Camera "perspective" "float fov" 30
Film "rgb" "integer xresolution" 16 "integer yresolution" 16
Sampler "independent" "integer pixelsamples" 4
Integrator "path" "integer maxdepth" 1
WorldBegin
LightSource "infinite" "rgb L" [1 1 1]
"""
PLANE = """Shape "trianglemesh" "point3 P" [-10 -10 0  10 -10 0  10 10 0  -10 10 0]
  "integer indices" [0 1 2  0 2 3]  "point2 uv" [0 0  1 0  1 1  0 1]
"""


def _write(tmp_path: Path, textures: str, reflectance: str = '"texture reflectance" "m"') -> Path:
    path = tmp_path / "mix.pbrt"
    path.write_text(HEADER + textures + f'Material "diffuse" {reflectance}\n' + PLANE)
    return path


def test_a_mix_of_two_constants_imports_their_values_and_amount(tmp_path):
    """rgb and float constants as operands, a constant float texture as the amount: the mix holds the same
    spectra a diffuse reflectance of those values gets, and the amount as a number."""
    path = _write(
        tmp_path,
        'Texture "half" "spectrum" "constant" "float value" 0.5\nTexture "a" "float" "constant" "float value" 0.3\n'
        'Texture "m" "spectrum" "mix" "rgb tex1" [0.2 0.4 0.6] "texture tex2" "half" "texture amount" "a"\n',
    )
    (shape,) = load_pbrt_scene(path).shapes
    mix = shape.material.reflectance
    assert isinstance(mix, MixTexture)
    assert mix.amount == pytest.approx(0.3)
    assert isinstance(mix.tex2, Spectrum) and np.all(mix.tex2.values == np.float32(0.5))
    (plain,) = load_pbrt_scene(_write(tmp_path, "", '"rgb reflectance" [0.2 0.4 0.6]')).shapes
    assert np.array_equal(mix.tex1.values, plain.material.reflectance.values)


def test_a_mix_of_constants_renders_as_the_blended_reflectance(tmp_path, device):
    """(1 − 0.25) · 0.2 + 0.25 · 0.6 = 0.3: the mixed plane's image is that of a plane of albedo 0.3 (same seed:
    equal to float rounding), and not that of the swapped weights (0.5)."""
    mixed = _write(tmp_path, 'Texture "m" "spectrum" "mix" "float tex1" 0.2 "float tex2" 0.6 "float amount" 0.25\n')
    image = Renderer(load_pbrt_scene(mixed), device).render().xyz
    reference = Renderer(load_pbrt_scene(_write(tmp_path, "", '"float reflectance" 0.3')), device).render().xyz
    np.testing.assert_allclose(image, reference, rtol=1e-5, atol=1e-7)
    swapped = Renderer(load_pbrt_scene(_write(tmp_path, "", '"float reflectance" 0.5')), device).render().xyz
    assert np.mean(swapped) > 1.5 * np.mean(image)


def test_image_operands_and_an_image_amount_import_as_bitmaps(tmp_path):
    """An imagemap as tex1 of a spectrum mix, and a float mix whose amount is a grey imagemap (pbrt's float
    textures: a float mix used as a mix material's amount is a float texture too)."""
    Image.fromarray(np.full((4, 4, 3), 128, np.uint8)).save(tmp_path / "colour.png")
    Image.fromarray(np.full((4, 4), 64, np.uint8)).save(tmp_path / "grey.png")
    path = _write(
        tmp_path,
        'Texture "img" "spectrum" "imagemap" "string filename" "colour.png"\n'
        'Texture "g" "float" "imagemap" "string filename" "grey.png"\n'
        'Texture "m" "spectrum" "mix" "texture tex1" "img" "rgb tex2" [0.1 0.1 0.1] "texture amount" "g"\n',
    )
    data, _ = pbrt_scene_data(path)
    (table,) = data["textures"].values()
    assert table["type"] == "mix" and table["tex1"]["texture"] == "bitmap" and table["amount"]["texture"] == "bitmap"
    (shape,) = load_pbrt_scene(path).shapes
    mix = shape.material.reflectance
    assert isinstance(mix.tex1, BitmapTexture) and isinstance(mix.amount, BitmapTexture)
    # sRGB 128 and 64 decoded: the closed form of the sRGB curve, not the importer's numbers.
    assert mix.tex1.values[0, 0, 0] == pytest.approx(((128 / 255 + 0.055) / 1.055) ** 2.4, rel=1e-4)
    assert mix.amount.values[0, 0, 0] == pytest.approx(((64 / 255 + 0.055) / 1.055) ** 2.4, rel=1e-4)


@pytest.mark.parametrize(
    "textures, line, message",
    [
        (
            'Texture "c" "spectrum" "checkerboard"\nTexture "m" "spectrum" "mix" "texture tex2" "c"\n',
            9,
            'a checkerboard texture as "tex2" (spectrace\'s mix takes spectra, image and solid textures)',
        ),
        ('Texture "m" "spectrum" "mix" "texture tex1" "nothing"\n', 8, "names 'nothing', which no Texture defined"),
        # The amount is a float texture: a spectrum texture of that name is not it.
        (
            'Texture "s" "spectrum" "constant" "float value" 0.5\nTexture "m" "spectrum" "mix" "texture amount" "s"\n',
            9,
            "names 's', which no Texture defined",
        ),
    ],
)
def test_what_spectraces_mix_cannot_take_is_refused_at_its_line(tmp_path, textures, line, message):
    path = _write(tmp_path, textures)
    with pytest.raises(SpectraceError) as failure:
        pbrt_scene_data(path)
    assert failure.value.where == f"{path}:{line}"
    assert message in failure.value.message


def test_the_composites_the_mix_import_refuses_are_the_registrys():
    from spectrace.textures import COMPOSITE_TEXTURES
    from spectrace.textures.mix import PBRT_COMPOSITES

    assert sorted(PBRT_COMPOSITES) == sorted(COMPOSITE_TEXTURES)
