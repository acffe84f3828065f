"""pbrt-v4's `mix` material: pbrt chooses, at each intersection, the second of its two materials with probability
`amount` (a hash of the point and direction: its MixMaterial::ChooseMaterial), so a pixel converges to the
amount-weighted blend of the two BSDFs. Checked here against that definition: with direct light only an image is
linear in the reflectance, so the mix's image is (1 − amount) · image(first) + amount · image(second)."""

from pathlib import Path

import numpy as np
import pytest

from spectrace.engine.renderer import Renderer
from spectrace.errors import SpectraceError
from spectrace.interop.pbrt import load_pbrt_scene, pbrt_scene_data

# A plane filling the view under a constant sky; pbrt's maxdepth 1 is direct light only.
HEADER = """LookAt 0 0 5  0 0 0  0 1 0
Camera "perspective" "float fov" 30
Film "rgb" "integer xresolution" 16 "integer yresolution" 16
Sampler "independent" "integer pixelsamples" 16
Integrator "path" "integer maxdepth" 1
WorldBegin
LightSource "infinite" "rgb L" [1 1 1]
MakeNamedMaterial "red" "string type" "diffuse" "rgb reflectance" [0.8 0.15 0.1]
MakeNamedMaterial "blue" "string type" "diffuse" "rgb reflectance" [0.1 0.2 0.7]
"""
PLANE = """Shape "trianglemesh" "point3 P" [-10 -10 0  10 -10 0  10 10 0  -10 10 0]
  "integer indices" [0 1 2  0 2 3]
"""


def _render(tmp_path: Path, material: str, device) -> np.ndarray:
    path = tmp_path / "mix.pbrt"
    path.write_text(HEADER + material + "\n" + PLANE)
    return Renderer(load_pbrt_scene(path), device).render().xyz.reshape(-1, 3).astype(np.float64)


@pytest.mark.parametrize("amount", [0.25, 0.7])
def test_a_mix_of_two_diffuse_materials_renders_the_blend_pbrt_converges_to(tmp_path, device, amount):
    """Mean film XYZ of the mix against the amount-weighted means of the two materials alone, within 5 standard
    errors (pixel spread of each image; the renders share the seed, which only makes the noise agree more). The
    weight on the wrong material (1 − amount instead of amount) is off by far more."""
    mixed = _render(tmp_path, f'Material "mix" "string materials" ["red" "blue"] "float amount" {amount}', device)
    red = _render(tmp_path, 'NamedMaterial "red"', device)
    blue = _render(tmp_path, 'NamedMaterial "blue"', device)
    expected = (1.0 - amount) * red.mean(axis=0) + amount * blue.mean(axis=0)
    standard_error = np.sqrt(
        mixed.var(axis=0, ddof=1) / len(mixed)
        + ((1.0 - amount) ** 2 * red.var(axis=0, ddof=1) + amount**2 * blue.var(axis=0, ddof=1)) / len(red)
    )
    assert np.all(np.abs(mixed.mean(axis=0) - expected) <= 5 * standard_error), (mixed.mean(axis=0), expected)
    swapped = amount * red.mean(axis=0) + (1.0 - amount) * blue.mean(axis=0)
    assert np.max(np.abs(mixed.mean(axis=0) - swapped) / standard_error) > 20


def test_mix_amounts_of_zero_or_one_and_mixes_of_other_materials(tmp_path):
    def materials(text: str) -> dict:
        path = tmp_path / "m.pbrt"
        path.write_text(HEADER + 'MakeNamedMaterial "gold" "string type" "conductor"\n' + text + "\n" + PLANE)
        data, _ = pbrt_scene_data(path)
        return data["materials"]

    def material(text: str) -> dict:
        return next(iter(materials(text).values()))

    red = {"type": "diffuse", "reflectance": {"rgb": [0.8, 0.15, 0.1]}}
    assert material('Material "mix" "string materials" ["red" "gold"] "float amount" 0') == red
    assert material('Material "mix" "string materials" ["gold" "red"] "float amount" 1') == red
    assert material('Material "mix" "string materials" ["red" "red"] "float amount" 0.3') == red
    # Any other pair: spectrace's mix material, naming the two materials it imports.
    imported = materials('Material "mix" "string materials" ["red" "gold"] "float amount" 0.5')
    (mixed,) = [table for table in imported.values() if table["type"] == "mix"]
    assert mixed["amount"] == 0.5
    assert [imported[name]["type"] for name in mixed["materials"]] == ["diffuse", "conductor"]
    with pytest.raises(SpectraceError, match="which no MakeNamedMaterial defined"):
        material('Material "mix" "string materials" ["red" "green"]')
    with pytest.raises(SpectraceError, match="material 'mix' with an interface"):
        material(
            'MakeNamedMaterial "none" "string type" "interface"\n'
            'Material "mix" "string materials" ["red" "none"] "float amount" 0.5'
        )


def test_a_mix_of_a_conductor_and_a_diffuse_material_renders_their_blend(tmp_path, device):
    """A rough gold and the red diffuse, amount 0.3 (pbrt's `roughness` 0.3 remapped to α as pbrt does): mean film
    XYZ against the weighted means of each alone, within 5 standard errors; the weights swapped are far off."""
    amount = 0.3
    gold = 'MakeNamedMaterial "gold" "string type" "conductor" "float roughness" 0.3\n'
    mix = f'Material "mix" "string materials" ["gold" "red"] "float amount" {amount}'
    mixed = _render(tmp_path, gold + mix, device)
    metal = _render(tmp_path, gold + 'NamedMaterial "gold"', device)
    red = _render(tmp_path, 'NamedMaterial "red"', device)
    expected = (1.0 - amount) * metal.mean(axis=0) + amount * red.mean(axis=0)
    standard_error = np.sqrt(
        mixed.var(axis=0, ddof=1) / len(mixed)
        + ((1.0 - amount) ** 2 * metal.var(axis=0, ddof=1) + amount**2 * red.var(axis=0, ddof=1)) / len(red)
    )
    assert np.all(np.abs(mixed.mean(axis=0) - expected) <= 5 * standard_error), (mixed.mean(axis=0), expected)
    swapped = amount * metal.mean(axis=0) + (1.0 - amount) * red.mean(axis=0)
    assert np.max(np.abs(mixed.mean(axis=0) - swapped) / standard_error) > 8


def test_a_float_image_texture_is_the_mix_amount(tmp_path, device):
    """`"texture amount"` naming a float imagemap: the mix texture's amount is that image (a grey bitmap); a mask of
    0 where u < 1/2 (x < 0) and 1 beyond shows the first material at x < 0 and the second at x > 0, which pbrt's
    camera (LookAt down −z, up +y) shows on the right and on the left of the image."""
    from PIL import Image

    Image.fromarray(np.array([[0, 255], [0, 255]], np.uint8)).save(tmp_path / "mask.png")
    path = tmp_path / "masked.pbrt"
    path.write_text(
        HEADER
        + 'Texture "mask" "float" "imagemap" "string filename" "mask.png" "string filter" "point"\n'
        + 'Material "mix" "string materials" ["red" "blue"] "texture amount" "mask"\n'
        + 'Shape "trianglemesh" "point3 P" [-1 -1 0  1 -1 0  1 1 0  -1 1 0] "integer indices" [0 1 2  0 2 3]\n'
        + '  "point2 uv" [0 0  1 0  1 1  0 1]\n'
    )
    data, _ = pbrt_scene_data(path)
    reflectance = next(iter(data["materials"].values()))["reflectance"]
    assert reflectance["texture"] == "mix" and reflectance["amount"]["texture"] == "bitmap"
    xyz = Renderer(load_pbrt_scene(path).with_overrides(width=16, height=16), device).render().xyz
    left, right = xyz[6:10, 5:7].reshape(-1, 3).mean(axis=0), xyz[6:10, 9:11].reshape(-1, 3).mean(axis=0)
    assert right[0] > 2 * right[2] and left[2] > 2 * left[0]  # red (X over Z) right, blue left
