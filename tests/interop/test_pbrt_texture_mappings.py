"""pbrt-v4's 2D texture mappings (`"string mapping"` spherical, cylindrical, planar) imported as the textures'
`mapping`: the transform in effect at the Texture line places the texture space, planar's v1, v2, udelta and vdelta
carried over, and a planar checkerboard rendered where pbrt-v4's formula puts its squares."""

from pathlib import Path

import numpy as np
import pytest

from spectrace.engine.renderer import Renderer
from spectrace.errors import SpectraceError
from spectrace.interop.pbrt import load_pbrt_scene, pbrt_scene_data

SIDE = 32
HEADER = f"""LookAt 0 0 5  0 0 0  0 1 0
Camera "orthographic"
Film "rgb" "integer xresolution" {SIDE} "integer yresolution" {SIDE}
PixelFilter "box"
Sampler "independent" "integer pixelsamples" 2
Integrator "path" "integer maxdepth" 1
WorldBegin
LightSource "infinite" "rgb L" [1 1 1]
"""
PLANE = """Shape "trianglemesh" "point3 P" [-10 -10 0  10 -10 0  10 10 0  -10 10 0] "integer indices" [0 1 2  0 2 3]
"""


def _write(tmp_path: Path, texture: str, reflectance: str = '"texture reflectance" "c"', name="m.pbrt") -> Path:
    path = tmp_path / name
    path.write_text(HEADER + texture + f'Material "diffuse" {reflectance}\n' + PLANE)
    return path


@pytest.mark.parametrize("mapping", ["spherical", "cylindrical", "planar"])
@pytest.mark.parametrize("kind", ["imagemap", "checkerboard", "dots"])
def test_each_mapping_of_each_2d_texture_imports_with_its_texture_space(tmp_path, mapping, kind):
    from PIL import Image

    Image.fromarray(np.full((2, 2, 3), 90, np.uint8)).save(tmp_path / "i.png")
    extra = ' "string filename" "i.png"' if kind == "imagemap" else ""
    planar = ' "vector3 v1" [0 2 0] "vector3 v2" [1 0 1] "float udelta" 0.5 "float vdelta" 0.25'
    texture = (
        f'AttributeBegin\nTranslate 1 2 3\nTexture "c" "spectrum" "{kind}" "string mapping" "{mapping}"{extra}'
        + (planar if mapping == "planar" else "")
        + "\nAttributeEnd\n"
    )
    path = _write(tmp_path, texture)
    data, importer = pbrt_scene_data(path)
    (table,) = data["textures"].values()
    assert table["mapping"] == mapping
    assert np.allclose(table["transform"][0]["matrix"], [[1, 0, 0, 1], [0, 1, 0, 2], [0, 0, 1, 3], [0, 0, 0, 1]])
    if mapping == "planar":
        assert table["v1"] == [0, 2, 0] and table["v2"] == [1, 0, 1]
    assert not importer.warnings, importer.warnings
    (shape,) = load_pbrt_scene(path).shapes
    placement = shape.material.reflectance.placement
    assert placement.mapping == mapping
    # World to texture: the inverse of the translation (planar: v1ᵀ, v2ᵀ times it in the first two rows).
    rows = np.reshape(placement.mapping_rows, (3, 4))
    if mapping == "planar":
        assert np.allclose(rows[:2], [[0, 2, 0, -4], [1, 0, 1, -4]])
    else:
        assert np.allclose(rows, [[1, 0, 0, -1], [0, 1, 0, -2], [0, 0, 1, -3]])


def test_an_unknown_mapping_is_refused_at_its_line(tmp_path):
    path = _write(tmp_path, 'Texture "c" "spectrum" "checkerboard" "string mapping" "conical"\n')
    with pytest.raises(SpectraceError) as failure:
        pbrt_scene_data(path)
    assert failure.value.where == f"{path}:9"
    assert "mapping 'conical' (spectrace takes uv, spherical, cylindrical, planar)" in failure.value.message


def test_a_planar_checkerboard_renders_where_pbrts_formula_puts_its_squares(tmp_path, device):
    """pbrt-v4: s = udelta + q · v1, t = vdelta + q · v2 (q the point in texture space, here p − (0.25, 0, 0)), tex1
    where floor(s) + floor(t) is even. pbrt's LookAt from +z with up +y puts world −x to the image's right, and its
    orthographic screen spans [−1, 1]². Pixels wholly inside one square equal, bit for bit, the render of a plane
    of that square's albedo (same seed)."""
    texture = (
        'AttributeBegin\nTranslate 0.25 0 0\nTexture "c" "spectrum" "checkerboard" "string mapping" "planar"\n'
        '  "vector3 v1" [2 0 0] "vector3 v2" [0 2 0] "float vdelta" 0.5 "float tex1" 0.8 "float tex2" 0.1\n'
        "AttributeEnd\n"
    )
    image = Renderer(load_pbrt_scene(_write(tmp_path, texture)), device).render().xyz
    plain = [
        Renderer(load_pbrt_scene(_write(tmp_path, "", f'"float reflectance" {a}', f"{a}.pbrt")), device).render().xyz
        for a in (0.8, 0.1)
    ]
    offsets = (np.arange(6) + 0.5) / 6
    i = np.arange(SIDE)[:, None, None, None] + offsets[None, None, :, None]
    j = np.arange(SIDE)[None, :, None, None] + offsets[None, None, None, :]
    x = np.broadcast_to(1.0 - 2.0 * j / SIDE, (SIDE, SIDE, 6, 6)).reshape(SIDE, SIDE, -1)
    y = np.broadcast_to(1.0 - 2.0 * i / SIDE, (SIDE, SIDE, 6, 6)).reshape(SIDE, SIDE, -1)
    s, t = 2.0 * (x - 0.25), 0.5 + 2.0 * y
    side = (np.floor(s) + np.floor(t)) % 2
    for k in (0, 1):
        clean = np.all(side == k, axis=-1)
        assert clean.sum() >= 100
        np.testing.assert_array_equal(image[clean], plain[k][clean])
    assert np.mean(plain[0]) > 2 * np.mean(plain[1])
