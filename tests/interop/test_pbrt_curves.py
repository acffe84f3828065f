"""pbrt-v4's `curve` shape imported as spectrace's curve (spectrace.interop.pbrt.curves): a cubic B-spline of one
width renders bit for bit as the same curve written in the scene format by hand; a Bézier curve and a quadratic
B-spline become polylines within 1 % of their radius of the float64 curve (widths varying linearly along it, in
object space, scaled with the transform); flat and ribbon curves are imported as tubes with a warning;
splitdepth is read and ignored; bad curves are one line naming the file and line."""

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


def test_a_bspline_curve_renders_as_the_same_curve_in_the_scene_format(tmp_path, device):
    pbrt = _write(tmp_path, BSPLINE_CURVE)
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
    }
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


def test_flat_curves_warn_and_splitdepth_is_ignored(tmp_path):
    body = f'Shape "curve" "point3 P" [{_points(BEZIER[:4])}] "integer splitdepth" 2\n'
    _, importer = pbrt_scene_data(_write(tmp_path, body))
    assert any('curve type "flat" imported as a tube' in w for w in importer.warnings)
    assert not any("splitdepth" in w for w in importer.warnings)


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
