"""The `mix` material: one of two materials shades each point, the second with probability `amount`, so a pixel
converges to the blend (1 − amount) f₁ + amount f₂ (pbrt-v4's MixMaterial, Mitsuba 3's blendbsdf). An image is
linear in the BSDF at the surface the camera sees when that surface is all the scene reflects from, so the mix's
image is (1 − amount) · image(first) + amount · image(second), region by region: checked against separate renders
of the two materials, within 5 standard errors of the region means (the pixel spread of each image)."""

from pathlib import Path

import numpy as np
import pytest

from scene_text import camera_film
from spectrace.engine.renderer import Renderer
from spectrace.errors import SpectraceError
from spectrace.scene.loader import load_scene

# A square filling the view, lit by a point light off to one side: a diffuse red and a rough gold, whose highlight
# makes the regions differ. One bounce (max_depth 2): light, surface, camera.
SCENE = (
    camera_film(
        origin="[0.0, 0.0, 3.0]",
        target="[0.0, 0.0, 0.0]",
        fov="30",
        width="24",
        height="24",
    )
    + """[integrator]
type = "{integrator}"
max_depth = 2
[sampler]
spp = {spp}
[materials.red]
type = "diffuse"
reflectance = {{ rgb = [0.8, 0.15, 0.1] }}
[materials.gold]
type = "conductor"
metal = "Au"
roughness = 0.3
[materials.blue]
type = "diffuse"
reflectance = {{ rgb = [0.1, 0.2, 0.7] }}
{extra}
[[shapes]]
type = "rectangle"
material = "{material}"
transform = [{{ scale = 2.0 }}]
[[lights]]
type = "point"
position = [0.6, 0.4, 1.2]
power = 40.0
"""
)
REGIONS = 3  # 3 x 3 blocks of 8 x 8 pixels


def _scene_path(tmp_path: Path, material: str, extra: str = "", integrator: str = "path", spp: int = 16) -> Path:
    path = tmp_path / f"{material}_{integrator}.toml"
    path.write_text(SCENE.format(material=material, extra=extra, integrator=integrator, spp=spp))
    return path


def _render(path: Path, device) -> np.ndarray:
    return Renderer(load_scene(path), device).render().xyz.astype(np.float64)


def _regions(xyz: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each region's mean XYZ and the variance of that mean (pixel spread / pixel count)."""
    h, w, _ = xyz.shape
    blocks = xyz.reshape(REGIONS, h // REGIONS, REGIONS, w // REGIONS, 3).transpose(0, 2, 1, 3, 4)
    blocks = blocks.reshape(REGIONS, REGIONS, -1, 3)
    return blocks.mean(axis=2), blocks.var(axis=2, ddof=1) / blocks.shape[2]


def _z_scores(mixed: np.ndarray, parts: list[tuple[float, np.ndarray]]) -> np.ndarray:
    """(mixed − Σ w · part) / its standard error, per region and channel."""
    mean, variance = _regions(mixed)
    expected = np.zeros_like(mean)
    for weight, image in parts:
        part_mean, part_variance = _regions(image)
        expected += weight * part_mean
        variance = variance + weight**2 * part_variance
    return (mean - expected) / np.sqrt(variance)


def _mix(name: str, first: str, second: str, amount: str) -> str:
    return f'[materials.{name}]\ntype = "mix"\nmaterials = ["{first}", "{second}"]\namount = {amount}\n'


@pytest.mark.parametrize("amount", [0.2, 0.75])
def test_a_mix_of_a_diffuse_and_a_rough_conductor_renders_their_blend(tmp_path, device, amount):
    red = _render(_scene_path(tmp_path, "red"), device)
    gold = _render(_scene_path(tmp_path, "gold"), device)
    mixed = _render(_scene_path(tmp_path, "m", _mix("m", "red", "gold", str(amount))), device)
    z = _z_scores(mixed, [(1.0 - amount, red), (amount, gold)])
    assert np.all(np.abs(z) < 5), z
    # The weights swapped, the second material at 1 − amount: far outside the noise.
    swapped = _z_scores(mixed, [(amount, red), (1.0 - amount, gold)])
    assert np.max(np.abs(swapped)) > 8, swapped


def test_nested_mixes_blend_with_the_product_of_their_amounts(tmp_path, device):
    """mix(mix(red, gold, 0.5), blue, 0.4) = 0.3 red + 0.3 gold + 0.4 blue."""
    images = {name: _render(_scene_path(tmp_path, name), device) for name in ("red", "gold", "blue")}
    extra = _mix("inner", "red", "gold", "0.5") + _mix("outer", "inner", "blue", "0.4")
    mixed = _render(_scene_path(tmp_path, "outer", extra), device)
    z = _z_scores(mixed, [(0.3, images["red"]), (0.3, images["gold"]), (0.4, images["blue"])])
    assert np.all(np.abs(z) < 5), z


def test_a_checkerboard_amount_gives_each_square_its_material(tmp_path, device):
    """amount 0 on the checkerboard's even squares, 1 on the others (2 x 2 squares on the rectangle's uv): each
    square region of the image matches the render of its material alone."""
    extra = (
        '[materials.board]\ntype = "mix"\nmaterials = ["red", "gold"]\n'
        'amount = { texture = "checkerboard", color0 = { value = 0.0 }, color1 = { value = 1.0 } }\n'
    )
    red = _render(_scene_path(tmp_path, "red"), device)
    gold = _render(_scene_path(tmp_path, "gold"), device)
    board = _render(_scene_path(tmp_path, "board", extra), device)
    # The rectangle (scaled by 2) spans ±2, the view ±3 tan 15° ≈ ±0.80: the squares meet at the image's centre.
    # Quadrants away from the seams: 8 x 8 pixels inside each.
    quadrants = {"lower_left": (slice(14, 22), slice(2, 10)), "upper_right": (slice(2, 10), slice(14, 22))}
    quadrants |= {"upper_left": (slice(2, 10), slice(2, 10)), "lower_right": (slice(14, 22), slice(14, 22))}
    shown = {}
    for name, (rows, cols) in quadrants.items():
        pixels = [image[rows, cols].reshape(-1, 3) for image in (board, red, gold)]
        se = [np.sqrt(p.var(axis=0, ddof=1) / len(p)) for p in pixels]
        z_red = (pixels[0].mean(axis=0) - pixels[1].mean(axis=0)) / np.hypot(se[0], se[1])
        z_gold = (pixels[0].mean(axis=0) - pixels[2].mean(axis=0)) / np.hypot(se[0], se[2])
        assert np.all(np.abs(z_red) < 5) or np.all(np.abs(z_gold) < 5), (name, z_red, z_gold)
        shown[name] = "red" if np.all(np.abs(z_red) < 5) else "gold"
    # Diagonal squares alike, neighbours different.
    assert shown["lower_left"] == shown["upper_right"] != shown["upper_left"] == shown["lower_right"], shown


@pytest.mark.parametrize("integrator", ["light", "bdpt"])
def test_light_tracing_and_bdpt_agree_with_path_tracing_on_a_mix(tmp_path, device, integrator):
    """Each integrator chooses the mixed material once per vertex, where it meets the surface; they estimate the
    same image: region means within 5 standard errors of the path tracer's."""
    extra = _mix("m", "red", "gold", "0.4")
    path_traced = _render(_scene_path(tmp_path, "m", extra, "path", 32), device)
    other = _render(_scene_path(tmp_path, "m", extra, integrator, 32), device)
    z = _z_scores(other, [(1.0, path_traced)])
    assert np.all(np.abs(z) < 5), z


def test_a_mix_of_a_material_with_itself_is_that_material_and_an_amount_of_one_the_second(tmp_path, device):
    """amount 1: the second material at every point, the same image bit for bit as the second alone would give if
    the mix took no sampler dimension (it takes none); amount 0: the first."""
    gold = _render(_scene_path(tmp_path, "gold"), device)
    red = _render(_scene_path(tmp_path, "red"), device)
    ones = _render(_scene_path(tmp_path, "m", _mix("m", "red", "gold", "1.0")), device)
    zeros = _render(_scene_path(tmp_path, "m", _mix("m", "red", "gold", "0.0")), device)
    np.testing.assert_array_equal(ones, gold)
    np.testing.assert_array_equal(zeros, red)


@pytest.mark.parametrize(
    "extra, material, message",
    [
        (_mix("m", "red", "nothing", "0.5"), "m", r"materials\.m\.materials: undefined material 'nothing'"),
        (_mix("m", "red", "m", "0.5"), "m", r"materials mix themselves: m -> m"),
        (_mix("m", "red", "n", "0.5") + _mix("n", "m", "red", "0.5"), "m", "materials mix themselves: m -> n -> m"),
        (_mix("m", "red", "gold", "1.5"), "m", r"materials\.m\.amount"),
        (
            '[materials.cut]\ntype = "diffuse"\nreflectance = { value = 0.5 }\nopacity = 0.5\n'
            + _mix("m", "cut", "gold", "0.5"),
            "m",
            "a mixed material cannot have an opacity",
        ),
        (
            _mix("m", "red", "gold", "0.5") + 'bump_map = { texture = "checkerboard" }\n',
            "m",
            "a mix takes no normal or bump map of its own",
        ),
    ],
)
def test_bad_mixes_are_refused_in_one_line_naming_the_key(tmp_path, extra, material, message):
    with pytest.raises(SpectraceError, match=message) as caught:
        load_scene(_scene_path(tmp_path, material, extra))
    assert "\n" not in str(caught.value)


def test_mixes_nest_at_most_eight_deep(tmp_path):
    def chain(depth: int) -> str:
        extra = _mix("m1", "red", "gold", "0.5")
        for level in range(2, depth + 1):
            extra += _mix(f"m{level}", f"m{level - 1}", "blue", "0.5")
        return extra

    load_scene(_scene_path(tmp_path, "m8", chain(8)))
    with pytest.raises(SpectraceError, match="mixes nest at most 8 deep, this one 9"):
        load_scene(_scene_path(tmp_path, "m9", chain(9)))


def test_a_mix_renders_with_the_same_bits_however_built_or_split(tmp_path, device):
    """The choice is a hash of the intersection, not a sampler draw: the scene's own kernels, the kernels built for
    every scene, the wavefront and a render split into passes give the same bits."""
    from spectrace.engine.wavefront import make_renderer

    scene = load_scene(_scene_path(tmp_path, "m", _mix("m", "red", "gold", "0.4"), spp=8))
    reference = Renderer(scene, device, specialise=True).render().xyz
    assert reference.mean() > 0
    np.testing.assert_array_equal(Renderer(scene, device, specialise=False).render().xyz, reference)
    np.testing.assert_array_equal(make_renderer(scene, device, "wavefront").render().xyz, reference)
    split = Renderer(scene, device)
    split.render(spp=8, pass_spp=3)
    np.testing.assert_array_equal(split.image().xyz, reference)
