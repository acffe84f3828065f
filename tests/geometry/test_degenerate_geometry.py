"""Degenerate geometry renders without crashes, NaN or dropped samples: zero-area, duplicate and non-manifold
triangles, and scenes far from the origin or scaled by a million. Where physics fixes the answer, it is checked:
geometry that has no area or repeats a surface changes nothing, and radiance does not depend on the scene's scale.
Non-finite coordinates are refused with a message naming the file or shape."""

import dataclasses

import numpy as np
import pytest

from spectrace.engine.renderer import Renderer
from spectrace.errors import SpectraceError
from spectrace.geometry.mesh import TriangleMesh
from spectrace.geometry.transforms import apply_transform
from spectrace.resources import scenes_dir
from spectrace.scene import load_scene
from spectrace.scene.model import AreaEmitter, Shape


@pytest.fixture(scope="module")
def cornell():
    return load_scene(scenes_dir() / "cornell_box.toml").with_overrides(width=20, height=20, spp=16, seed=1)


@pytest.fixture(scope="module")
def reference(cornell, device):
    return Renderer(cornell, device).render()


def _render(scene, device):
    image = Renderer(scene, device).render()
    assert np.isfinite(image.xyz).all()
    assert image.dropped_samples == 0
    return image


def _with_shapes(scene, *extra):
    return dataclasses.replace(scene, shapes=[*scene.shapes, *extra])


def _transformed(scene, scale: float, offset: float):
    """Every shape and the camera scaled by `scale` about the origin, then moved by `offset` along (1, 1, 1)."""
    matrix = np.eye(4)
    matrix[:3, :3] *= scale
    matrix[:3, 3] = offset
    shapes = [dataclasses.replace(s, mesh=apply_transform(s.mesh, matrix)) for s in scene.shapes]
    camera = dataclasses.replace(
        scene.camera,
        origin=tuple(np.multiply(scene.camera.origin, scale) + offset),
        target=tuple(np.multiply(scene.camera.target, scale) + offset),
    )
    return dataclasses.replace(scene, shapes=shapes, camera=camera)


INSIDE_BOX = np.array([[0.10, 0.10, 0.10], [0.20, 0.20, 0.20], [0.30, 0.30, 0.30], [0.25, 0.30, 0.20]])


def test_zero_area_triangles_change_nothing(cornell, reference, device):
    collinear_and_pinched = TriangleMesh(INSIDE_BOX, np.array([[0, 1, 2], [0, 0, 3], [3, 1, 3]]))
    white = cornell.shapes[0].material
    emitter = AreaEmitter(cornell.shapes[3].emitter.radiance)
    scene = _with_shapes(
        cornell,
        Shape(collinear_and_pinched, white, name="zero area"),
        Shape(collinear_and_pinched, white, emitter=emitter, name="zero-area light"),
    )
    assert np.array_equal(_render(scene, device).xyz, reference.xyz)


def test_a_triangle_collapsed_to_a_point_changes_nothing(cornell, reference, device):
    point = TriangleMesh(INSIDE_BOX, np.array([[3, 3, 3]]))
    scene = _with_shapes(cornell, Shape(point, cornell.shapes[0].material, name="point"))
    assert np.array_equal(_render(scene, device).xyz, reference.xyz)


def test_duplicate_triangles_are_the_same_surface(cornell, reference, device):
    """A surface listed twice is still one surface: the same image, bit for bit."""
    scene = _with_shapes(cornell, cornell.shapes[0], cornell.shapes[1], cornell.shapes[2])
    assert np.array_equal(_render(scene, device).xyz, reference.xyz)


def test_duplicate_light_renders_finite(cornell, device):
    """Two coincident emitters are not a physical surface (light sampling counts both, a ray that hits them
    only one: see docs/robustness.md); the render must still be finite and lit."""
    image = _render(_with_shapes(cornell, cornell.shapes[3]), device)
    assert image.xyz[..., 1].mean() > 0


def test_non_manifold_meshes_render(cornell, device):
    """Three fins sharing one edge (an edge with three faces), a T-junction, and an isolated back-facing fin."""
    edge_low, edge_high = np.array([0.278, 0.10, 0.28]), np.array([0.278, 0.30, 0.28])
    vertices, faces = [edge_low, edge_high], []
    for k, angle in enumerate((0.0, 2.1, 4.2)):
        out = 0.1 * np.array([np.cos(angle), 0.0, np.sin(angle)])
        vertices += [edge_high + out, edge_low + out]
        faces += [[0, 1, 2 + 2 * k], [0, 2 + 2 * k, 3 + 2 * k]]
    middle = len(vertices)
    vertices += [0.5 * (edge_low + edge_high), edge_low + [0.0, 0.0, 0.12]]  # a vertex on the shared edge
    faces += [[middle, 0, middle + 1]]
    fins = TriangleMesh(np.array(vertices), np.array(faces))
    image = _render(_with_shapes(cornell, Shape(fins, cornell.shapes[0].material, name="fins")), device)
    assert image.xyz[..., 1].mean() > 0


def _mean_luminance_over_seeds(scene, device, seeds=range(8)) -> tuple[float, float]:
    """Mean Y of the image and its standard error, from independent renders with different seeds."""
    means = [_render(scene.with_overrides(seed=seed), device).xyz[..., 1].mean() for seed in seeds]
    return float(np.mean(means)), float(np.std(means, ddof=1) / np.sqrt(len(means)))


@pytest.mark.parametrize("scale, offset", [(1e6, 0.0), (1e6, 1e9), (1e11, 0.0)])
def test_a_scaled_scene_has_the_same_radiance(cornell, device, scale, offset):
    """Radiance does not depend on the unit of length: the Cornell box in micrometres (1e6) or far larger, even
    a billion units from the origin, renders the same mean luminance within Monte Carlo error."""
    mean, error = _mean_luminance_over_seeds(_transformed(cornell, scale, offset), device)
    mean_reference, error_reference = _mean_luminance_over_seeds(cornell, device)
    assert abs(mean - mean_reference) <= 4.0 * np.hypot(error, error_reference)


def test_metre_scale_geometry_a_million_metres_away_renders_finite(cornell, device):
    """At 1e6 m float32 resolves 6 cm, so the half-metre box is mangled; it must still render without NaN."""
    image = _render(_transformed(cornell, 1.0, 1e6), device)
    assert image.xyz[..., 1].max() > 0


def test_nan_vertices_in_a_mesh_file_name_the_file(tmp_path):
    (tmp_path / "broken.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 nan 0\nf 1 2 3\n")
    scene = tmp_path / "scene.toml"
    scene.write_text(
        "[camera]\norigin = [0, 0, 5]\ntarget = [0, 0, 0]\nfov = 40\n[film]\nwidth = 4\nheight = 4\n"
        '[materials.m]\ntype = "diffuse"\nreflectance = { value = 0.5 }\n'
        '[[shapes]]\ntype = "mesh"\nfile = "broken.obj"\nmaterial = "m"\n'
    )
    with pytest.raises(SpectraceError) as caught:
        load_scene(scene)
    message = str(caught.value)
    assert message.startswith(f"{scene}: shapes[0].file: mesh file '{tmp_path / 'broken.obj'}' has 1 vertices")
    assert "NaN or infinite" in message


@pytest.mark.parametrize("bad", [np.nan, np.inf, 1e13])
def test_a_python_built_shape_with_bad_coordinates_is_refused(cornell, device, bad):
    vertices = INSIDE_BOX.copy()
    vertices[1, 2] = bad
    mesh = TriangleMesh(vertices, np.array([[0, 1, 3]]))
    scene = _with_shapes(cornell, Shape(mesh, cornell.shapes[0].material, name="broken"))
    with pytest.raises(SpectraceError, match=r"shape 4 \('broken'\) has .*(NaN or infinite|beyond)"):
        Renderer(scene, device)
