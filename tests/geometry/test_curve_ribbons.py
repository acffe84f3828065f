"""pbrt-v4's flat and ribbon curves (kernels/curve_ribbon.cl) against closed forms (no other renderer has them:
Mitsuba 3 has neither). A strip has no thickness and one normal across its width, so a diffuse strip under a distant
light shows ρ/π E |n·l| uniformly across it, where a tube's radiance falls off toward its silhouette; a flat strip's
normal faces the ray, a ribbon's is its own; the area a strip covers is its width times its length times the cosine
of its normal to the view, nothing where it is seen edge-on. Orthographic views, so every ray has one direction."""

import numpy as np
import pytest

import spectrace
from spectrace.errors import SpectraceError

VIEW_WIDTH = 1.5


def _render(shape, lights, width, height, spp, max_depth=2):
    scene = spectrace.Scene(
        camera=spectrace.Camera(
            origin=(0.0, 0.0, 5.0), target=(0.0, 0.0, 0.0), type="orthographic", view_width=VIEW_WIDTH
        ),
        width=width,
        height=height,
        spp=spp,
        shapes=[shape],
        lights=lights,
        max_depth=max_depth,
    )
    return np.asarray(spectrace.render(scene, progress=False).xyz)[..., 1]


def _rows_expected(height: int, width: int, half_extent: float, value: float) -> np.ndarray:
    """Each image row's mean of `value` over the part of its height within ±half_extent of the centre line."""
    pixel = VIEW_WIDTH / width
    rows_y = 0.5 * height * pixel - (np.arange(height) + 0.5) * pixel
    y = rows_y[:, None] + pixel * ((np.arange(4000) + 0.5) / 4000 - 0.5)[None]
    return value * np.mean(np.abs(y) <= half_extent, axis=1)


def _turned(beta: float) -> list[float]:
    """A unit normal across the x axis, turned from +z (toward the camera) by beta about x."""
    return [0.0, -float(np.sin(beta)), float(np.cos(beta))]


@pytest.mark.parametrize(
    "curve_type, beta_degrees", [("flat", 0.0), ("ribbon", 0.0), ("ribbon", -50.0), ("ribbon", 20.0)]
)
def test_a_diffuse_strip_under_a_distant_light_is_uniform_across_its_width(curve_type, beta_degrees):
    """A straight strip along x, longer than the frame, radius r (half-width), seen face on (flat: always; ribbon:
    its normal n turned by β from the view), lit by a distant light of irradiance E from behind the camera, tilted
    by 35° about x: every point it shows has radiance ρ/π E |n·l|, so each image row's mean is that times the
    fraction of the row's height the strip covers, r cos β either side of its axis: within 5 standard errors of
    the row's columns. The same curve as a tube differs by far more (its radiance falls off toward its edges)."""
    radius, rho, irradiance = 0.4, 0.5, 3.0
    beta = np.radians(beta_degrees)
    light_from = np.array([0.0, np.sin(np.radians(35.0)), np.cos(np.radians(35.0))])
    points = [[-10.0, 0.0, 0.0, radius], [10.0, 0.0, 0.0, radius]]
    normals = [_turned(beta)] * 2 if curve_type == "ribbon" else None
    width, height = 16, 32
    lights = [spectrace.distant_light(tuple(-light_from), irradiance)]
    strip = spectrace.curve(points, spectrace.diffuse(rho), curve_type=curve_type, curve_normals=normals)
    y_image = _render(strip, lights, width, height, 32)
    normal = np.array(_turned(beta))
    expected = _rows_expected(height, width, radius * np.cos(beta), rho / np.pi * irradiance * abs(normal @ light_from))
    mean = y_image.mean(axis=1)
    standard_error = y_image.std(axis=1, ddof=1) / np.sqrt(width)
    assert expected.max() > 0.2 and np.count_nonzero(expected == 0.0) >= 8
    tolerance = 5.0 * standard_error + 1e-4 * expected.max()
    assert np.all(np.abs(mean - expected) <= tolerance), (mean, expected, standard_error)
    if curve_type == "flat":
        tube = _render(spectrace.curve(points, spectrace.diffuse(rho)), lights, width, height, 32).mean(axis=1)
        assert np.max(np.abs(tube - expected) - tolerance) > 0.02


@pytest.mark.parametrize(
    "curve_type, beta_degrees", [("flat", 0.0), ("ribbon", 0.0), ("ribbon", 60.0), ("ribbon", -30.0)]
)
def test_a_strip_covers_its_width_times_its_length(curve_type, beta_degrees):
    """A black strip of half-width r and length L inside the frame, in front of a sky of radiance 1: the image's
    mean of 1 − Y is the fraction of the frame it covers, 2 r cos β L over the frame's area, within 4 standard
    errors of a Bernoulli mean over all the samples."""
    radius, length = 0.1, 1.0
    beta = np.radians(beta_degrees)
    normals = [_turned(beta)] * 3 if curve_type == "ribbon" else None
    points = [[-0.5 * length, 0.0, 0.0, radius], [0.0, 0.0, 0.0, radius], [0.5 * length, 0.0, 0.0, radius]]
    strip = spectrace.curve(points, spectrace.diffuse(0.0), curve_type=curve_type, curve_normals=normals)
    width = height = 24
    spp = 16
    y_image = _render(strip, [spectrace.constant_environment(1.0)], width, height, spp, max_depth=1)
    covered = 1.0 - y_image.mean()
    expected = 2.0 * radius * np.cos(beta) * length / VIEW_WIDTH**2
    samples = width * height * spp
    assert abs(covered - expected) <= 4.0 * np.sqrt(expected * (1.0 - expected) / samples), (covered, expected)


def test_a_twisting_ribbon_covers_the_integral_of_its_projected_width():
    """A ribbon along x whose normal turns from facing the view (+z) to edge-on (+y) between its two points: pbrt's
    slerp turns it uniformly, so its projected width at s is 2 r cos(πs/2) and it covers 2 r L · 2/π. The host cuts
    it into pieces of at most 10° (bilinear patches, whose across vector is the chord of the turn: the trapezoid
    rule on cos, 0.25 % short here, far inside the tolerance), within 4 standard errors of a Bernoulli mean."""
    radius, length = 0.15, 1.0
    points = [[-0.5 * length, 0.0, 0.0, radius], [0.5 * length, 0.0, 0.0, radius]]
    ribbon = spectrace.curve(
        points, spectrace.diffuse(0.0), curve_type="ribbon", curve_normals=[[0.0, 0.0, 1.0], [0.0, 1.0, 0.0]]
    )
    assert ribbon.analytic.count == 9
    width = height = 24
    spp = 16
    y_image = _render(ribbon, [spectrace.constant_environment(1.0)], width, height, spp, max_depth=1)
    covered = 1.0 - y_image.mean()
    expected = 2.0 * radius * length * 2.0 / np.pi / VIEW_WIDTH**2
    samples = width * height * spp
    assert abs(covered - expected) <= 4.0 * np.sqrt(expected * (1.0 - expected) / samples), (covered, expected)


def test_a_ribbon_seen_edge_on_covers_nothing():
    """The same black ribbon with its normal at right angles to the view: no sample meets it, so the image is bit
    for bit the sky's (the same ribbon moved out of the frame); turned a little from edge-on it does cover pixels."""
    sky = [spectrace.constant_environment(1.0)]

    def render(beta, x=0.0):
        points = [[x - 0.5, 0.0, 0.0, 0.1], [x + 0.5, 0.0, 0.0, 0.1]]
        normals = [_turned(np.radians(beta))] * 2
        ribbon = spectrace.curve(points, spectrace.diffuse(0.0), curve_type="ribbon", curve_normals=normals)
        return _render(ribbon, sky, 24, 24, 4, max_depth=1)

    empty = render(0.0, x=100.0)
    for beta, hidden in ((90.0, True), (-90.0, True), (80.0, False)):
        y_image = render(beta)
        assert np.array_equal(y_image, empty) == hidden, (beta, np.count_nonzero(y_image != empty))


@pytest.mark.parametrize(
    "kwargs, where",
    [
        ({"curve_type": "ribbon"}, "curve_normals"),
        ({"curve_type": "ribbon", "curve_normals": [[0, 0, 1]]}, "curve_normals"),
        ({"curve_type": "ribbon", "curve_normals": [[1, 0, 0], [0, 0, 1]]}, "curve_normals"),
        ({"curve_type": "flat", "curve_normals": [[0, 0, 1], [0, 0, 1]]}, "curve_normals"),
        ({"curve_type": "flat", "uv_convention": "mitsuba"}, "uv_convention"),
        ({"curve_type": "ribbon", "curve_normals": [[0, 0, 1]] * 4, "basis": "bspline"}, "basis"),
        ({"curve_type": "band"}, "curve_type"),
    ],
)
def test_bad_strip_keys_name_the_key(kwargs, where):
    points = [[-0.5, 0.0, 0.0, 0.1], [0.5, 0.0, 0.0, 0.1]]
    if kwargs.get("basis") == "bspline":
        points = [[x, 0.0, 0.0, 0.1] for x in (-0.5, -0.2, 0.2, 0.5)]
    with pytest.raises(SpectraceError) as caught:
        spectrace.curve(points, spectrace.diffuse(0.5), **kwargs)
    assert caught.value.where == where and "\n" not in str(caught.value)


def test_strip_curves_saved_as_a_scene_file_read_back_the_same_segments(tmp_path):
    """spectrace.save_scene keeps a curve's type: a flat curve reads back as the same flat segments, a ribbon
    (written inline, with a normal per point) as the same segments and normals."""
    points = [[-1.0, 0.0, 0.0, 0.1], [0.0, 0.3, 0.5, 0.1], [1.0, 0.0, 0.2, 0.05]]
    normals = [[0.0, 0.0, 1.0], [0.0, 0.7, 0.7], [0.0, 1.0, 0.0]]
    shapes = [
        spectrace.curve(points, spectrace.diffuse(0.5), curve_type="flat", name="flat"),
        spectrace.curve(points, spectrace.diffuse(0.5), curve_type="ribbon", curve_normals=normals, name="ribbon"),
    ]
    camera = spectrace.Camera(origin=(0, 0, 9), target=(0, 0, 0))
    scene = spectrace.Scene(camera=camera, width=8, height=8, shapes=shapes)
    spectrace.save_scene(scene, tmp_path / "strips.toml")
    again = spectrace.load_scene(tmp_path / "strips.toml")
    for before, after in zip(scene.shapes, again.shapes, strict=True):
        a, b = before.analytic, after.analytic
        assert a.curve_type == b.curve_type == before.name and a.count == b.count >= 2
        assert np.array_equal(a.a, b.a) and np.array_equal(a.b, b.b) and np.array_equal(a.ra, b.ra)
        if a.ribbon_normals is not None:
            assert np.allclose(a.ribbon_normals, b.ribbon_normals, atol=1e-12)


def test_a_strip_gives_the_tube_s_offset_across_the_fibre(kernel_runner):
    """The v a path vertex gets (v = (1 + h)/2, the hair BSDF's h) at offset y across a fibre along x, for rays at
    right angles to it from either side: the tube's h is y / r seen from +z and −y / r from −z (the offset along
    ωo × the fibre's direction); a flat strip and a ribbon (normal +z, so seen from its back from −z) give the same,
    and u the same position along the fibre. A flat strip's hit lies on its plane through the axis, facing the ray
    (t = 5 from either side); a ribbon's on its plane z = 0."""
    from tests.geometry.test_curve_shapes import _scene, _scene_hits

    radius = 0.5
    points = [[-1.0, 0.0, 0.0, radius], [1.0, 0.0, 0.0, radius]]
    y = np.linspace(-0.45, 0.45, 7)
    x = np.linspace(-0.8, 0.8, 7)
    for side in (1.0, -1.0):
        origins = np.stack([x, y, np.full(7, 5.0 * side)], axis=1)
        directions = np.tile([0.0, 0.0, -side], (7, 1))
        found = {}
        for curve_type in ("tube", "flat", "ribbon"):
            normals = [[0.0, 0.0, 1.0]] * 2 if curve_type == "ribbon" else None
            curve = spectrace.curve(points, spectrace.diffuse(0.5), curve_type=curve_type, curve_normals=normals)
            hits = _scene_hits(kernel_runner, _scene([curve]), origins, directions, np.full(7, 100.0))[0]
            found[curve_type] = hits
        want_v = 0.5 * (1.0 + side * y / radius)
        for curve_type, hits in found.items():
            assert np.allclose(hits[:, 2], want_v, atol=2e-3), (side, curve_type, hits[:, 2], want_v)
            assert np.allclose(hits[:, 1], (x + 1.0) / 2.0, atol=1e-5), (curve_type, hits[:, 1])
        assert np.allclose(found["flat"][:, 0], 5.0, atol=1e-5) and np.allclose(found["ribbon"][:, 0], 5.0, atol=1e-5)
        assert np.allclose(found["tube"][:, 0], 5.0 - np.sqrt(radius**2 - y**2), atol=1e-4)
