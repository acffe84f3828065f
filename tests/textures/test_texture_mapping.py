"""Texture mappings (textures/mapping.py, kernels/texture_mapping.cl), against their closed forms: a checkerboard
whose (u, v) a mapping makes from the surface point, seen by an orthographic camera, so each pixel's points are
known. Where the closed form (pbrt-v4's TextureMapping2D formulas, written here from the book, not the code under
test) puts one side of the board over the whole pixel, the pixel is bit for bit the render of a surface of that
side's albedo (same seed: the same paths, the texture reading no random numbers); the pixels the edges cross are
left out. Both sides must cover many pixels, so a mapping that put the board anywhere else fails."""

import numpy as np
import pytest

import spectrace
from spectrace.engine.renderer import Renderer
from spectrace.errors import SpectraceError
from spectrace.interop.mitsuba.export import scene_to_mitsuba_dict
from spectrace.scene.model import Camera, Scene

SIDE = 32
SUBSAMPLES = 6  # per pixel and axis: where the closed form is checked to be one side over the whole pixel
ALBEDOS = (0.8, 0.1)


def _scene(geometry: str, reflectance) -> Scene:
    # Seen from +z, image right +x and up +y, the view 2 units across: pixel (i, j) covers x in -1 + 2 [j, j + 1]/SIDE,
    # y in 1 - 2 [i + 1, i]/SIDE.
    camera = Camera(origin=(0.0, 0.0, 5.0), target=(0.0, 0.0, 0.0), type="orthographic", view_width=2.0)
    return Scene(
        camera=camera,
        width=SIDE,
        height=SIDE,
        shapes=[spectrace.shape(geometry, spectrace.diffuse(reflectance))],
        lights=[spectrace.constant_environment(1.0)],
        max_depth=2,  # one bounce
        spp=2,
        seed=5,
        sampler="independent",
    )


def _render(device, geometry: str, reflectance) -> np.ndarray:
    return Renderer(_scene(geometry, reflectance), device).render().xyz


def _pixel_points() -> tuple[np.ndarray, np.ndarray]:
    """x, y of SUBSAMPLES² points spanning each pixel, inset from its border by a hair: [SIDE, SIDE, n]."""
    offsets = (np.arange(SUBSAMPLES) + 0.5) / SUBSAMPLES
    i = np.arange(SIDE)[:, None, None, None] + offsets[None, None, :, None]
    j = np.arange(SIDE)[None, :, None, None] + offsets[None, None, None, :]
    x = np.broadcast_to(-1.0 + 2.0 * j / SIDE, (SIDE, SIDE, SUBSAMPLES, SUBSAMPLES))
    y = np.broadcast_to(1.0 - 2.0 * i / SIDE, (SIDE, SIDE, SUBSAMPLES, SUBSAMPLES))
    return x.reshape(SIDE, SIDE, -1), y.reshape(SIDE, SIDE, -1)


def _check(device, geometry: str, mapping: str, to_texture, st_of, uv_scale, v1=(1, 0, 0), v2=(0, 1, 0)):
    """st_of(x, y) -> (s, t) pbrt's mapping gives at the visible point over (x, y), NaN off the surface; the board's
    side is floor(S) + floor(T) mod 2 at (S, T) = uv_scale · (s, 1 − t) (the mapping's v down the image, as a
    mesh's)."""
    # Through the API: the texture space placed by the inverse of the world-to-texture matrix.
    placed = [{"matrix": np.linalg.inv(np.asarray(to_texture, np.float64)).tolist()}]
    board = spectrace.checkerboard(*ALBEDOS, uv_scale=uv_scale, mapping=mapping, transform=placed, v1=v1, v2=v2)
    image = _render(device, geometry, board)
    plain = [_render(device, geometry, a) for a in ALBEDOS]
    x, y = _pixel_points()
    s, t = st_of(x, y)
    side = (np.floor(uv_scale[0] * s) + np.floor(uv_scale[1] * (1.0 - t))) % 2
    for k in (0, 1):
        clean = np.all(side == k, axis=-1)
        assert clean.sum() >= 40, (mapping, k, clean.sum())
        np.testing.assert_array_equal(image[clean], plain[k][clean])
    # And the board is not the same everywhere: the two sides' pixels differ.
    assert not np.array_equal(plain[0], plain[1])


def _sphere_point(x, y):
    """The unit sphere's point seen over (x, y) from +z: (x, y, √(1 − x² − y²)), NaN beyond its outline."""
    with np.errstate(invalid="ignore"):
        return x, y, np.sqrt(1.0 - x * x - y * y)


def test_planar_mapping_puts_the_board_where_p_dot_v1_and_p_dot_v2_say(device):
    """A rectangle in z = 0, its texture space moved by (0.3, -0.2, 0) and v1, v2 turned and scaled: s = q · v1,
    t = q · v2, q = p − (0.3, −0.2, 0)."""
    v1, v2 = np.array([1.5, 0.5, 0.0]), np.array([-0.5, 1.5, 0.0])
    to_texture = np.eye(4)
    to_texture[:3, 3] = (-0.3, 0.2, 0.0)

    def st_of(x, y):
        q = np.stack([x - 0.3, y + 0.2, np.zeros_like(x)], axis=-1)
        return q @ v1, q @ v2

    _check(device, "rectangle", "planar", to_texture, st_of, (1.0, 1.0), v1, v2)


def test_spherical_mapping_puts_the_board_at_theta_over_pi_and_phi_over_two_pi(device):
    """The unit sphere about the texture space's origin: s = θ/π (θ from +z), t = φ/2π (φ from +x toward +y, in
    [0, 2π)), the board 4 × 8 squares over them."""

    def st_of(x, y):
        px, py, pz = _sphere_point(x, y)
        phi = np.mod(np.arctan2(py, px), 2 * np.pi)
        return np.arccos(np.clip(pz, -1, 1)) / np.pi, phi / (2 * np.pi)

    _check(device, "sphere", "spherical", np.eye(4), st_of, (4.0, 8.0))


def test_cylindrical_mapping_puts_the_board_at_phi_and_height(device):
    """The unit sphere with a cylindrical mapping whose texture space is turned about x (texture x' = x, y' = z,
    z' = −y: the cylinder's axis across the image): s = (π + atan2(y', x'))/2π, t = z'."""
    rotate = np.eye(4)
    rotate[1:3, 1:3] = [[0.0, 1.0], [-1.0, 0.0]]  # world to texture: y' = z, z' = -y

    def st_of(x, y):
        px, py, pz = _sphere_point(x, y)
        tx, ty, tz = px, pz, -py
        return (np.pi + np.arctan2(ty, tx)) / (2 * np.pi), tz

    _check(device, "sphere", "cylindrical", rotate, st_of, (6.0, 3.0))


def test_a_mapped_texture_is_refused_by_the_mitsuba_export(tmp_path, mitsuba_scalar_spectral):
    """Mitsuba 3's textures read the surface's uv only: a mapping would be lost, so the export says so."""
    board = spectrace.checkerboard(0.8, 0.1, mapping="spherical")
    with pytest.raises(SpectraceError, match="with a spherical mapping"):
        scene_to_mitsuba_dict(_scene("sphere", board), tmp_path)


@pytest.mark.parametrize(
    "arguments, message",
    [
        ({"mapping": "conical"}, "mapping must be one of 'uv', 'spherical', 'cylindrical', 'planar'"),
        ({"transform": [{"translate": [1, 0, 0]}]}, 'a transform is read with a mapping other than "uv"'),
        ({"mapping": "planar", "v1": (1, 0)}, "v1 and v2 are three finite numbers each"),
    ],
)
def test_the_api_refuses_a_bad_mapping_in_one_line(arguments, message):
    with pytest.raises(SpectraceError, match=message):
        spectrace.checkerboard(0.8, 0.1, **arguments)


@pytest.mark.parametrize(
    "keys, key_path, message",
    [
        ("transform = [{ translate = [1, 0, 0] }]", "materials.board.reflectance.transform", "a mapping other"),
        ('mapping = "conical"', "materials.board.reflectance.mapping", ""),
        ('mapping = "planar", transform = [{ scale = 0 }]', "materials.board.reflectance.transform", ""),
    ],
)
def test_the_scene_file_refuses_a_bad_mapping_naming_its_key(tmp_path, keys, key_path, message):
    from scene_text import camera_film
    from spectrace.scene.loader import load_scene

    path = tmp_path / "s.toml"
    path.write_text(
        camera_film()
        + '[materials.board]\ntype = "diffuse"\n'
        + f'reflectance = {{ texture = "checkerboard", {keys} }}\n'
        + '[[shapes]]\ntype = "rectangle"\nmaterial = "board"\n'
    )
    with pytest.raises(SpectraceError) as failure:
        load_scene(path)
    assert key_path in str(failure.value) and message in str(failure.value), str(failure.value)
    assert "\n" not in str(failure.value)


def test_a_scene_file_mapping_loads_as_the_apis(tmp_path):
    from scene_text import camera_film
    from spectrace.scene.loader import load_scene

    path = tmp_path / "s.toml"
    path.write_text(
        camera_film()
        + '[materials.board]\ntype = "diffuse"\n'
        + 'reflectance = { texture = "dots", mapping = "planar", v1 = [0, 2, 0], '
        + "transform = [{ translate = [1, 2, 3] }] }\n"
        + '[[shapes]]\ntype = "rectangle"\nmaterial = "board"\n'
    )
    (shape,) = load_scene(path).shapes
    api = spectrace.dots_texture(mapping="planar", v1=(0, 2, 0), transform=[{"translate": [1, 2, 3]}])
    assert shape.material.reflectance.placement == api.placement
    assert np.allclose(np.reshape(api.placement.mapping_rows, (3, 4))[:2], [[0, 2, 0, -4], [0, 1, 0, -2]])


def test_surface_detail_refuses_a_mapped_texture_in_one_line():
    """Normal and bump maps and opacity are read at the surface's own uv (kernels/surface_detail.cl)."""
    board = spectrace.checkerboard(0.8, 0.1, mapping="cylindrical")
    with pytest.raises(SpectraceError, match="bump_map takes no cylindrical mapping"):
        spectrace.diffuse(0.5, bump_map=board)


def test_the_scene_kernels_of_a_mapped_texture_render_the_general_kernels_image_bit_for_bit(device):
    """SCENE_HAS_TEXTURE_MAPPINGS builds the mapping in only where a texture has one; the general kernels, which
    always have it, must give the same bits."""
    board = spectrace.checkerboard(*ALBEDOS, uv_scale=(4.0, 8.0), mapping="spherical")
    scene = _scene("sphere", board)
    specialised = Renderer(scene, device, specialise=True).render().xyz
    general = Renderer(scene, device, specialise=False).render().xyz
    assert specialised[..., 1].mean() > 0
    assert np.array_equal(specialised.view(np.uint32), general.view(np.uint32))


def test_a_mapped_image_as_a_mix_operand_is_looked_up_through_its_mapping(device):
    """A composite's operands map themselves (texture.cl's inner lookup): a mix with amount 0 of a planar-mapped
    image renders the image's own render bit for bit (mix(a, b, 0) = a), and differs from the unmapped image."""
    texels = np.array([[[0.9, 0.2, 0.1], [0.1, 0.3, 0.8]]])
    mapped = {"mapping": "planar", "v1": (2.0, 0.0, 0.0), "v2": (0.0, 2.0, 0.0), "filter": "nearest"}
    image = spectrace.bitmap(texels, **mapped)
    alone = _render(device, "rectangle", image)
    mixed = _render(device, "rectangle", spectrace.mix_texture(image, 0.1, 0.0))
    np.testing.assert_array_equal(mixed, alone)
    unmapped = _render(device, "rectangle", spectrace.bitmap(texels, filter="nearest"))
    assert not np.array_equal(alone, unmapped)
