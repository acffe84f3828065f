"""Pixel filters by filter importance sampling: a rendered black/white edge matches the step convolved with each
filter, computed here by quadrature of the filters as their papers and Mitsuba 3 define them; renders stay the same
bits however split into passes; the table's sampling is exact in expectation whatever its coarseness."""

import math

import numpy as np
import pytest

import spectrace
from scene_text import camera_film
from spectrace.engine.renderer import Renderer
from spectrace.engine.wavefront import WavefrontRenderer
from spectrace.scene.model import Scene

WIDTH, HEIGHT = 24, 48
EDGE = 12.1  # film x (pixels) of the edge: left of it black, right of it radiance 1


def _mitchell(x, b=1.0 / 3.0, c=1.0 / 3.0):
    """Mitchell & Netravali (1988), eq. 8, for |x| in filter units ([0, 2])."""
    x = np.abs(x)
    near = ((12 - 9 * b - 6 * c) * x**3 + (-18 + 12 * b + 6 * c) * x**2 + (6 - 2 * b)) / 6
    far = ((-b - 6 * c) * x**3 + (6 * b + 30 * c) * x**2 + (-12 * b - 48 * c) * x + (8 * b + 24 * c)) / 6
    return np.where(x < 1, near, np.where(x < 2, far, 0.0))


# Each filter as a function of the offset in pixels, and its support radius (Mitsuba 3's definitions: box of
# radius ½, tent of radius 1, Gaussian σ = ½ windowed at 4σ with its value there subtracted, Mitchell of radius 2).
FILTERS = {
    "box": (lambda x: np.where(np.abs(x) <= 0.5, 1.0, 0.0), 0.5),
    "tent": (lambda x: np.maximum(0.0, 1.0 - np.abs(x)), 1.0),
    "gaussian": (lambda x: np.maximum(0.0, np.exp(-2.0 * x * x) - math.exp(-8.0)), 2.0),
    "mitchell": (lambda x: _mitchell(2.0 * x / 2.0), 2.0),
}


def _expected_profile(name: str) -> np.ndarray:
    """Pixel i's value: ∫ f(t) [c_i + t > EDGE] dt / ∫ f(t) dt, c_i = i + ½ (the filter is separable and the image
    constant along y, so the y factor cancels)."""
    f, radius = FILTERS[name]
    t = np.linspace(-radius, radius, 400001)
    weights = f(t)
    centres = np.arange(WIDTH) + 0.5
    inside = (centres[:, None] + t[None, :]) > EDGE
    return (weights[None, :] * inside).sum(axis=1) / weights.sum()


def _edge_scene(pixel_filter: spectrace.PixelFilter, spp: int) -> Scene:
    """An orthographic camera one unit a pixel looking at a large emitting rectangle whose edge is at film x = EDGE.
    The camera looks along +z with +y up, so its image right is world −x: film x = −world x + WIDTH / 2."""
    camera = spectrace.Camera(origin=(0.0, 0.0, 0.0), target=(0.0, 0.0, 1.0), type="orthographic", view_width=WIDTH)
    edge_x = -(EDGE - WIDTH / 2)
    half = 100.0
    light = spectrace.shape(
        "rectangle",
        spectrace.diffuse(0.0),
        emitter=spectrace.area_emitter(1.0, two_sided=True),
        transform=[{"scale": half}, {"translate": [edge_x - half, 0.0, 5.0]}],
    )
    return Scene(
        camera=camera, width=WIDTH, height=HEIGHT, shapes=[light], max_depth=1, spp=spp, pixel_filter=pixel_filter
    )


def _standard_error_with_floor(standard_error: np.ndarray, expected: np.ndarray, spp: int) -> np.ndarray:
    """The rows' standard error, but at least that of a value reached by a fraction |expected| of the samples of
    weight ~1 (sqrt(p/N)): the Gaussian's far tail may receive no sample at all, and the rows' spread then says 0."""
    return np.sqrt(standard_error**2 + np.abs(expected) / (HEIGHT * spp)) + 1e-7


@pytest.mark.parametrize("shape", [Renderer, WavefrontRenderer], ids=["megakernel", "wavefront"])
@pytest.mark.parametrize("name", list(FILTERS))
def test_an_edge_renders_as_the_step_convolved_with_the_filter(device, name, shape):
    """Every row sees the same edge, so the rows are independent replicas of the profile: each column's mean over the
    48 rows is within 5 standard errors (their spread) of the analytic convolution, with both kernel shapes (the
    wavefront carries each sample's filter weight in its path slot). Mitchell's negative lobes show as values below
    0 and above 1 beside the edge."""
    scene = _edge_scene(spectrace.PixelFilter(name), spp=64)
    renderer = shape(scene, device)
    renderer.render(spp=64)
    y = renderer.image().xyz[..., 1].astype(np.float64)
    mean = y.mean(axis=0)
    standard_error = y.std(axis=0, ddof=1) / math.sqrt(HEIGHT)
    expected = _expected_profile(name)
    tolerance = 5.0 * _standard_error_with_floor(standard_error, expected, 64)
    assert np.all(np.abs(mean - expected) <= tolerance), np.max(np.abs(mean - expected) / tolerance)
    # The comparison can tell the filters apart: each profile differs from the box's by far more than the noise.
    if name != "box":
        assert np.max(np.abs(expected - _expected_profile("box"))) > 10.0 * standard_error.max()
    if name == "mitchell":
        assert expected.min() < -0.003 and expected.max() > 1.003


@pytest.mark.parametrize("name", ["tent", "gaussian", "mitchell"])
def test_filtered_renders_are_the_same_bits_however_split(device, name):
    scene = _edge_scene(spectrace.PixelFilter(name), spp=8)
    images = []
    for pass_spp in (8, 3):
        renderer = Renderer(scene, device)
        renderer.render(spp=8, pass_spp=pass_spp)
        images.append(renderer.image().xyz)
    np.testing.assert_array_equal(images[0], images[1])


def test_a_filter_of_another_radius_and_width_is_its_own_convolution(device):
    """pbrt-v4's Gaussian default (σ = ½ windowed at 1.5) and a wide tent, through the same table and closed form."""
    for pixel_filter, f in (
        (spectrace.PixelFilter("gaussian", stddev=0.5, radius=1.5), lambda x: np.exp(-2 * x * x) - math.exp(-4.5)),
        (spectrace.PixelFilter("tent", radius=2.5), lambda x: 2.5 - np.abs(x)),
    ):
        radius = pixel_filter.support
        FILTERS["custom"] = (lambda x, f=f, r=radius: np.where(np.abs(x) <= r, f(x), 0.0), radius)
        try:
            renderer = Renderer(_edge_scene(pixel_filter, spp=64), device)
            renderer.render(spp=64)
            y = renderer.image().xyz[..., 1].astype(np.float64)
            standard_error = y.std(axis=0, ddof=1) / math.sqrt(HEIGHT)
            expected = _expected_profile("custom")
            tolerance = 5.0 * _standard_error_with_floor(standard_error, expected, 64)
            assert np.all(np.abs(y.mean(axis=0) - expected) <= tolerance)
        finally:
            del FILTERS["custom"]


SCENE_TEXT = (
    camera_film(origin="[0, 0, 5]", target="[0, 0, 0]", fov="40", width="8", height="6")
    + """{filter}
[materials.grey]
type = "diffuse"
reflectance = {{ value = 0.5 }}
[[shapes]]
type = "sphere"
material = "grey"
emitter = {{ radiance = {{ value = 1 }} }}
"""
)


def test_the_scene_file_takes_a_filter_by_name_or_table(tmp_path):
    base = SCENE_TEXT
    cases = {
        "": spectrace.PixelFilter("box"),
        'filter = "tent"': spectrace.PixelFilter("tent"),
        'filter = { type = "gaussian", stddev = 0.3 }': spectrace.PixelFilter("gaussian", stddev=0.3),
        'filter = { type = "mitchell", b = 0, c = 0.5 }': spectrace.PixelFilter("mitchell", b=0.0, c=0.5),
    }
    for text, expected in cases.items():
        path = tmp_path / "scene.toml"
        path.write_text(base.format(filter=text))
        assert spectrace.load_scene(path).pixel_filter == expected
    path.write_text(base.format(filter='filter = { type = "gaussian", sigma = 0.3 }'))
    with pytest.raises(spectrace.SpectraceError, match="film.filter"):
        spectrace.load_scene(path)


def test_the_filter_option_renders_as_the_scene_files_filter(monkeypatch, capsys, tmp_path):
    """`spectrace render --filter gaussian:stddev=0.5,radius=1.5` gives the bits of the same scene whose film.filter
    names that filter (the key whose renders the tests above check against the convolution), not the box's."""
    from cli_runner import run_in_process
    from spectrace.io.exr import read_exr

    scenes = {}
    for name, text in (("plain", ""), ("file", 'filter = { type = "gaussian", stddev = 0.5, radius = 1.5 }')):
        scenes[name] = tmp_path / f"{name}.toml"
        scenes[name].write_text(SCENE_TEXT.format(filter=text))
    images = {}
    for name, scene, option in (
        ("option", scenes["plain"], ["--filter", "gaussian:stddev=0.5,radius=1.5"]),
        ("file", scenes["file"], []),
        ("box", scenes["plain"], []),
    ):
        out = tmp_path / f"{name}.exr"
        argv = ["render", str(scene), "-o", str(out), "--spp", "4", "-q", *option]
        status, err = run_in_process(monkeypatch, capsys, argv)
        assert status in (0, None), err
        images[name] = read_exr(out)[0]["RGB"]
    np.testing.assert_array_equal(images["option"], images["file"])
    assert not np.array_equal(images["option"], images["box"])


@pytest.mark.parametrize(
    ("spec", "message"),
    [
        ("gauss", "unknown pixel filter 'gauss'"),
        ("gaussian:sigma=1", "gaussian filter has no key 'sigma' (its keys are stddev, radius)"),
        ("gaussian:stddev=x", "stddev must be a number, got 'x'"),
        ("gaussian:stddev", "give each key once as stddev=NUMBER"),
        ("tent:radius=20", "radius must lie in [0.001, 16] pixels"),
        ("mitchell:radius=1e-30", "radius must lie in [0.001, 16] pixels"),
        ("gaussian:stddev=1e-300,radius=1", "stddev must lie in [0.001, 4] pixels"),
        ("gaussian:stddev=4,radius=0.2", "radius must be at least stddev/16 (0.25 px), got 0.2"),
        ("box:radius=1", "box filter has no key 'radius'"),
    ],
)
def test_a_bad_filter_option_is_one_line_and_writes_nothing(monkeypatch, capsys, tmp_path, spec, message):
    from cli_runner import render_cornell_box, run_in_process

    out = tmp_path / "c.exr"
    status, err = run_in_process(monkeypatch, capsys, [*render_cornell_box(out, 1, 8, 8), "--filter", spec])
    assert status != 0
    assert err.strip().count("\n") == 0 and "--filter" in err and message in err, err
    assert not out.exists()
