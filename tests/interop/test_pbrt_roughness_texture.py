"""pbrt-v4's float textures as a material's roughness: an imagemap becomes a one-channel texture of GGX α per
texel (pbrt's float lookup averages the channels; `remaproughness`, default true, takes α = √roughness of the value
it looks up), a constant one a number."""

from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from replica_agreement import assert_replicas_agree, spectrace_replicas
from spectrace.engine.renderer import Renderer
from spectrace.interop.pbrt import import_pbrt, load_pbrt_scene

HEADER = """LookAt 0 3 3  0 0 0  0 1 0
Camera "perspective" "float fov" 40
Film "rgb" "integer xresolution" 16 "integer yresolution" 16
Sampler "independent" "integer pixelsamples" 64
WorldBegin
LightSource "point" "point3 from" [0.5 2 1] "float power" 40
"""
PLANE = """Shape "trianglemesh" "point3 P" [-2 0 2  2 0 2  2 0 -2  -2 0 -2] "integer indices" [0 1 2  0 2 3]
  "point2 uv" [0 0  1 0  1 1  0 1]
"""


def _scene(tmp_path: Path, roughness: str, remap: bool = True) -> Path:
    path = tmp_path / "rough.pbrt"
    path.write_text(
        HEADER
        + 'Texture "bumps" "float" "imagemap" "string filename" "rough.png" "string encoding" "linear"\n'
        + f'Material "conductor" {roughness} "bool remaproughness" {str(remap).lower()}\n'
        + PLANE
    )
    return path


@pytest.mark.parametrize("remap", [True, False])
def test_an_imagemap_roughness_becomes_alpha_per_texel(tmp_path, remap):
    rgb = np.array([[[10, 20, 30], [200, 100, 0]], [[64, 64, 64], [255, 255, 255]]], np.uint8)
    Image.fromarray(rgb).save(tmp_path / "rough.png")
    warnings, _ = import_pbrt(_scene(tmp_path, '"texture roughness" "bumps"', remap), tmp_path / "out.toml")
    assert not warnings
    import tomllib

    data = tomllib.loads((tmp_path / "out.toml").read_text())
    texture = next(iter(data["materials"].values()))["roughness"]
    assert texture["texture"] == "bitmap" and texture["raw"] is True
    alpha = np.asarray(Image.open(tmp_path / texture["file"]), np.float64)
    roughness = rgb.mean(axis=-1) / 255.0  # linear encoding; pbrt averages the channels of a float lookup
    np.testing.assert_allclose(alpha, np.sqrt(roughness) if remap else roughness, rtol=1e-6)


def test_a_uniform_roughness_image_renders_as_the_number(tmp_path, device):
    """A roughness image of one value everywhere and the same roughness as a number: 8 replicas of 16 spp each,
    4 x 4-pixel block means within 5 standard errors (tests/replica_agreement.py). Measured: α 0.2 against
    √0.2 (the remapping left out) differs by 300 standard errors in the highlight's block."""
    Image.fromarray(np.full((4, 4), 51, np.uint8)).save(tmp_path / "rough.png")  # 0.2 in linear encoding
    textured, number = (
        spectrace_replicas(Renderer(load_pbrt_scene(_scene(tmp_path, roughness)), device), 8, 16)
        for roughness in ('"texture roughness" "bumps"', '"float roughness" 0.2')
    )
    assert_replicas_agree(textured, number, 4)
    assert number[..., 1].mean() > 0.0


@pytest.mark.parametrize("factor", ['"float scale" 0.1', '"texture scale" "tenth"'])
def test_a_scaled_imagemap_roughness_is_alpha_of_the_scaled_texels(tmp_path, factor):
    """pbrt-v4's scenes scale a float imagemap by a `scale` texture (a number, or a constant texture) before
    using it as a roughness (its crown scene does): α = √(0.1 · texel) per texel."""
    grey = np.array([[10, 200], [64, 255]], np.uint8)
    Image.fromarray(grey).save(tmp_path / "rough.png")
    path = _scene(tmp_path, '"texture roughness" "scaled"')
    path.write_text(
        path.read_text().replace(
            'Material "conductor"',
            'Texture "tenth" "float" "constant" "float value" 0.1\n'
            f'Texture "scaled" "float" "scale" "texture tex" "bumps" {factor}\nMaterial "conductor"',
        )
    )
    warnings, _ = import_pbrt(path, tmp_path / "out.toml")
    assert not warnings
    import tomllib

    data = tomllib.loads((tmp_path / "out.toml").read_text())
    texture = next(iter(data["materials"].values()))["roughness"]
    alpha = np.asarray(Image.open(tmp_path / texture["file"]), np.float64)
    np.testing.assert_allclose(alpha, np.sqrt(0.1 * grey / 255.0), rtol=1e-6)
