"""pbrt-v4's `curve` shape imported as spectrace's curve (spectrace.interop.pbrt.curves): a cubic B-spline of one
width renders bit for bit as the same curve written in the scene format by hand; a Bézier curve and a quadratic
B-spline become polylines within 1 % of their radius of the float64 curve (widths varying linearly along it, in
object space, scaled with the transform); `flat` (pbrt's default) and `ribbon` curves become spectrace's strips of
those types, a ribbon's `N` slerped along each segment as pbrt does and turned into spectrace's world, `cylinder`
a tube; splitdepth is read and ignored; bad curves are one line naming the file and line."""

import tomllib
from pathlib import Path

import numpy as np
import pytest

from spectrace.engine.renderer import Renderer
from spectrace.errors import SpectraceError
from spectrace.geometry.curves import BSPLINE_TOLERANCE
from spectrace.interop.pbrt import import_pbrt, pbrt_scene_data
from spectrace.interop.toml_writer import dumps
from spectrace.scene import load_scene

HEADER = """LookAt 0 -1 6  0 0 0  0 1 0
Camera "perspective" "float fov" 40
Film "rgb" "integer xresolution" 24 "integer yresolution" 16
WorldBegin
LightSource "distant" "point3 from" [1 3 4] "point3 to" [0 0 0] "blackbody L" [5500] "float scale" 3
LightSource "infinite" "rgb L" [0.3 0.3 0.3]
Material "diffuse" "rgb reflectance" [0.7 0.5 0.3]
"""
BSPLINE = [[-2, -1, 0], [-1, 0.5, 0.3], [0, -0.8, -0.2], [1, 0.6, 0.1], [2, -0.5, 0]]
BSPLINE_CURVE = (
    "AttributeBegin\nTranslate 0 0.4 0\nScale 0.8 0.8 0.8\n"
    'Shape "curve" "string type" "cylinder" "string basis" "bspline" "float width" 0.25 "integer splitdepth" 5 '
    f'"point3 P" [{" ".join(str(v) for p in BSPLINE for v in p)}]\nAttributeEnd\n'
)
BEZIER = [[-2, -1.5, 0], [-1, -0.5, 0.5], [0, -2.0, 0], [1, -1.2, 0.2], [1.5, -0.8, 0], [2, -1.8, 0.3], [2.5, -1, 0]]


def _write(folder: Path, body: str) -> Path:
    path = folder / "curves.pbrt"
    path.write_text(HEADER + body)
    return path


def _points(text: list[list[float]]) -> str:
    return " ".join(str(v) for p in text for v in p)


@pytest.mark.parametrize("kind", ["cylinder", "flat"])
def test_a_bspline_curve_renders_as_the_same_curve_in_the_scene_format(tmp_path, device, kind):
    pbrt = _write(tmp_path, BSPLINE_CURVE.replace('"cylinder"', f'"{kind}"'))
    imported = tmp_path / "imported.toml"
    import_pbrt(pbrt, imported)
    data = tomllib.loads(imported.read_text())
    (index,) = [i for i, shape in enumerate(data["shapes"]) if shape["type"] == "curve"]
    # By hand: the control points placed by the curve's transform and pbrt's handedness mirror (spectrace's world
    # is pbrt's with x reversed, spectrace.interop.pbrt.cameras), at radius width / 2 scaled by the transform's 0.8
    # (pbrt's widths are in object space; spectrace's transform leaves radii as written).
    by_hand = {
        "type": "curve",
        "basis": "bspline",
        "points": [[*p, 0.25 / 2 * 0.8] for p in BSPLINE],
        "transform": [{"scale": 0.8}, {"translate": [0, 0.4, 0]}, {"scale": [-1, 1, 1]}],
        "material": data["shapes"][index]["material"],
        "name": "by hand",
    } | ({"curve_type": "flat"} if kind == "flat" else {})
    data["shapes"][index] = by_hand
    written = tmp_path / "by_hand.toml"
    written.write_text(dumps(data))
    ours, theirs = load_scene(imported), load_scene(written)
    a, b = ours.shapes[index].analytic, theirs.shapes[index].analytic
    assert a.count == b.count > 4
    assert np.array_equal(a.a, b.a) and np.array_equal(a.ra, b.ra)
    first = Renderer(ours.with_overrides(spp=4), device).render().xyz
    second = Renderer(theirs.with_overrides(spp=4), device).render().xyz
    assert first[..., 1].max() > 0.05
    assert np.array_equal(first.view(np.uint32), second.view(np.uint32))  # bit for bit


def _bezier(points: np.ndarray, t: np.ndarray) -> np.ndarray:
    """A cubic Bézier span by de Casteljau's construction, in float64."""
    p = np.broadcast_to(points, (len(t), *points.shape)).copy()
    for level in range(3, 0, -1):
        p = (1 - t)[:, None, None] * p[:, :level] + t[:, None, None] * p[:, 1 : level + 1]
    return p[:, 0]


def test_a_bezier_curve_is_a_polyline_within_the_stated_fraction_of_its_radius(tmp_path):
    body = (
        'Scale 2 2 2\nShape "curve" "string type" "cylinder" "float width0" 0.1 "float width1" 0.3 '
        f'"point3 P" [{_points(BEZIER)}]\n'
    )
    data, importer = pbrt_scene_data(_write(tmp_path, body))
    (curve,) = [shape for shape in data["shapes"] if shape["type"] == "curve"]
    assert curve["basis"] == "linear" and curve["open_ends"] is True
    polyline = np.array(curve["points"])
    control = np.array(BEZIER, float) * 2 * [-1, 1, 1]  # the Scale, then the handedness mirror
    t = np.linspace(0, 1, 600)
    # Two spans, u from 0 to ½ and ½ to 1; the width (a diameter) runs from 0.1 to 0.3 over u and doubles with
    # the scale.
    centres = np.concatenate([_bezier(control[0:4], t), _bezier(control[3:7], t)])
    u = np.concatenate([t / 2, 0.5 + t / 2])
    radii = (0.1 + 0.2 * u) * 2 / 2
    # Every sphere of the true curve has one of the polyline's within 1 % of its radius (|Δc| + |Δr|), the one
    # at its centre's projection on the nearest segments (a candidate, so the least gap is no larger).
    a, b = polyline[:-1], polyline[1:]
    axis = b[:, :3] - a[:, :3]
    along = np.einsum("psk,sk->ps", centres[:, None] - a[None, :, :3], axis) / np.einsum("sk,sk->s", axis, axis)
    s = np.clip(along, 0.0, 1.0)[..., None]
    nearest = a[None] + s * (b - a)[None]
    gap = np.linalg.norm(centres[:, None] - nearest[..., :3], axis=2) + np.abs(radii[:, None] - nearest[..., 3])
    assert (gap.min(axis=1) / radii).max() <= BSPLINE_TOLERANCE
    assert np.allclose(polyline[0, :3], control[0]) and np.allclose(polyline[-1, :3], control[-1])


def test_flat_is_the_default_type_and_splitdepth_is_ignored(tmp_path):
    body = (
        f'Shape "curve" "point3 P" [{_points(BEZIER[:4])}] "integer splitdepth" 2\n'
        f'Shape "curve" "string type" "flat" "string basis" "bspline" "point3 P" [{_points(BSPLINE)}]\n'
        f'Shape "curve" "string type" "cylinder" "point3 P" [{_points(BEZIER[:4])}]\n'
    )
    data, importer = pbrt_scene_data(_write(tmp_path, body))
    curves = [shape for shape in data["shapes"] if shape["type"] == "curve"]
    assert [curve.get("curve_type", "tube") for curve in curves] == ["flat", "flat", "tube"]
    assert curves[1]["basis"] == "bspline"
    assert importer.warnings == []
    scene = _imported(tmp_path, body)
    assert [shape.analytic.curve_type for shape in scene.shapes if shape.analytic is not None] == [
        "flat",
        "flat",
        "tube",
    ]


def _imported(folder: Path, body: str):
    """The scene the importer writes for `body`, loaded."""
    imported = folder / "imported.toml"
    import_pbrt(_write(folder, body), imported)
    return load_scene(imported)


def _slerp(n0: np.ndarray, n1: np.ndarray, t: np.ndarray) -> np.ndarray:
    angle = np.arccos(np.clip(n0 @ n1, -1.0, 1.0))
    return (np.sin((1 - t)[:, None] * angle) * n0 + np.sin(t[:, None] * angle) * n1) / np.sin(angle)


def test_a_ribbon_takes_its_normals_slerped_along_each_segment(tmp_path):
    """Two straight Bézier segments along x whose control points are evenly spaced (so the curve parameter of a
    point is its x over the segment's length) and widths that vary (so the polyline has points inside them), N
    turning by 90° then 60° about x, under a rotation of 90° about z: every segment end the scene holds has the
    normal pbrt's slerp gives at its parameter, rotated (and mirrored in x, spectrace's world being pbrt's with x
    reversed), within 1e-6."""
    control = [[float(i), 0.0, 0.0] for i in range(7)]
    normals = [[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [0.0, np.cos(np.radians(150.0)), np.sin(np.radians(150.0))]]
    body = (
        'AttributeBegin\nRotate 90 0 0 1\nShape "curve" "string type" "ribbon" "float width0" 0.1 "float width1" 0.4 '
        f'"point3 P" [{_points(control)}] "normal N" [{_points(normals)}]\nAttributeEnd\n'
    )
    data, importer = pbrt_scene_data(_write(tmp_path, body))
    (curve,) = [shape for shape in data["shapes"] if shape["type"] == "curve"]
    assert curve["curve_type"] == "ribbon" and importer.warnings == []
    (surface,) = [s.analytic for s in _imported(tmp_path, body).shapes if s.analytic is not None]
    assert surface.curve_type == "ribbon" and surface.count >= 15  # 150° of turn in pieces of at most 10°
    # pbrt's object x runs along the world's y after the rotation; the mirror leaves y alone, flips x.
    to_world = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]) * [[-1.0], [1.0], [1.0]]
    ends = np.concatenate([surface.a, surface.b[-1:]])
    x_object = ends @ np.linalg.inv(to_world).T
    parameter = x_object[:, 0] / 3.0
    units = np.array(normals)
    segment = np.minimum(parameter.astype(int), 1)
    want = np.array([_slerp(units[k], units[k + 1], np.array([p - k]))[0] for k, p in zip(segment, parameter)])
    want = want @ to_world.T  # a rotation and a mirror: the inverse transpose is the matrix itself
    got = np.concatenate([surface.ribbon_normals[:, 0], surface.ribbon_normals[-1:, 1]])
    assert np.allclose(got, want, atol=1e-6), np.abs(got - want).max()


@pytest.mark.parametrize(
    "normals, message",
    [
        (None, r'a ribbon curve needs "normal N"'),
        ([[0, 0, 1]], r"needs 2 normals"),
        ([[0, 0, 1], [0, 0, 0]], r"finite and non-zero"),
    ],
)
def test_a_ribbon_without_its_normals_is_one_line(tmp_path, normals, message):
    given = f' "normal N" [{_points(normals)}]' if normals else ""
    body = f'Shape "curve" "string type" "ribbon" "point3 P" [{_points(BEZIER[:4])}]{given}\n'
    with pytest.raises(SpectraceError, match=message) as caught:
        pbrt_scene_data(_write(tmp_path, body))
    assert "\n" not in str(caught.value)


@pytest.mark.parametrize(
    "body, message",
    [
        ('Shape "curve" "point3 P" [0 0 0 1 0 0 2 0 0]\n', r"curves\.pbrt:8: a Bézier curve of degree 3 needs"),
        ('Shape "curve" "string basis" "hermite" "point3 P" [0 0 0 1 0 0 2 0 0 3 0 0]\n', r'basis "hermite"'),
        ('Shape "curve" "float width" -1 "point3 P" [0 0 0 1 0 0 2 0 0 3 0 0]\n', r"widths must be > 0"),
    ],
)
def test_bad_curves_are_one_line_naming_the_line(tmp_path, body, message):
    with pytest.raises(SpectraceError, match=message) as caught:
        pbrt_scene_data(_write(tmp_path, body))
    assert "\n" not in str(caught.value)
