"""Textures in scene files: the inline and named forms, colour decoding (sRGB unless raw, checked against
colour-science), and bad input reported as one line naming the file and key path, without a traceback."""

import colour
import numpy as np
import OpenEXR
import pytest
from PIL import Image as PILImage

from cli_runner import run_in_process, run_spectrace
from scene_text import camera_film
from spectrace.errors import SpectraceError
from spectrace.scene import load_scene
from spectrace.scene.loader import check_texture_values
from spectrace.textures import bitmap, checkerboard

HEADER = (
    camera_film(origin="[0, 0, 3]", target="[0, 0, 0]", fov="30", width="8", height="8")
    + """[sampler]
spp = 2
"""
)

SCENE = (
    HEADER
    + """{textures}
[materials.m]
type = "diffuse"
reflectance = {reflectance}
[[shapes]]
type = "{shape}"
material = "m"
[[lights]]
type = "constant"
radiance = {{ value = 1 }}
"""
)


def _scene(tmp_path, reflectance: str, textures: str = "", shape: str = "rectangle"):
    path = tmp_path / "scene.toml"
    path.write_text(SCENE.format(reflectance=reflectance, textures=textures, shape=shape))
    return path


def _png(path, array, mode=None):
    PILImage.fromarray(array, mode=mode).save(path)
    return path


def _exr(path, rgb):
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    with OpenEXR.File(header, {"RGB": np.ascontiguousarray(rgb, np.float32)}) as exr:
        exr.write(str(path))
    return path


def test_inline_png_is_decoded_from_srgb_and_raw_keeps_code_values(tmp_path):
    codes = np.array([[[0, 64, 128], [191, 255, 32]]], np.uint8)
    _png(tmp_path / "wood.png", codes)
    scene = load_scene(_scene(tmp_path, '{ texture = "bitmap", file = "wood.png", wrap = "mirror" }'))
    texture = scene.shapes[0].material.reflectance
    expected = colour.cctf_decoding(codes / 255.0, function="sRGB")
    np.testing.assert_allclose(texture.values, expected, atol=1e-6)
    assert texture.placement.wrap == "mirror"
    raw = load_scene(_scene(tmp_path, '{ texture = "bitmap", file = "wood.png", raw = true }'))
    np.testing.assert_allclose(raw.shapes[0].material.reflectance.values, codes / 255.0, atol=1e-7)


def test_sixteen_bit_grey_png_keeps_its_precision(tmp_path):
    codes = np.array([[0, 1000], [40000, 65535]], np.uint16)
    _png(tmp_path / "grey.png", codes)
    scene = load_scene(_scene(tmp_path, '{ texture = "bitmap", file = "grey.png", raw = true }'))
    values = scene.shapes[0].material.reflectance.values
    assert values.shape == (2, 2, 1)
    np.testing.assert_allclose(values[..., 0], codes / 65535.0, atol=1e-7)


def test_named_texture_is_shared_and_a_checkerboard_takes_it(tmp_path):
    _exr(tmp_path / "a.exr", np.full((2, 2, 3), 0.25))
    textures = '[textures.tiles]\ntype = "bitmap"\nfile = "a.exr"\nuv_scale = [2, 3]\n'
    scene = load_scene(
        _scene(
            tmp_path,
            '{ texture = "checkerboard", color0 = { texture = "tiles" }, color1 = { rgb = [0.1, 0.2, 0.3] } }',
            textures,
        )
    )
    board = scene.shapes[0].material.reflectance
    assert isinstance(board, checkerboard.CheckerboardTexture)
    assert isinstance(board.color0, bitmap.BitmapTexture) and board.color0.placement.uv_scale == (2.0, 3.0)
    np.testing.assert_allclose(board.color0.values, 0.25)  # an EXR is linear: no decoding


@pytest.mark.slow
def test_textured_scene_renders_from_the_command_line(tmp_path):
    _png(tmp_path / "wood.png", np.array([[[200, 120, 40], [90, 60, 30]]], np.uint8))
    scene = _scene(tmp_path, '{ texture = "bitmap", file = "wood.png", filter = "trilinear" }')
    result = run_spectrace("render", str(scene), "-o", str(tmp_path / "out.exr"), "-q")
    assert result.returncode == 0, result.stderr
    assert (tmp_path / "out.exr").is_file()


def _bad_inputs(tmp_path) -> list[tuple[str, str, str, str]]:
    """(reflectance, [textures] text, shape, the key path and words the one line must hold)."""
    (tmp_path / "garbage.png").write_bytes(b"not an image at all")
    nan = np.full((2, 2, 3), 0.5)
    nan[0, 0, 1] = np.nan
    _exr(tmp_path / "nan.exr", nan)
    _exr(tmp_path / "negative.exr", np.full((2, 2, 3), -0.5))
    _exr(tmp_path / "bright.exr", np.full((2, 2, 3), 3.0))
    _png(tmp_path / "ok.png", np.zeros((2, 2, 3), np.uint8))
    board = '[textures.board]\ntype = "checkerboard"\n'
    return [
        ('{ texture = "bitmap", file = "missing.png" }', "", "rectangle", "materials.m.reflectance.file"),
        ('{ texture = "bitmap", file = "garbage.png" }', "", "rectangle", "materials.m.reflectance.file"),
        ('{ texture = "bitmap", file = "nan.exr" }', "", "rectangle", "materials.m.reflectance.file: texture"),
        ('{ texture = "bitmap", file = "negative.exr" }', "", "rectangle", "materials.m.reflectance: texture"),
        ('{ texture = "bitmap", file = "bright.exr" }', "", "rectangle", "materials.m.reflectance: texture"),
        ('{ texture = "spectral", file = "nan.exr" }', "", "rectangle", "materials.m.reflectance.file: texture"),
        ('{ texture = "bitmap", file = "ok.png", wrap = "tile" }', "", "rectangle", "materials.m.reflectance.wrap"),
        ('{ texture = "wod" }', "", "rectangle", "materials.m.reflectance.texture: undefined texture"),
        ('{ texture = "bitmap", file = "ok.png" }', "", "prism", "shapes[0].material: shape 'prism0' has no tex"),
        (
            '{ texture = "checkerboard", color0 = { texture = "board" } }',
            board,
            "rectangle",
            "materials.m.reflectance.color0.texture",
        ),
        (
            '{ texture = "bitmap", file = "ok.png" }',
            '[textures.bitmap]\ntype = "bitmap"\nfile = "ok.png"\n',
            "rectangle",
            "textures.bitmap: a texture may not be named",
        ),
    ]


@pytest.mark.slow
def test_bad_texture_input_is_one_line(tmp_path, monkeypatch, capsys):
    for reflectance, textures, shape, expected in _bad_inputs(tmp_path):
        scene = _scene(tmp_path, reflectance, textures, shape)
        code, err = run_in_process(monkeypatch, capsys, ["render", str(scene), "-o", str(tmp_path / "x.png")])
        assert code != 0, reflectance
        lines = err.strip().splitlines()
        assert len(lines) == 1 and "Traceback" not in err, err
        assert lines[0].startswith(f"error: {scene}: {expected}"), (reflectance, lines[0])
        assert not (tmp_path / "x.png").exists()


@pytest.mark.slow
def test_bad_texture_is_one_line_from_a_real_process(tmp_path):
    """The same through `python -m spectrace`: exit status 1 or 2, one line, nothing written."""
    (tmp_path / "garbage.png").write_bytes(b"\x89PNG\r\n\x1a\nbroken")
    scene = _scene(tmp_path, '{ texture = "bitmap", file = "garbage.png" }')
    result = run_spectrace("render", str(scene), "-o", str(tmp_path / "x.png"))
    assert result.returncode != 0
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in result.stderr
    assert lines[0].startswith(f"error: {scene}: materials.m.reflectance.file: cannot read texture")


def test_a_scalar_use_needs_one_channel():
    """A data texture (a future roughness map) must be grey: an RGB one is refused naming the key."""
    rgb = bitmap.make(np.zeros((2, 2, 3)), raw=True)
    with pytest.raises(SpectraceError, match="has 3 channels; this parameter needs one") as error:
        check_texture_values(rgb, "float", "scene.toml: materials.m.roughness")
    assert error.value.where == "scene.toml: materials.m.roughness"
    check_texture_values(bitmap.make(np.zeros((2, 2)), raw=True), "float", "x")  # grey passes


@pytest.mark.slow
def test_textures_beyond_a_gibibyte_are_refused_before_conversion():
    """The budget is checked from the image's size before any texel is converted: a 20000² RGB reflectance texture
    (broadcast, so the test allocates nothing) would need 20000² × 3 half-float coefficients, 2.2 GiB."""
    import spectrace
    from spectrace.engine.scene_buffers import build_scene_buffers
    from spectrace.scene.model import Camera, Scene
    from spectrace.textures.bitmap import BitmapTexture

    huge = BitmapTexture(np.broadcast_to(np.full((1, 1, 3), 0.5, np.float32), (20000, 20000, 3)))
    scene = Scene(
        camera=Camera(origin=(0.0, 0.0, 3.0), target=(0.0, 0.0, 0.0)),
        width=4,
        height=4,
        shapes=[spectrace.shape("rectangle", spectrace.diffuse(huge))],
    )
    with pytest.raises(SpectraceError, match=r"textures need 2\.2 GiB of device memory.*at most 1\.0 GiB"):
        build_scene_buffers(scene)


def test_spectra_listing_reads_checkerboard_sides_as_reflectances(tmp_path):
    """`spectrace spectra` lists a checkerboard's spectrum sides under their key paths, an rgb one uplifted as a
    reflectance (bounded by 1), not as an emission."""
    from spectrace.scene.spectra_index import scene_spectra
    from spectrace.spectral.uplift import uplift_reflectance

    path = _scene(
        tmp_path, '{ texture = "checkerboard", color0 = { value = 0.3 }, color1 = { rgb = [0.2, 0.5, 0.9] } }'
    )
    listed = scene_spectra(path)
    np.testing.assert_allclose(listed["materials.m.reflectance.color0"].values, 0.3)
    np.testing.assert_allclose(
        listed["materials.m.reflectance.color1"].values, uplift_reflectance((0.2, 0.5, 0.9))[0].values
    )


MORE = (
    HEADER
    + """[materials.m]
type = "conductor"
metal = "Au"
roughness = {roughness}
specular_tint = {{ texture = "bitmap", file = "tint.png" }}
[materials.black]
type = "diffuse"
reflectance = {{ value = 0 }}
[[shapes]]
type = "rectangle"
material = "m"
[[shapes]]
type = "{emitter_shape}"
material = "black"
transform = [{{ translate = [0, 0, 2] }}]
emitter = {{ radiance = {radiance}, scale = 4 }}
"""
)


def _more(tmp_path, roughness: str, radiance: str, emitter_shape: str = "rectangle"):
    _png(tmp_path / "grey.png", np.array([[0, 255]], np.uint8), mode="L")
    _png(tmp_path / "tint.png", np.full((2, 2, 3), 128, np.uint8))
    _png(tmp_path / "rgb.png", np.full((2, 2, 3), 200, np.uint8))
    path = tmp_path / "more.toml"
    path.write_text(MORE.format(roughness=roughness, radiance=radiance, emitter_shape=emitter_shape))
    return path


@pytest.mark.slow
def test_roughness_tint_and_emission_textures_in_a_scene_file(tmp_path):
    """A raw grey roughness keeps its code values / 255, the tint and emission are decoded from sRGB, the
    emitter's scale multiplies the image's mean radiance, and the scene renders."""
    path = _more(
        tmp_path, '{ texture = "bitmap", file = "grey.png", raw = true }', '{ texture = "bitmap", file = "rgb.png" }'
    )
    scene = load_scene(path)
    material, emitter = scene.shapes[0].material, scene.shapes[1].emitter
    np.testing.assert_allclose(material.roughness.values.ravel(), [0.0, 1.0])
    assert not material.is_delta
    linear = colour.cctf_decoding(200 / 255, function="sRGB")
    np.testing.assert_allclose(emitter.image.texture.values, linear, rtol=1e-6)
    assert emitter.image.scale == 4.0
    # (1, 1, 1) emits D65 with Y = 1, whose mean over the grid is what the power estimate uses
    white = sum(p.values for p in emitter.image.primaries)
    np.testing.assert_allclose(emitter.radiance.values, 4.0 * linear * white, rtol=1e-5)
    result = run_spectrace("render", str(path), "-o", str(tmp_path / "out.exr"), "-q")
    assert result.returncode == 0, result.stderr


@pytest.mark.parametrize(
    "roughness, radiance, emitter_shape, expected",
    [
        ('{ texture = "bitmap", file = "tint.png" }', "{ value = 1 }", "rectangle", "materials.m.roughness: texture"),
        ("1.5", "{ value = 1 }", "rectangle", "materials.m.roughness"),
        ("0.1", '{ texture = "bitmap", file = "rgb.png" }', "prism", "shapes[1].emitter.radiance: shape"),
        ("0.1", '{ texture = "checkerboard" }', "rectangle", "shapes[1].emitter.radiance: an emission texture"),
    ],
)
def test_bad_roughness_or_emission_texture_is_one_line(tmp_path, roughness, radiance, emitter_shape, expected):
    path = _more(tmp_path, roughness, radiance, emitter_shape)
    result = run_spectrace("render", str(path), "-o", str(tmp_path / "x.png"))
    assert result.returncode != 0
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in result.stderr, result.stderr
    assert lines[0].startswith(f"error: {path}: {expected}"), lines[0]
    assert not (tmp_path / "x.png").exists()


def test_scale_and_mix_in_a_scene_file(tmp_path):
    """The docs' example: a named mix of a bitmap and an rgb by a raw grey amount, and an inline scale; a scaled
    reflectance above 1, an RGB amount, a factor that varies with the wavelength and a checkerboard operand are
    one-line errors naming the key."""
    from spectrace.textures.mix import MixTexture
    from spectrace.textures.scale import ScaleTexture

    _png(tmp_path / "paint.png", np.full((2, 2, 3), 200, np.uint8))
    _png(tmp_path / "mask.png", np.array([[0, 255], [128, 64]], np.uint8))
    named = '[textures.worn]\ntype = "mix"\ntex1 = { texture = "bitmap", file = "paint.png" }\n'
    named += 'tex2 = { rgb = [0.3, 0.25, 0.2] }\namount = { texture = "bitmap", file = "mask.png", raw = true }\n'
    worn = load_scene(_scene(tmp_path, '{ texture = "worn" }', named)).shapes[0].material.reflectance
    assert isinstance(worn, MixTexture)
    np.testing.assert_allclose(worn.amount.values[..., 0], np.array([[0, 255], [128, 64]]) / 255.0, atol=1e-7)
    scaled = (
        load_scene(
            _scene(tmp_path, '{ texture = "scale", tex = { texture = "bitmap", file = "paint.png" }, scale = 0.6 }')
        )
        .shapes[0]
        .material.reflectance
    )
    assert isinstance(scaled, ScaleTexture) and scaled.scale == 0.6
    constant = load_scene(_scene(tmp_path, '{ texture = "scale", tex = { value = 0.5 }, scale = { value = 0.8 } }'))
    assert constant.shapes[0].material.reflectance.scale == 0.8  # a constant spectrum is its number
    bad = [
        ('{ texture = "scale", tex = { value = 0.6 }, scale = 2 }', "", "materials.m.reflectance: scale texture has"),
        (
            '{ texture = "mix", amount = { texture = "bitmap", file = "paint.png" } }',
            "",
            "materials.m.reflectance.amount: texture",
        ),
        (
            '{ texture = "scale", tex = { value = 0.5 }, scale = { rgb = [0.2, 0.5, 0.9] } }',
            "",
            "materials.m.reflectance.scale: scale is a number or a grey texture",
        ),
        (
            '{ texture = "mix", tex1 = { texture = "board" } }',
            '[textures.board]\ntype = "checkerboard"\n',
            "materials.m.reflectance.tex1.texture: texture 'board' is a checkerboard",
        ),
    ]
    for reflectance, textures, expected in bad:
        with pytest.raises(SpectraceError) as error:
            load_scene(_scene(tmp_path, reflectance, textures))
        assert str(error.value).startswith(f"{tmp_path / 'scene.toml'}: {expected}"), str(error.value)
