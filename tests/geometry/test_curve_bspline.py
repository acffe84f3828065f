"""A B-spline curve is rendered as linear swept-sphere segments (geometry/curves.py bspline_polyline): every sphere
of the true swept surface (centre and radius of the uniform cubic B-spline, evaluated in float64 from its own basis
functions here) has a sphere of the segments within BSPLINE_TOLERANCE of its radius in |Δc| + |Δr|, and the other
way round, which bounds the distance between the two surfaces by that fraction of the radius."""

import numpy as np
import pytest
from scipy.spatial import cKDTree

from spectrace.geometry.curves import BSPLINE_TOLERANCE, curve_surface


def _basis(t: np.ndarray) -> np.ndarray:
    """The four uniform cubic B-spline basis functions at t (de Boor's, written out): (len(t), 4)."""
    s = 1.0 - t
    return np.stack([s**3, 3 * t**3 - 6 * t**2 + 4, -3 * t**3 + 3 * t**2 + 3 * t + 1, t**3], axis=1) / 6.0


def _true_spheres(points: np.ndarray, per_span: int = 400) -> np.ndarray:
    t = np.linspace(0.0, 1.0, per_span)
    return np.concatenate([_basis(t) @ points[i : i + 4] for i in range(len(points) - 3)])


def _segment_spheres(surface, per_segment: int = 60) -> np.ndarray:
    s = np.linspace(0.0, 1.0, per_segment)[:, None]
    centres = surface.a[:, None] + s[None] * (surface.b - surface.a)[:, None]
    radii = surface.ra[:, None] + s[None, :, 0] * (surface.rb - surface.ra)[:, None]
    return np.concatenate([centres, radii[..., None]], axis=2).reshape(-1, 4)


def _gap(spheres: np.ndarray, others: np.ndarray) -> np.ndarray:
    """For each sphere, min over the others of (|Δc| + |Δr|) / its radius, among the 64 others of nearest centre
    (the samples are dense: the radius changes little among them)."""
    _, index = cKDTree(others[:, :3]).query(spheres[:, :3], k=64)
    near = others[index]
    distance = np.linalg.norm(spheres[:, None, :3] - near[..., :3], axis=2) + np.abs(spheres[:, None, 3] - near[..., 3])
    return distance.min(axis=1) / spheres[:, 3]


def test_bspline_segments_lie_within_the_stated_fraction_of_the_radius():
    rng = np.random.default_rng(7)
    for trial in range(4):
        n = 7
        points = np.concatenate(
            [np.cumsum(rng.normal(scale=0.6, size=(n, 3)), axis=0), rng.uniform(0.03, 0.2, (n, 1))], axis=1
        )
        surface = curve_surface([points], "bspline")
        true = _true_spheres(points)
        segments = _segment_spheres(surface)
        assert _gap(true, segments).max() <= BSPLINE_TOLERANCE, trial
        # Against the true curve sampled finely enough that its spacing adds nothing that counts.
        assert _gap(segments, _true_spheres(points, 4000)).max() <= BSPLINE_TOLERANCE, trial
        # The bound is met with few pieces: a coarser cut would not meet it (the test can fail).
        coarse = curve_surface([points], "bspline", tolerance=16 * BSPLINE_TOLERANCE)
        assert coarse.count < surface.count
        assert _gap(true, _segment_spheres(coarse)).max() > BSPLINE_TOLERANCE


def test_linear_curve_points_move_and_radii_stay():
    """A transform moves the control points and leaves the radii (Mitsuba 3's to_world on its curves)."""
    matrix = np.diag([2.0, 3.0, 0.5, 1.0])
    matrix[:3, 3] = (1.0, -1.0, 0.5)
    points = np.array([[0.0, 0.0, 0.0, 0.1], [1.0, 1.0, 1.0, 0.2], [2.0, 0.0, 1.0, 0.3]])
    surface = curve_surface([points], "linear", matrix)
    placed = points[:, :3] * [2.0, 3.0, 0.5] + [1.0, -1.0, 0.5]
    assert np.allclose(surface.a, placed[:2]) and np.allclose(surface.b, placed[1:])
    assert np.allclose(surface.ra, [0.1, 0.2]) and np.allclose(surface.rb, [0.2, 0.3])


@pytest.mark.slow
@pytest.mark.subprocess
def test_bad_curves_in_a_scene_file_are_one_line_naming_the_key_and_nothing_is_written(tmp_path):
    """A curve too short for its basis, a curve file with a bad line, a ribbon without its normals (the loader's
    check) and curve_type on a sphere (the schema's): exit 2, one line naming the key (and the file's line), no
    image written."""
    from cli_runner import run_spectrace

    head = "[camera]\norigin = [0, 0, 5]\ntarget = [0, 0, 0]\nfov = 40\n[film]\nwidth = 8\nheight = 8\n"
    head += '[materials.m]\ntype = "diffuse"\nreflectance = { value = 0.5 }\n'
    (tmp_path / "hair.txt").write_text("0 0 0 0.1\n1 0 0 0.1\n\n0 1 0 0.1\n1 1 x 0.1\n")
    cases = {
        "short.toml": (
            '[[shapes]]\ntype = "curve"\nbasis = "bspline"\nmaterial = "m"\n'
            "points = [[0, 0, 0, 0.1], [1, 0, 0, 0.1], [2, 1, 0, 0.1]]\n",
            "shapes[0].points: curve 0: a bspline curve needs at least 4 points, got 3",
        ),
        "file.toml": (
            '[[shapes]]\ntype = "curve"\nfile = "hair.txt"\nmaterial = "m"\n',
            "line 5: expected 4 finite numbers",
        ),
        "bare.toml": (
            '[[shapes]]\ntype = "curve"\nmaterial = "m"\npoints = [[0, 0, 0, 0.1], [1, 0, 0, 0.1]]\n'
            'curve_type = "ribbon"\n',
            "shapes[0].curve_normals: a ribbon curve needs",
        ),
        "sphere.toml": (
            '[[shapes]]\ntype = "sphere"\nmaterial = "m"\ncurve_type = "flat"\n',
            "curve_type and curve_normals are a curve's, not a sphere's",
        ),
    }
    for name, (shape, message) in cases.items():
        (tmp_path / name).write_text(head + shape)
        image = tmp_path / f"{name}.png"
        result = run_spectrace("render", str(tmp_path / name), "-o", str(image), "-q")
        assert result.returncode == 2, result.stderr
        lines = result.stderr.strip().splitlines()
        assert len(lines) == 1 and message in lines[0] and "Traceback" not in result.stderr, result.stderr
        assert not image.exists()


def test_a_scene_of_curves_saved_as_a_scene_file_reads_back_the_same_segments(tmp_path):
    """spectrace.save_scene writes a curve as a curve file of its segments' polylines, which read back as the same
    segments (open ends and radii included)."""
    import spectrace

    rng = np.random.default_rng(2)
    points = np.concatenate([np.cumsum(rng.normal(size=(6, 3)), axis=0), rng.uniform(0.05, 0.1, (6, 1))], axis=1)
    shapes = [
        spectrace.curve(points, spectrace.diffuse(0.5), basis="bspline", name="spline"),
        spectrace.curve([points[:3], points[3:]], spectrace.diffuse(0.5), name="wires"),
    ]
    scene = spectrace.Scene(
        camera=spectrace.Camera(origin=(0, 0, 9), target=(0, 0, 0)), width=8, height=8, shapes=shapes
    )
    spectrace.save_scene(scene, tmp_path / "curves.toml")
    again = spectrace.load_scene(tmp_path / "curves.toml")
    for before, after in zip(scene.shapes, again.shapes, strict=True):
        assert before.analytic == after.analytic, before.name
