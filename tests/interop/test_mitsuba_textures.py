"""Mitsuba 3 textures, imported and exported: `bitmap` and `checkerboard` by id and inline, their to_uv, wrap, filter
and raw settings, checked against Mitsuba 3's own conventions (stated below; a peer test measures them in Mitsuba);
what spectrace cannot represent named in one line; and the export's textures read back by the importer.

Mitsuba 3's texture coordinates (measured with its ray_intersect in test_mitsuba_uv_conventions): its rectangle has
uv = ((x + 1)/2, (y + 1)/2), v up; an OBJ's vt (u, v) is read as (u, 1 - v); a PLY's u, v as stored. A bitmap's row
0 is at v = 0 and its checkerboard shows color0 where frac(uv') < 1/2 in both or neither coordinate, uv' = to_uv(uv).
"""

import shutil
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from cli_runner import run_in_process
from replica_agreement import spectrace_replicas
from spectrace.engine.renderer import Renderer
from spectrace.errors import SpectraceError
from spectrace.geometry import primitives
from spectrace.interop.mitsuba import import_mitsuba, load_mitsuba_scene, mitsuba_scene_data
from spectrace.interop.mitsuba.export import mitsuba_film_xyz
from spectrace.textures.bitmap import BitmapTexture
from spectrace.textures.checkerboard import CheckerboardTexture

DATA = Path(__file__).resolve().parents[1] / "data" / "mitsuba"
SENSOR = """<sensor type="perspective"><float name="fov" value="45"/>
    <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="6"/></film></sensor>"""
QUAD = '<shape type="obj"><string name="filename" value="quad.obj"/>{}</shape>'


@pytest.fixture
def folder(tmp_path) -> Path:
    for name in ("texture.png", "quad.obj"):
        shutil.copy(DATA / name, tmp_path / name)
    return tmp_path


def _write(folder: Path, body: str) -> Path:
    path = folder / "scene.xml"
    path.write_text(f'<scene version="3.0.0">\n{SENSOR}\n{body}\n<emitter type="constant"/>\n</scene>\n')
    return path


def _srgb_decoded(codes: np.ndarray) -> np.ndarray:
    """IEC 61966-2-1's decoding of 8-bit code values, written out here as the reference."""
    c = codes / 255.0
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def _st(shape, texture) -> np.ndarray:
    """The st each vertex of `shape` looks `texture` up at in spectrace."""
    scale, offset = texture.placement.uv_scale, texture.placement.uv_offset
    return shape.mesh.uvs * scale + offset


def _mitsuba_st(uv_mitsuba: np.ndarray, scale, offset) -> np.ndarray:
    """Mitsuba's lookup point: to_uv (scale, then translate) applied to its own uv."""
    return uv_mitsuba * scale + offset


# ---------------------------------------------------------------- what maps


def test_bitmap_by_id_with_to_uv_wrap_and_filter(folder):
    """The scene of tests/data/mitsuba/textures.xml: a bitmap referenced by id on an OBJ and on a rectangle, with
    to_uv (scale 2 x 3, then translate (0.25, 0.5)), mirror wrap and nearest filter. Each vertex looks the texture
    up at the st Mitsuba would (its conventions above), the rectangle's through a v-flipped copy; the texels are
    the PNG's code values through the sRGB curve."""
    shutil.copy(DATA / "textures.xml", folder / "scene.xml")
    data, notes = mitsuba_scene_data(folder / "scene.xml")
    assert data["textures"]["tiles"] == {
        "type": "bitmap",
        "file": "texture.png",
        "wrap": "mirror",
        "filter": "nearest",
        "uv_scale": [2.0, 3.0],
        "uv_offset": [0.25, 0.5],
    }
    assert data["materials"]["tiled"] == {"type": "diffuse", "reflectance": {"texture": "tiles"}}
    assert data["shapes"][1]["material"] == "tiled_flipped_v"
    assert any("'tiled_flipped_v' with its textures' v flipped" in note for note in notes)

    scene = load_mitsuba_scene(folder / "scene.xml")
    quad, rectangle = scene.shapes[0], scene.shapes[1]
    for shape in (quad, rectangle):
        texture = shape.material.reflectance
        assert isinstance(texture, BitmapTexture)
        assert (texture.placement.wrap, texture.placement.filter) == ("mirror", "nearest")
        codes = np.asarray(Image.open(DATA / "texture.png").convert("RGB"), np.float64)
        np.testing.assert_allclose(texture.values, _srgb_decoded(codes), atol=1e-6)
    # OBJ: vt = ((x + 1)/2, (y + 1)/2) (quad.obj), read by Mitsuba as (u, 1 - v); the quad was moved by -1.2 in x.
    x, y = quad.mesh.vertices[:, 0] + 1.2, quad.mesh.vertices[:, 1]
    expected = _mitsuba_st(np.column_stack([(x + 1) / 2, (1 - y) / 2]), (2, 3), (0.25, 0.5))
    np.testing.assert_allclose(_st(quad, quad.material.reflectance), expected, atol=1e-12)
    # Mitsuba's rectangle: uv = ((x + 1)/2, (y + 1)/2) in its own frame, moved by +1.2 in x.
    x, y = rectangle.mesh.vertices[:, 0] - 1.2, rectangle.mesh.vertices[:, 1]
    expected = _mitsuba_st(np.column_stack([(x + 1) / 2, (y + 1) / 2]), (2, 3), (0.25, 0.5))
    np.testing.assert_allclose(_st(rectangle, rectangle.material.reflectance), expected, atol=1e-12)


def test_inline_checkerboard_with_a_bitmap_side(folder):
    """textures.xml's roughplastic: an inline checkerboard (to_uv scale 4) whose color1 is an inline raw bitmap with
    clamp wrap, on a rectangle. Mitsuba's checkerboard changes colour at half units of uv', spectrace's at whole
    units of st: uv_scale = 2 x 4, and v flipped for the rectangle; the bitmap side has its own (identity) to_uv,
    flipped too; raw keeps the code values."""
    shutil.copy(DATA / "textures.xml", folder / "scene.xml")
    data, _ = mitsuba_scene_data(folder / "scene.xml")
    board = data["materials"]["board_flipped_v"]
    assert board["type"] == "plastic" and board["roughness"] == 0.2
    checker = data["textures"][board["reflectance"]["texture"]]
    assert checker == {
        "type": "checkerboard",
        "color0": {"rgb": [0.8, 0.7, 0.2]},
        "color1": {"texture": checker["color1"]["texture"]},
        "uv_scale": [8.0, -8.0],
        "uv_offset": [0.0, 8.0],
    }
    assert data["textures"][checker["color1"]["texture"]] == {
        "type": "bitmap",
        "file": "texture.png",
        "raw": True,
        "wrap": "clamp",
        "uv_scale": [1.0, -1.0],
        "uv_offset": [0.0, 1.0],
    }
    floor = load_mitsuba_scene(folder / "scene.xml").shapes[2]
    texture = floor.material.reflectance
    assert isinstance(texture, CheckerboardTexture) and isinstance(texture.color1, BitmapTexture)
    codes = np.asarray(Image.open(DATA / "texture.png").convert("RGB"), np.float64)
    np.testing.assert_allclose(texture.color1.values, codes / 255.0, atol=1e-6)  # raw: no sRGB decoding
    # Squares: Mitsuba's color0 where floor(2 u') + floor(2 v') is even, uv' = 4 uv (its rectangle's uv); spectrace's
    # where floor(s) + floor(t) is even. Compared at the centres of a grid of points over the floor.
    u, v = np.meshgrid((np.arange(40) + 0.5) / 40, (np.arange(40) + 0.5) / 40)
    mitsuba_side = (np.floor(2 * 4 * u) + np.floor(2 * 4 * v)) % 2
    spectrace_uv = np.stack([u, 1 - v], axis=-1)  # the same points in spectrace's rectangle uv (v down)
    st = spectrace_uv * texture.placement.uv_scale + texture.placement.uv_offset
    np.testing.assert_array_equal((np.floor(st[..., 0]) + np.floor(st[..., 1])) % 2, mitsuba_side)


def test_checkerboard_defaults_and_an_inline_bitmap_on_plastic(folder):
    body = (
        """<bsdf type="plastic" id="p"><texture type="bitmap" name="diffuse_reflectance">
            <string name="filename" value="texture.png"/></texture></bsdf>
        <bsdf type="diffuse" id="c"><texture type="checkerboard" name="reflectance"/></bsdf>
        """
        + QUAD.format('<ref id="p"/>')
        + QUAD.format('<ref id="c"/>')
    )
    data, _ = mitsuba_scene_data(_write(folder, body))
    assert data["textures"]["diffuse_reflectance_texture"] == {"type": "bitmap", "file": "texture.png"}
    assert data["textures"]["reflectance_texture"] == {
        "type": "checkerboard",
        "color0": {"value": 0.4},
        "color1": {"value": 0.2},
    }  # Mitsuba's defaults; spectrace's default uv_scale 2 makes its 2 x 2 squares
    plastic, diffuse = (shape.material for shape in load_mitsuba_scene(folder / "scene.xml").shapes)
    assert plastic.reflectance.placement.filter == "bilinear" and plastic.reflectance.placement.wrap == "repeat"
    assert diffuse.reflectance.placement.uv_scale == (2.0, 2.0)


def test_a_texture_shared_by_materials_is_one_table(folder):
    body = (
        """<texture type="bitmap" id="t"><string name="filename" value="texture.png"/></texture>
        <bsdf type="diffuse" id="a"><ref name="reflectance" id="t"/></bsdf>
        <bsdf type="plastic" id="b"><ref name="diffuse_reflectance" id="t"/></bsdf>
        """
        + QUAD.format('<ref id="a"/>')
        + QUAD.format('<ref id="b"/>')
        + QUAD.format('<ref id="a"/>')
    )
    data, _ = mitsuba_scene_data(_write(folder, body))
    assert list(data["textures"]) == ["t"] and list(data["materials"]) == ["a", "b"]
    scene = load_mitsuba_scene(folder / "scene.xml")
    assert scene.shapes[0].material.reflectance is scene.shapes[1].material.reflectance  # read once


def test_ply_texture_coordinates_are_flipped_as_mitsuba_reads_them(folder):
    """Mitsuba reads a PLY's u, v as stored; spectrace flips v (as for OBJ files): a texture on a PLY shape is
    imported with v flipped, so each vertex looks it up at the same st as in Mitsuba."""
    header = (
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
        "property float u\nproperty float v\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
    )
    uv = np.array([[0.1, 0.2], [0.9, 0.3], [0.4, 0.8]])
    (folder / "tri.ply").write_text(header + "0 0 0 0.1 0.2\n1 0 0 0.9 0.3\n0 1 0 0.4 0.8\n3 0 1 2\n")
    body = """<shape type="ply"><string name="filename" value="tri.ply"/><bsdf type="diffuse">
        <texture type="bitmap" name="reflectance"><string name="filename" value="texture.png"/>
        <transform name="to_uv"><translate x="0.5" y="0.25"/><scale x="2" y="5"/></transform>
        </texture></bsdf></shape>"""
    shape = load_mitsuba_scene(_write(folder, body)).shapes[0]
    # Mitsuba's to_uv applies the file's steps in order: translate, then scale: uv' = (uv + t) * s.
    expected = (uv + (0.5, 0.25)) * (2, 5)
    np.testing.assert_allclose(_st(shape, shape.material.reflectance), expected, atol=1e-6)


# ---------------------------------------------------------------- what does not, and bad input

BAD = [
    (
        "unknown-filter",
        '<string name="filter_type" value="cubic"/>',
        "shape/bsdf/texture/string[1]@value",
        "unknown filter_type 'cubic' (bilinear, nearest)",
    ),
    (
        "unknown-wrap",
        '<string name="wrap_mode" value="tile"/>',
        "shape/bsdf/texture/string[1]@value",
        "unknown wrap_mode 'tile' (repeat, mirror, clamp)",
    ),
    (
        "raw-not-boolean",
        '<boolean name="raw" value="maybe"/>',
        "shape/bsdf/texture/boolean@value",
        "expected true or false, got 'maybe'",
    ),
    (
        "to-uv-not-a-number",
        '<transform name="to_uv"><scale x="two"/></transform>',
        "shape/bsdf/texture/transform/scale@x",
        "expected a finite number, got 'two'",
    ),
    (
        "to-uv-zero-scale",
        '<transform name="to_uv"><scale value="0"/></transform>',
        "shape/bsdf/texture/transform/scale",
        "scale factors must be non-zero",
    ),
    (
        "to-uv-a-float",
        '<float name="to_uv" value="2"/>',
        "shape/bsdf/texture/float",
        "to_uv must be a <transform>, got <float>",
    ),
]


@pytest.mark.parametrize("name, inside, path, says", BAD, ids=[case[0] for case in BAD])
def test_bad_bitmap_settings_are_one_line_naming_the_element(folder, monkeypatch, capsys, name, inside, path, says):
    body = QUAD.format(
        '<bsdf type="diffuse"><texture type="bitmap" name="reflectance">'
        f'<string name="filename" value="texture.png"/>{inside}</texture></bsdf>'
    )
    xml = _write(folder, body)
    status, stderr = run_in_process(monkeypatch, capsys, ["import-mitsuba", str(xml), "-o", str(folder / "o.toml")])
    assert status == 2 and stderr.count("\n") == 1 and "Traceback" not in stderr, stderr
    assert stderr.startswith(f"error: {xml}: {path}: "), stderr
    assert says in stderr, stderr
    assert not (folder / "o.toml").exists()


UNSUPPORTED = [
    (
        "rotated-to-uv",
        QUAD.format(
            '<bsdf type="diffuse"><texture type="bitmap" name="reflectance">'
            '<string name="filename" value="texture.png"/>'
            '<transform name="to_uv"><rotate z="1" angle="30"/></transform></texture></bsdf>'
        ),
        "texture 'bitmap' with a to_uv that rotates or shears",
    ),
    (
        "other-texture-type",
        QUAD.format('<bsdf type="diffuse"><texture type="volume" name="reflectance"/></bsdf>'),
        "texture 'volume' as reflectance (line",
    ),
    (
        "unknown-bitmap-property",
        QUAD.format(
            '<bsdf type="diffuse"><texture type="bitmap" name="reflectance">'
            '<string name="filename" value="texture.png"/><float name="gamma" value="2"/></texture></bsdf>'
        ),
        "texture 'bitmap' with gamma (line",
    ),
    (
        "untextured-parameter",
        QUAD.format(
            '<bsdf type="conductor"><texture type="checkerboard" name="eta"/><spectrum name="k" value="1"/></bsdf>'
        ),
        "texture 'checkerboard' as eta of conductor (spectrace's conductor takes no texture there)",
    ),
    (
        "textured-point-light",
        """<emitter type="point"><point name="position" x="0" y="0" z="0"/>
        <texture type="bitmap" name="intensity"><string name="filename" value="texture.png"/></texture></emitter>""",
        "texture 'bitmap' as intensity of point (spectrace's point takes no texture there)",
    ),
    (
        "textured-emission",
        """<emitter type="constant">
        <texture type="bitmap" name="radiance"><string name="filename" value="texture.png"/></texture>
        </emitter>""",
        "texture 'bitmap' as radiance of constant (spectrace's constant takes no texture there)",
    ),
    (
        "checkerboard-in-checkerboard",
        QUAD.format(
            '<bsdf type="diffuse"><texture type="checkerboard" name="reflectance">'
            '<texture type="checkerboard" name="color0"/></texture></bsdf>'
        ),
        "texture 'checkerboard' as color0 of a checkerboard",
    ),
]


@pytest.mark.parametrize("name, body, says", UNSUPPORTED, ids=[case[0] for case in UNSUPPORTED])
def test_what_spectrace_cannot_represent_is_named(folder, name, body, says):
    with pytest.raises(SpectraceError) as error:
        mitsuba_scene_data(_write(folder, body))
    message = str(error.value)
    assert message.startswith(f"{folder / 'scene.xml'}: unsupported Mitsuba 3 plugins: "), message
    assert says in message and "\n" not in message, message


@pytest.mark.parametrize(
    "body, path, says",
    [
        (
            QUAD.format('<bsdf type="diffuse"><texture type="bitmap" name="reflectance"/></bsdf>'),
            "shape/bsdf/texture",
            "texture 'bitmap' needs a property named 'filename'",
        ),
        (
            QUAD.format(
                '<bsdf type="diffuse"><texture type="bitmap" name="reflectance">'
                '<string name="filename" value="missing.png"/></texture></bsdf>'
            ),
            "shape/bsdf/texture/string@value",
            "missing.png' does not exist or is not a file",
        ),
        (
            '<texture type="checkerboard" id="loop"><ref name="color0" id="loop"/></texture>'
            + QUAD.format('<bsdf type="diffuse"><ref name="reflectance" id="loop"/></bsdf>'),
            "texture",
            "texture 'checkerboard' refers to itself (through <ref>)",
        ),
        (
            QUAD.format(
                '<bsdf type="diffuse"><texture type="bitmap" name="reflectance">'
                '<string name="filename" value="quad.obj"/></texture></bsdf>'
            ),
            "shape/bsdf/texture",
            "cannot read texture",  # the loader's complaint, told at the element it came from
        ),
        (
            '<shape type="obj"><string name="filename" value="plain.obj"/><bsdf type="diffuse">'
            '<texture type="checkerboard" name="reflectance"/></bsdf></shape>',
            "shape",
            "has no texture coordinates",
        ),
    ],
    ids=["no-filename", "missing-file", "reference-cycle", "not-an-image", "mesh-without-uvs"],
)
def test_bad_texture_input_is_one_line(folder, body, path, says):
    (folder / "plain.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    xml = _write(folder, body)
    out = folder / "out.toml"
    out.write_text("# before\n")
    with pytest.raises(SpectraceError) as error:
        import_mitsuba(xml, out)
    assert error.value.where == f"{xml}: {path}", str(error.value)
    assert says in error.value.message and "\n" not in str(error.value), str(error.value)
    assert out.read_text() == "# before\n"


# ---------------------------------------------------------------- surface detail and textured roughness


def _detail_images(folder: Path) -> None:
    """normal.png: a raw 2 x 2 RGB normal map; height.png and mask.png: one-channel 8-bit maps."""
    Image.fromarray(np.array([[[128, 128, 255], [200, 128, 200]], [[128, 60, 220], [90, 170, 230]]], np.uint8)).save(
        folder / "normal.png"
    )
    Image.fromarray(np.array([[0, 64], [128, 255]], np.uint8)).save(folder / "height.png")
    Image.fromarray(np.array([[0, 255], [255, 0]], np.uint8)).save(folder / "mask.png")


NORMAL_MAP = (
    '<texture type="bitmap" name="normalmap"><string name="filename" value="normal.png"/>'
    '<boolean name="raw" value="true"/></texture>'
)
HEIGHTS = (
    '<texture type="bitmap" name="anything"><string name="filename" value="height.png"/>'
    '<boolean name="raw" value="true"/></texture>'
)
DIFFUSE = '<bsdf type="diffuse"><rgb name="reflectance" value="0.5"/></bsdf>'


@pytest.mark.parametrize(
    "bsdf",
    [
        f'<bsdf type="normalmap">{NORMAL_MAP}{DIFFUSE}</bsdf>',
        f'<bsdf type="twosided"><bsdf type="normalmap">{NORMAL_MAP}{DIFFUSE}</bsdf></bsdf>',
        f'<bsdf type="normalmap">{NORMAL_MAP}<bsdf type="twosided">{DIFFUSE}</bsdf></bsdf>',
    ],
    ids=["bare", "inside-twosided", "around-twosided"],
)
def test_normalmap_becomes_the_materials_normal_map(folder, bsdf):
    """Mitsuba's normalmap adapter (its `normalmap` texture, a raw bitmap) is the nested material with normal_map:
    the same texels (code values / 255, not sRGB-decoded), in either order with twosided."""
    _detail_images(folder)
    data, _ = mitsuba_scene_data(_write(folder, QUAD.format(bsdf)))
    material = data["materials"][data["shapes"][0]["material"]]
    assert material == {
        "type": "diffuse",
        "reflectance": {"rgb": [0.5, 0.5, 0.5]},
        "normal_map": {"texture": "normal_map_texture"},
        "shadowing_function": True,  # Mitsuba's default use_shadowing_function
    } | ({"two_sided": False} if "twosided" not in bsdf else {})  # Mitsuba's diffuse alone is one-sided
    assert data["textures"]["normal_map_texture"] == {"type": "bitmap", "file": "normal.png", "raw": True}
    normal_map = load_mitsuba_scene(folder / "scene.xml").shapes[0].material.detail.normal_map
    codes = np.asarray(Image.open(folder / "normal.png"), np.float64)
    np.testing.assert_allclose(normal_map.values, codes / 255.0, atol=1e-6)


def test_a_normal_map_on_a_rectangle_is_flipped_in_v(folder):
    """On Mitsuba's rectangle (v up) the normal map is looked up at (u, 1 − v), as every texture there: the same
    texel at the same point. The frame needs no change: both build x along dp/du and y = z × x."""
    _detail_images(folder)
    body = f'<shape type="rectangle"><bsdf type="normalmap">{NORMAL_MAP}{DIFFUSE}</bsdf></shape>'
    data, _ = mitsuba_scene_data(_write(folder, body))
    assert data["shapes"][0]["material"].endswith("_flipped_v")
    texture = data["textures"][data["materials"][data["shapes"][0]["material"]]["normal_map"]["texture"]]
    assert texture["uv_scale"] == [1.0, -1.0] and texture["uv_offset"] == [0.0, 1.0]


@pytest.mark.parametrize("order", ["bump-outside", "twosided-outside"])
def test_bumpmap_becomes_bump_map_and_scale(folder, order):
    """Mitsuba's bumpmap tilts the frame by tangents dp/du + scale · ∂h/∂u · n (bumpmap.cpp, `frame`): a surface
    displaced by scale · h, which is spectrace's bump_scale (scene units per texture value). Its one texture may
    have any name."""
    _detail_images(folder)
    bump = f'<bsdf type="bumpmap">{HEIGHTS}<float name="scale" value="0.05"/>{{}}</bsdf>'
    bsdf = (
        bump.format(f'<bsdf type="twosided">{DIFFUSE}</bsdf>')
        if order == "bump-outside"
        else f'<bsdf type="twosided">{bump.format(DIFFUSE)}</bsdf>'
    )
    data, _ = mitsuba_scene_data(_write(folder, QUAD.format(bsdf)))
    material = data["materials"][data["shapes"][0]["material"]]
    assert material["bump_map"] == {"texture": "bump_map_texture"} and material["bump_scale"] == 0.05
    detail = load_mitsuba_scene(folder / "scene.xml").shapes[0].material.detail
    assert detail.bump_scale == 0.05 and detail.bump_map.channels == 1 and detail.shadowing_function
    np.testing.assert_allclose(detail.bump_map.values[..., 0], [[0, 64 / 255], [128 / 255, 1]], atol=1e-6)


@pytest.mark.parametrize("kind", ["normalmap", "bumpmap"])
@pytest.mark.parametrize("value", [True, False])
def test_use_shadowing_function_becomes_shadowing_function(folder, kind, value):
    _detail_images(folder)
    switch = f'<boolean name="use_shadowing_function" value="{str(value).lower()}"/>'
    inner = NORMAL_MAP if kind == "normalmap" else HEIGHTS
    data, _ = mitsuba_scene_data(_write(folder, QUAD.format(f'<bsdf type="{kind}">{inner}{switch}{DIFFUSE}</bsdf>')))
    assert data["materials"][data["shapes"][0]["material"]]["shadowing_function"] is value
    assert load_mitsuba_scene(folder / "scene.xml").shapes[0].material.detail.shadowing_function is value


def test_bumpmap_scale_defaults_to_1(folder):
    _detail_images(folder)
    data, _ = mitsuba_scene_data(_write(folder, QUAD.format(f'<bsdf type="bumpmap">{HEIGHTS}{DIFFUSE}</bsdf>')))
    material = data["materials"][data["shapes"][0]["material"]]
    assert "bump_scale" not in material  # spectrace's default is Mitsuba's, 1
    assert load_mitsuba_scene(folder / "scene.xml").shapes[0].material.detail.bump_scale == 1.0


@pytest.mark.parametrize(
    "inside, opacity",
    [
        ('<float name="opacity" value="0.3"/>', 0.3),
        ("", 0.5),  # Mitsuba's default
        (
            '<texture type="bitmap" name="opacity"><string name="filename" value="mask.png"/>'
            '<boolean name="raw" value="true"/></texture>',
            {"texture": "opacity_texture"},
        ),
    ],
    ids=["number", "default", "texture"],
)
def test_mask_becomes_opacity(folder, inside, opacity):
    _detail_images(folder)
    data, _ = mitsuba_scene_data(_write(folder, QUAD.format(f'<bsdf type="mask">{inside}{DIFFUSE}</bsdf>')))
    assert data["materials"][data["shapes"][0]["material"]]["opacity"] == opacity
    detail = load_mitsuba_scene(folder / "scene.xml").shapes[0].material.detail
    if isinstance(opacity, float):
        assert detail.opacity == opacity
    else:
        np.testing.assert_allclose(detail.opacity.values[..., 0], [[0, 1], [1, 0]], atol=1e-6)


def test_adapters_nest_in_any_order(folder):
    """mask around twosided around normalmap around a plastic: every key lands on the plastic's material."""
    _detail_images(folder)
    bsdf = (
        '<bsdf type="mask"><float name="opacity" value="0.75"/><bsdf type="twosided">'
        f'<bsdf type="normalmap">{NORMAL_MAP}<bsdf type="plastic"/></bsdf></bsdf></bsdf>'
    )
    data, _ = mitsuba_scene_data(_write(folder, QUAD.format(bsdf)))
    material = data["materials"][data["shapes"][0]["material"]]
    assert material["type"] == "plastic" and material["opacity"] == 0.75
    assert material["normal_map"] == {"texture": "normal_map_texture"}
    detail = load_mitsuba_scene(folder / "scene.xml").shapes[0].material.detail
    assert detail.opacity == 0.75 and detail.normal_map is not None


@pytest.mark.parametrize(
    "bsdf, kind",
    [
        ('<bsdf type="roughconductor"><string name="material" value="Au"/>{}</bsdf>', "conductor"),
        ('<bsdf type="roughplastic">{}</bsdf>', "plastic"),
        ('<bsdf type="roughdielectric">{}</bsdf>', "dielectric"),
    ],
    ids=["roughconductor", "roughplastic", "roughdielectric"],
)
def test_a_textured_alpha_becomes_a_roughness_texture(folder, bsdf, kind):
    """A texture on `alpha` is GGX α per point in both: the roughness key takes it (raw, so α is the code value)."""
    Image.fromarray(np.array([[26, 51], [77, 102]], np.uint8)).save(folder / "alpha.png")
    alpha = (
        '<texture type="bitmap" name="alpha"><string name="filename" value="alpha.png"/>'
        '<boolean name="raw" value="true"/></texture><string name="distribution" value="ggx"/>'
    )
    data, notes = mitsuba_scene_data(_write(folder, QUAD.format(bsdf.format(alpha))))
    material = data["materials"][data["shapes"][0]["material"]]
    assert material["type"] == kind and material["roughness"] == {"texture": "roughness_texture"}
    roughness = load_mitsuba_scene(folder / "scene.xml").shapes[0].material.roughness
    assert isinstance(roughness, BitmapTexture)
    np.testing.assert_allclose(roughness.values[..., 0], np.array([[26, 51], [77, 102]]) / 255.0, atol=1e-6)


DETAIL_UNSUPPORTED = [
    (
        "normalmap-around-bumpmap",
        f'<bsdf type="normalmap">{NORMAL_MAP}<bsdf type="bumpmap">{HEIGHTS}{DIFFUSE}</bsdf></bsdf>',
        "bsdf 'normalmap' around a bsdf with a bump map already (a spectrace material takes one normal map or bump",
    ),
    (
        "bumpmap-around-bumpmap",
        f'<bsdf type="bumpmap">{HEIGHTS}<bsdf type="bumpmap">{HEIGHTS}{DIFFUSE}</bsdf></bsdf>',
        "bsdf 'bumpmap' around a bsdf with a bump map already",
    ),
    (
        "mask-around-mask",
        f'<bsdf type="mask"><bsdf type="mask">{DIFFUSE}</bsdf></bsdf>',
        "bsdf 'mask' around a bsdf with a opacity already",
    ),
    (
        "checkerboard-normalmap",
        f'<bsdf type="normalmap"><texture type="checkerboard" name="normalmap"/>{DIFFUSE}</bsdf>',
        "texture 'checkerboard' as normalmap (spectrace's normal maps are bitmaps or rawconstant)",
    ),
    (
        "colour-opacity",
        f'<bsdf type="mask"><rgb name="opacity" value="0.5"/>{DIFFUSE}</bsdf>',
        "rgb as opacity",
    ),
    (
        "bumpmap-extra-property",
        f'<bsdf type="bumpmap">{HEIGHTS}<float name="epsilon" value="1"/>{DIFFUSE}</bsdf>',
        "bsdf 'bumpmap' with epsilon",
    ),
    (
        "textured-anisotropic-alpha",
        '<bsdf type="roughdielectric"><texture type="checkerboard" name="alpha_u"/>'
        '<float name="alpha_v" value="0.2"/></bsdf>',
        "bsdf 'roughdielectric' with a textured alpha_u or alpha_v (anisotropic roughness)",
    ),
]


@pytest.mark.parametrize(
    "bsdf",
    [
        '<bsdf type="diffuse"><texture type="checkerboard" name="reflectance"/></bsdf>',
        f'<bsdf type="normalmap">{NORMAL_MAP}{DIFFUSE}</bsdf>',
    ],
)
def test_a_textured_cube_imports_with_its_uvs_as_they_are(folder, bsdf):
    """Spectrace's cube carries Mitsuba's cube's texture coordinates (test_mitsuba_uv_conventions), so a texture or
    a normal map on it imports unflipped, as on the sphere."""
    _detail_images(folder)
    data, _ = mitsuba_scene_data(_write(folder, f'<shape type="cube">{bsdf}</shape>'))
    (shape,) = data["shapes"]
    assert shape["type"] == "cube" and not shape["material"].endswith("_flipped_v")
    assert shape["material"] in data["materials"]


@pytest.mark.parametrize("name, body, says", DETAIL_UNSUPPORTED, ids=[case[0] for case in DETAIL_UNSUPPORTED])
def test_surface_detail_spectrace_cannot_represent_is_named(folder, name, body, says):
    _detail_images(folder)
    with pytest.raises(SpectraceError) as error:
        mitsuba_scene_data(_write(folder, body if body.startswith("<shape") else QUAD.format(body)))
    message = str(error.value)
    assert message.startswith(f"{folder / 'scene.xml'}: unsupported Mitsuba 3 plugins: "), message
    assert says in message and "\n" not in message, message


@pytest.mark.parametrize(
    "bsdf, path, says",
    [
        (
            f'<bsdf type="mask"><float name="opacity" value="1.5"/>{DIFFUSE}</bsdf>',
            "shape/bsdf/float@value",
            "opacity must lie in [0, 1], got 1.5",
        ),
        ('<bsdf type="normalmap"/>', "shape/bsdf", "bsdf 'normalmap' needs exactly one nested bsdf, got 0"),
        (
            f'<bsdf type="mask">{DIFFUSE}{DIFFUSE}</bsdf>',
            "shape/bsdf",
            "bsdf 'mask' needs exactly one nested bsdf, got 2",
        ),
        (
            f'<bsdf type="normalmap">{DIFFUSE}</bsdf>',
            "shape/bsdf",
            "bsdf 'normalmap' needs a property named 'normalmap'",
        ),
        (
            f'<bsdf type="bumpmap">{DIFFUSE}</bsdf>',
            "shape/bsdf",
            "bsdf 'bumpmap' needs exactly one nested texture, got 0",
        ),
        (
            f'<bsdf type="normalmap"><texture type="bitmap" name="normalmap">'
            f'<string name="filename" value="normal.png"/></texture>{DIFFUSE}</bsdf>',
            "shape/bsdf/texture",
            "is read as sRGB colours; it holds data",  # Mitsuba would decode it: spectrace refuses that
        ),
    ],
    ids=["opacity-above-1", "no-nested-bsdf", "two-nested-bsdfs", "no-normalmap", "no-height", "normal-map-not-raw"],
)
def test_bad_surface_detail_is_one_line(folder, monkeypatch, capsys, bsdf, path, says):
    _detail_images(folder)
    xml = _write(folder, QUAD.format(bsdf))
    (folder / "o.toml").write_text("# before\n")
    status, stderr = run_in_process(monkeypatch, capsys, ["import-mitsuba", str(xml), "-o", str(folder / "o.toml")])
    assert status == 2 and stderr.count("\n") == 1 and "Traceback" not in stderr, stderr
    assert stderr.startswith(f"error: {xml}: {path}: "), stderr
    assert says in stderr, stderr
    assert (folder / "o.toml").read_text() == "# before\n"


# ---------------------------------------------------------------- against Mitsuba 3


@pytest.mark.peer
def test_mitsuba_uv_conventions(folder, mitsuba_scalar_spectral):
    """The conventions this file states, measured in Mitsuba: the uv its rectangle, an OBJ and a PLY give a ray's
    hit (and its sphere and cube, against spectrace's), which texel row a bitmap shows at small v, and which colour its
    checkerboard shows where."""
    mi = mitsuba_scalar_spectral
    header = (
        "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
        "property float u\nproperty float v\nelement face 2\nproperty list uchar int vertex_indices\nend_header\n"
    )
    (folder / "quad.ply").write_text(header + "-1 -1 0 0 0\n1 -1 0 1 0\n1 1 0 1 1\n-1 1 0 0 1\n3 0 1 2\n3 0 2 3\n")
    shapes = {
        "rectangle": ({"type": "rectangle"}, lambda x, y: ((x + 1) / 2, (y + 1) / 2)),
        "obj": ({"type": "obj", "filename": str(folder / "quad.obj")}, lambda x, y: ((x + 1) / 2, (1 - y) / 2)),
        "ply": ({"type": "ply", "filename": str(folder / "quad.ply")}, lambda x, y: ((x + 1) / 2, (y + 1) / 2)),
    }
    for name, (shape, expected) in shapes.items():
        scene = mi.load_dict({"type": "scene", "shape": shape})
        for x, y in [(-0.8, -0.6), (0.7, 0.3), (0.2, 0.9)]:
            hit = scene.ray_intersect(mi.Ray3f([x, y, 1.0], [0.0, 0.0, -1.0]))
            np.testing.assert_allclose(np.array(hit.uv), expected(x, y), atol=1e-5, err_msg=name)
    # The sphere: u from the azimuth about +z from +x towards +y, v from the polar angle from +z (spectrace's
    # sphere's vertices carry the same: tests/geometry/test_geometry.py).
    scene = mi.load_dict({"type": "scene", "shape": {"type": "sphere"}})
    for direction in [(0.3, 0.5, 0.8), (-0.6, 0.2, -0.1), (0.4, -0.7, 0.3), (-0.2, -0.3, -0.9)]:
        d = np.array(direction) / np.linalg.norm(direction)
        hit = scene.ray_intersect(mi.Ray3f(3.0 * d, -d))
        expected = (np.mod(np.arctan2(d[1], d[0]), 2 * np.pi) / (2 * np.pi), np.arccos(d[2]) / np.pi)
        np.testing.assert_allclose(np.array(hit.uv), expected, atol=1e-5, err_msg=f"sphere {direction}")
    # The cube: rays at a grid of points on every face of Mitsuba's cube; the uv of each hit against the uv that
    # spectrace's cube interpolates at the same point (barycentric in the triangle of its face that holds it).
    scene = mi.load_dict({"type": "scene", "shape": {"type": "cube"}})
    mesh = primitives.cube()
    corners = mesh.vertices[mesh.faces]
    normals = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    steps = np.linspace(-0.9, 0.9, 5)
    hits = 0
    for axis in range(3):
        for sign in (-1.0, 1.0):
            outward = np.zeros(3)
            outward[axis] = sign
            for a in steps:
                for b in steps:
                    point = np.insert(np.array([a, b]), axis, sign)
                    hit = scene.ray_intersect(mi.Ray3f(point + 2.0 * outward, -outward))
                    assert hit.is_valid()
                    on_face = np.flatnonzero(normals @ outward > 0)
                    for triangle in on_face:
                        p0, p1, p2 = corners[triangle]
                        weights = np.linalg.lstsq(np.column_stack([p1 - p0, p2 - p0]), point - p0, rcond=None)[0]
                        barycentric = np.array([1.0 - weights.sum(), *weights])
                        if barycentric.min() >= -1e-9:
                            break
                    expected = barycentric @ mesh.uvs[mesh.faces[triangle]]
                    np.testing.assert_allclose(np.array(hit.uv), expected, atol=1e-5, err_msg=f"cube {point}")
                    hits += 1
    assert hits == 6 * 25
    mi.set_variant("scalar_rgb")  # texture values without spectra
    try:
        image = np.zeros((2, 2, 3), np.float32)
        image[0, :, 0] = 1.0  # row 0 red, row 1 blue
        image[1, :, 2] = 1.0
        bitmap = mi.load_dict({"type": "bitmap", "data": mi.TensorXf(image), "raw": True, "filter_type": "nearest"})
        checker = mi.load_dict({"type": "checkerboard", "color0": {"type": "rgb", "value": [1, 0, 0]}, "color1": 0.0})
        si = mi.SurfaceInteraction3f()
        for uv, bitmap_red, checker_red in [((0.3, 0.2), 1, 1), ((0.3, 0.7), 0, 0), ((0.7, 0.7), 0, 1)]:
            si.uv = mi.Point2f(*uv)
            assert np.array(bitmap.eval(si))[0] == bitmap_red and np.array(checker.eval(si))[0] == checker_red, uv
    finally:
        mi.set_variant("scalar_spectral")


def _uv_sphere_obj(path: Path, rings: int = 6, segments: int = 10) -> None:
    """A unit sphere as an OBJ with vertex normals (smooth shading) and texture coordinates (u around, v down from
    the top as an OBJ stores it: vt v = 1 at the top), outward winding."""
    lines = []
    for i in range(rings + 1):
        theta = np.pi * i / rings
        for j in range(segments + 1):
            phi = 2 * np.pi * j / segments
            x, y, z = np.sin(theta) * np.sin(phi), np.cos(theta), np.sin(theta) * np.cos(phi)
            lines += [f"v {x:.9f} {y:.9f} {z:.9f}", f"vn {x:.9f} {y:.9f} {z:.9f}", f"vt {j / segments} {1 - i / rings}"]
    for i in range(rings):
        for j in range(segments):
            a, b = i * (segments + 1) + j + 1, (i + 1) * (segments + 1) + j + 1
            corners = [(a, b, b + 1), (a, b + 1, a + 1)]
            for triangle in corners[1:] if i == rings - 1 else corners[:1] if i == 0 else corners:
                lines.append("f " + " ".join(f"{k}/{k}/{k}" for k in triangle))
    path.write_text("\n".join(lines) + "\n")


# The comparison scene: a checkerboard floor (a rectangle, so v is flipped on import; to_uv scale and translate)
# under a constant-tilt normal map (_TILT, leaning both along u and along y = n × x, so that a flipped sign of either
# or a swapped frame changes how the light meets it),
# a back wall (a rectangle) showing texture.png with nearest filtering, and a smooth-shaded OBJ sphere with vertex
# normals wearing texture.png mirrored and bilinear (coarse, 6 x 10 quads, so that faceted shading would show); lit
# from the side by a directional light (its terminator crosses the ball, where shading follows the normals most) and a
# dim constant environment. Every bsdf is two-sided, as spectrace's diffuse is.
COMPARISON = """<scene version="3.0.0">
    <integrator type="path"><integer name="max_depth" value="3"/></integrator>
    <sensor type="perspective">
        <float name="fov" value="45"/>
        <transform name="to_world"><lookat origin="0, 1.4, 4.2" target="0, 0.1, 0" up="0, 1, 0"/></transform>
        <film type="hdrfilm">
            <integer name="width" value="{size}"/><integer name="height" value="{size}"/>
            <string name="pixel_format" value="xyz"/><rfilter type="box"/>
        </film>
    </sensor>
    <texture type="bitmap" id="picture">
        <string name="filename" value="texture.png"/><string name="filter_type" value="nearest"/>
    </texture>
    <bsdf type="twosided" id="wall"><bsdf type="diffuse"><ref name="reflectance" id="picture"/></bsdf></bsdf>
    <bsdf type="twosided" id="floor">{tilt_open}
        <bsdf type="diffuse">
            <texture type="checkerboard" name="reflectance">
                <rgb name="color0" value="0.75, 0.7, 0.3"/><rgb name="color1" value="0.1, 0.25, 0.5"/>
                <transform name="to_uv"><scale value="3"/><translate x="0.25" y="0.1"/></transform>
            </texture>
        </bsdf>
    {tilt_close}</bsdf>
    <bsdf type="twosided" id="ball"><bsdf type="diffuse">
        <texture type="bitmap" name="reflectance">
            <string name="filename" value="texture.png"/><string name="wrap_mode" value="mirror"/>
            <transform name="to_uv"><scale x="2" y="1.5"/></transform>
        </texture>
    </bsdf></bsdf>
    <shape type="rectangle">
        <transform name="to_world"><scale value="2"/><rotate x="1" angle="-90"/><translate y="-0.8"/></transform>
        <ref id="floor"/>
    </shape>
    <shape type="rectangle">
        <transform name="to_world"><scale x="2" y="1.5"/><translate y="0.7" z="-2"/></transform>
        <ref id="wall"/>
    </shape>
    <shape type="obj">
        <string name="filename" value="ball.obj"/>
        <transform name="to_world"><scale value="1.1"/><rotate y="1" angle="-30"/></transform>
        <ref id="ball"/>
    </shape>
    <emitter type="directional">
        <vector name="direction" x="1" y="-0.25" z="0.35"/><rgb name="irradiance" value="2.5, 2.5, 2.5"/>
    </emitter>
    <emitter type="constant"><rgb name="radiance" value="0.15, 0.15, 0.15"/></emitter>
</scene>
"""
# The floor's tangent-space normal: tilted about 13° from the rectangle's normal, toward −u (world −x, where the
# directional light comes from) and toward +y (world −z, also toward the light, away from the camera). The light
# meets the floor about 13° above the plane, so the tilt changes its brightness by a large fraction. Kept below the
# camera's elevation over the floor: where the viewer is below the tilted plane the two renderers differ by design
# (spectrace shades with the geometric normal there, docs/textures.md "Light leaks").
_TILT = np.array([-0.15, 0.18, 0.97])
TILTED = {
    "tilt_open": '<bsdf type="normalmap"><texture type="bitmap" name="normalmap">'
    '<string name="filename" value="tilt.png"/><boolean name="raw" value="true"/></texture>',
    "tilt_close": "</bsdf>",
}
UNTILTED = {"tilt_open": "", "tilt_close": ""}  # for the export, which has no surface detail yet


def _write_tilt_map(path: Path, tilt: np.ndarray = _TILT) -> None:
    """A raw 4 x 4 RGB normal map holding n = tilt / |tilt| everywhere, as 8-bit codes of (n + 1) / 2."""
    n = tilt / np.linalg.norm(tilt)
    codes = np.round((n + 1) / 2 * 255).astype(np.uint8)
    Image.fromarray(np.tile(codes, (4, 4, 1))).save(path)


def _texel_colours() -> np.ndarray:
    """The linear sRGB colours the comparison's textures show: texture.png's texels and the checkerboard's sides."""
    codes = np.asarray(Image.open(DATA / "texture.png").convert("RGB"), np.float64).reshape(-1, 3)
    return np.vstack([_srgb_decoded(codes), [[0.75, 0.7, 0.3], [0.1, 0.25, 0.5]]])


def _uplift_difference(mi, colours: np.ndarray) -> float:
    """The largest relative difference, over the colours and X, Y, Z, between Mitsuba's RGB uplift and spectrace's
    (the same Jakob & Hanika model from different coefficient tables) in what the scene makes of them: a texel lit
    by the scene's (D65) light once, R·D65, and after two bounces off the same colour, R²·D65."""
    from spectrace.spectral.colorimetry import spectrum_to_xyz
    from spectrace.spectral.grid import GRID_NM
    from spectrace.spectral.illuminants import cie_illuminant
    from spectrace.spectral.rgb_texture import reflectance_coefficients
    from spectrace.spectral.uplift import sigmoid_polynomial_spectrum

    d65 = cie_illuminant("D65").values
    ours = np.array([sigmoid_polynomial_spectrum(c) for c in reflectance_coefficients(colours)])
    theirs = []
    for colour in colours:
        coefficients = mi.srgb_model_fetch(mi.Color3f(*colour))
        values = []
        for start in range(0, len(GRID_NM), 4):
            wavelengths = np.resize(GRID_NM[start : start + 4], 4)
            values += list(np.array(mi.srgb_model_eval(coefficients, mi.Spectrum(*wavelengths))))[
                : len(GRID_NM[start : start + 4])
            ]
        theirs.append(values)
    theirs = np.array(theirs)
    worst = 0.0
    for power in (1, 2):
        a, b = spectrum_to_xyz(ours**power * d65), spectrum_to_xyz(theirs**power * d65)
        worst = max(worst, float(np.max(np.abs(a - b) / a)))
    return worst


@pytest.mark.peer
@pytest.mark.parametrize("ball", ["obj", "sphere"])
def test_textured_scene_renders_like_mitsuba(folder, device, mitsuba_scalar_spectral, ball):
    """COMPARISON rendered by Mitsuba's scalar_spectral variant and, imported, by spectrace: REPLICAS independent
    images of REPLICA_SPP samples from each; film XYZ means over 4 x 4-pixel blocks and over the whole image must
    agree within 5 standard errors of the difference (from the replicas' spread) plus an uplift allowance. Both
    renderers turn each texel's RGB into a spectrum by Jakob & Hanika's model, but from different coefficient tables
    (spectrace's within ΔE 0.15 of the exact fit), which changes what a texel reflects by up to
    `_uplift_difference` (2.2 % for these colours, mostly after two bounces off the darkest): each block may differ
    by that fraction of its mean on top of the noise.

    Measured: blocks within 3.7 σ (mean 0.8 σ), whole-image X, Y, Z within 1.5 σ, at a block standard error of
    about 1.7 %. Textures not flipped in v on the rectangles fail at 83 σ; the ball shaded with its facets
    (face_normals) instead of its vertex normals at 16 σ. With the floor's normal map: blocks within 3.6 σ (mean
    0.95 σ); its green channel flipped on spectrace's side only (a DirectX map) fails at 10.8 σ, its red at 37 σ.
    With `ball = "sphere"` the ball is the built-in sphere (Mitsuba's exact one, spectrace's icosphere with Mitsuba's
    uv)."""
    mi = mitsuba_scalar_spectral
    replicas, replica_spp, size, block = 16, 8, 32, 4
    _uv_sphere_obj(folder / "ball.obj")
    _write_tilt_map(folder / "tilt.png")
    xml = folder / "comparison.xml"
    text = COMPARISON.format(size=size, **TILTED)
    if ball == "sphere":
        text = text.replace(
            '<shape type="obj">\n        <string name="filename" value="ball.obj"/>', '<shape type="sphere">'
        )
        assert '<shape type="sphere">' in text
    xml.write_text(text)

    scene = mi.load_file(str(xml))
    theirs = np.stack([mitsuba_film_xyz(mi.render(scene, spp=replica_spp, seed=seed), mi) for seed in range(replicas)])
    ours = spectrace_replicas(Renderer(load_mitsuba_scene(xml), device), replicas, replica_spp)
    allowance = _uplift_difference(mi, _texel_colours())

    n = size // block
    for reduce in (
        lambda images: images.reshape(len(images), n, block, n, block, 3).mean(axis=(2, 4)),
        lambda images: images.mean(axis=(1, 2)),
    ):
        a, b = reduce(ours), reduce(theirs)
        difference = a.mean(axis=0) - b.mean(axis=0)
        standard_error = np.sqrt(a.var(axis=0, ddof=1) / len(a) + b.var(axis=0, ddof=1) / len(b))
        beyond_allowance = np.abs(difference) - allowance * np.abs(b.mean(axis=0))
        assert np.all(beyond_allowance <= 5 * standard_error), (np.max(np.abs(difference) / standard_error), allowance)
    assert theirs[..., 1].mean() > 0.05  # a lit image


# ---------------------------------------------------------------- export


@pytest.mark.peer
def test_exported_textures_import_back_the_same(folder, mitsuba_scalar_spectral):
    """COMPARISON imported, exported (scene_to_mitsuba_dict: meshes as PLY files with spectrace's uv, bitmaps as
    float OpenEXR files), written to XML by Mitsuba's own serialiser and imported again: each shape's vertices look
    its texture up at the same st, with the same texels, wrap and filter, and the checkerboard's sides the same."""
    from spectrace.interop.mitsuba.export import scene_to_mitsuba_dict

    mi = mitsuba_scalar_spectral
    _uv_sphere_obj(folder / "ball.obj")
    xml = folder / "comparison.xml"
    xml.write_text(COMPARISON.format(size=8, **UNTILTED))
    original = load_mitsuba_scene(xml)
    exported = scene_to_mitsuba_dict(original, folder / "export")
    config = mi.parser.ParserConfig("scalar_spectral")
    round_trip_xml = folder / "export" / "scene.xml"
    round_trip_xml.write_text(mi.parser.write_string(mi.parser.parse_dict(config, exported)))
    round_trip = load_mitsuba_scene(round_trip_xml)

    assert len(round_trip.shapes) == len(original.shapes) == 3
    for before, after in zip(original.shapes, round_trip.shapes, strict=True):
        np.testing.assert_allclose(after.mesh.vertices, before.mesh.vertices, atol=1e-6)
        texture_before, texture_after = before.material.reflectance, after.material.reflectance
        assert type(texture_after) is type(texture_before)
        np.testing.assert_allclose(_st(after, texture_after), _st(before, texture_before), atol=1e-5)
        if isinstance(texture_before, BitmapTexture):
            np.testing.assert_array_equal(texture_after.values, texture_before.values)
            assert (texture_after.placement.wrap, texture_after.placement.filter) == (
                texture_before.placement.wrap,
                texture_before.placement.filter,
            )
        else:
            for side in ("color0", "color1"):
                np.testing.assert_allclose(
                    getattr(texture_after, side).values, getattr(texture_before, side).values, atol=1e-7
                )


@pytest.mark.peer
def test_what_mitsuba_textures_cannot_match_is_refused(tmp_path, mitsuba_scalar_spectral):
    """A spectral texture (Mitsuba's bitmap holds RGB), trilinear filtering (Mitsuba's bitmap has no MIP levels) and
    scale and mix textures (Mitsuba 3 has neither) are refused in one line, naming the texture."""
    import spectrace
    from spectrace.interop.mitsuba.export import scene_to_mitsuba_dict
    from spectrace.scene.model import Camera, Scene

    spectral = spectrace.spectral_texture(np.full((2, 2, 3), 0.5), [450.0, 550.0, 650.0])
    trilinear = spectrace.bitmap(np.full((2, 2), 0.5), filter="trilinear")
    for texture, says in [
        (spectral, "a spectral texture ('array'): Mitsuba 3 has no spectral image texture"),
        (trilinear, "texture 'array': filter 'trilinear' (Mitsuba 3's bitmap has no MIP mapping)"),
        (spectrace.scale_texture(0.5, 0.5), "a scale texture ('scale'): Mitsuba 3 has no scale texture"),
        (spectrace.mix_texture(0.2, 0.4), "a mix texture ('mix'): Mitsuba 3 has no mix texture"),
    ]:
        scene = Scene(
            camera=Camera(origin=(0.0, 0.0, 3.0), target=(0.0, 0.0, 0.0)),
            width=4,
            height=4,
            shapes=[spectrace.shape("rectangle", spectrace.diffuse(texture))],
        )
        with pytest.raises(SpectraceError) as error:
            scene_to_mitsuba_dict(scene, tmp_path)
        assert says in str(error.value) and "\n" not in str(error.value), str(error.value)


def test_a_checkerboard_read_as_a_number_imports_its_sides_as_mitsuba_looks_them_up(folder):
    """Mitsuba 3's checkerboard gives its number lookup (an α, a blend's weight) color1 where its colour lookup gives
    color0: asked here of Mitsuba itself at the centre of the first square. A shared checkerboard used both ways
    becomes two tables, the colour one as written and the number one with its sides swapped."""
    mi = pytest.importorskip(
        "mitsuba", reason="the comparison with Mitsuba's lookups needs `pip install spectrace[test]`"
    )
    mi.set_variant("scalar_rgb")
    board = mi.load_dict({"type": "checkerboard", "color0": 0.1, "color1": 0.9})
    si = mi.SurfaceInteraction3f()
    si.uv = mi.Point2f(0.25, 0.25)
    colour_there, number_there = float(board.eval(si)[0]), float(board.eval_1(si))
    assert (colour_there, number_there) == pytest.approx((0.1, 0.9))  # the two lookups disagree
    body = (
        """<texture type="checkerboard" id="board">
            <float name="color0" value="0.1"/><float name="color1" value="0.9"/></texture>
        <bsdf type="roughconductor" id="metal"><ref name="alpha" id="board"/></bsdf>
        <bsdf type="diffuse" id="paint"><ref name="reflectance" id="board"/></bsdf>
        <bsdf type="blendbsdf" id="blend"><ref name="weight" id="board"/>
            <bsdf type="diffuse"/><bsdf type="conductor"/></bsdf>
        """
        + QUAD.format('<ref id="metal"/>')
        + QUAD.format('<ref id="paint"/>')
        + QUAD.format('<ref id="blend"/>')
    )
    data, _ = mitsuba_scene_data(_write(folder, body))
    textures, materials = data["textures"], data["materials"]
    number = materials["metal"]["roughness"]["texture"]
    colour = materials["paint"]["reflectance"]["texture"]
    assert materials["blend"]["amount"] == {"texture": number} and colour != number
    assert textures[colour]["color0"] == {"value": pytest.approx(colour_there)}
    assert textures[number]["color0"] == {"value": pytest.approx(number_there)}
