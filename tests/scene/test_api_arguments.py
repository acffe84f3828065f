"""The Python API checks its arguments where they come in: each wrong one raises SpectraceError with one line that
names it, before a device opens (a negative or fractional pass_spp would otherwise never finish a render, a NaN or
text spp end it at once with a black image, a fractional width or an unknown integrator fail deep in the engine,
trimesh faces past the vertices read other memory and negative ones wrap around to the last vertices)."""

import math
from dataclasses import replace

import numpy as np
import pytest
import trimesh

import spectrace
from spectrace.errors import SpectraceError


def _refuses(call, *names: str) -> str:
    """The one-line message of the SpectraceError `call` raises, which must name each of `names`."""
    with pytest.raises(SpectraceError) as raised:
        call()
    message = str(raised.value)
    assert "\n" not in message and all(name in message for name in names), message
    return message


@pytest.fixture(scope="module")
def scene() -> spectrace.Scene:
    camera = spectrace.Camera(origin=(0.0, 0.0, 5.0), target=(0.0, 0.0, 0.0), fov_degrees=40.0)
    glowing = spectrace.shape("rectangle", spectrace.diffuse(0.5), emitter=spectrace.area_emitter(1.0))
    return spectrace.Scene(camera=camera, width=8, height=6, shapes=[glowing], spp=2)


@pytest.fixture
def no_device(monkeypatch):
    """Fails the test if a render gets as far as opening a device: the arguments must be refused first."""
    import spectrace.engine.renderer as renderer

    def refuse(*args, **kwargs):
        raise AssertionError("a device was opened for arguments that should have been refused")

    monkeypatch.setattr(renderer, "open_device", refuse)


@pytest.mark.parametrize(
    ("argument", "value", "says"),
    [
        ("spp", "16", "spp must be a whole number, got '16'"),
        ("spp", math.nan, "spp must be a whole number, got nan"),
        ("spp", 16.0, "spp must be a whole number, got 16.0"),
        ("spp", True, "spp must be a whole number, got True"),
        ("spp", 0, "spp must be at least 1, got 0"),
        ("pass_spp", -1, "pass_spp must be at least 1, got -1"),
        ("pass_spp", 0, "pass_spp must be at least 1, got 0"),
        ("pass_spp", 0.5, "pass_spp must be a whole number, got 0.5"),
        ("pass_spp", math.inf, "pass_spp must be a whole number, got inf"),
        ("pass_spp", False, "pass_spp must be a whole number, got False"),
        ("aovs", 5, "aovs: expected AOV names as a comma-separated string or a sequence, got 5"),
        ("aovs", ["albedo", "bogus"], "aovs: unknown AOV 'bogus'"),
        ("aovs", [3], "aovs: unknown AOV 3"),
        ("spectral_bins", 2.5, "spectral_bins must be a whole number, got 2.5"),
        ("spectral_bins", -1, "spectral_bins must be at least 0, got -1"),
        ("tile_rows", True, "tile_rows must be a whole number, got True"),
    ],
)
def test_render_refuses_a_wrong_argument(scene, no_device, argument, value, says):
    message = _refuses(lambda: spectrace.render(scene, progress=False, **{argument: value}), argument)
    assert says in message, message


@pytest.mark.parametrize(
    ("field", "value", "says"),
    [
        ("integrator", "pathtracer", "integrator must be one of path, direct, light, bdpt, sppm, got 'pathtracer'"),
        ("integrator", None, "integrator must be one of"),
        ("sampler", "halton", "sampler must be one of independent, sobol, got 'halton'"),
        ("width", 8.5, "width must be a whole number, got 8.5"),
        ("width", 8.0, "width must be a whole number, got 8.0"),
        ("height", True, "height must be a whole number, got True"),
        ("spp", "4", "spp must be a whole number, got '4'"),
        ("seed", 1.5, "seed must be a whole number, got 1.5"),
        ("max_depth", True, "max_depth must be a whole number, got True"),
        ("rr_depth", math.nan, "rr_depth must be a whole number, got nan"),
        ("hide_emitters", 1, "hide_emitters must be True or False, got 1"),
        ("count_thin_passes", "no", "count_thin_passes must be True or False, got 'no'"),
        ("exposure", "1", "exposure must be a number of stops, got '1'"),
        ("aovs", ("albedo", "z"), "aovs: unknown AOV 'z'"),
        ("aovs", 1, "aovs must be a sequence of AOV names, got 1"),
    ],
)
def test_a_scene_refuses_a_setting_of_the_wrong_type(scene, field, value, says):
    message = _refuses(lambda: replace(scene, **{field: value}), field)
    assert says in message, message


def test_a_scene_switched_to_a_wrong_setting_is_refused_as_well(scene):
    _refuses(lambda: scene.with_overrides(integrator="bdtp"), "integrator", "bdtp")
    _refuses(lambda: scene.with_overrides(width=12.5), "width")


def test_numpy_integers_and_lists_of_aovs_are_settings_of_their_types(scene):
    changed = replace(scene, width=np.int64(12), seed=np.uint32(7), aovs=["normal", "albedo"])
    assert changed.width == 12 and changed.seed == 7
    assert changed.aovs == ("albedo", "normal")  # the AOVs' own order, as the loader gives them


@pytest.mark.parametrize(
    ("field", "value", "says"),
    [("seed", -1, "seed must lie in 0..2147483647"), ("width", 0, "width must be ≥ 1, got 0")],
)
def test_ranges_are_still_the_renderers(scene, no_device, field, value, says):
    # Types are refused at construction; a value of the right type out of range is refused before the device.
    out_of_range = replace(scene, **{field: value})
    message = _refuses(lambda: spectrace.render(out_of_range, progress=False))
    assert says in message, message


def _trimesh(vertices, faces) -> trimesh.Trimesh:
    return trimesh.Trimesh(vertices=np.asarray(vertices, float), faces=np.asarray(faces), process=False)


TRIANGLE = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]


@pytest.mark.parametrize(
    ("vertices", "faces", "says"),
    [
        (TRIANGLE, [[0, 1, 3]], "faces index vertex 3, outside the 3 vertices (indices 0..2)"),
        (TRIANGLE, [[0, 1, 2], [2, 1, 99]], "faces index vertex 99"),
        (TRIANGLE, [[0, 1, -1]], "faces index vertex -1, outside the 3 vertices"),
        ([[0.0, 0.0, 0.0], [1.0, math.nan, 0.0], [0.0, 1.0, 0.0]], [[0, 1, 2]], "NaN or infinite vertex"),
        ([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, math.inf, 0.0]], [[0, 1, 2]], "NaN or infinite vertex"),
    ],
)
def test_a_trimesh_with_faces_outside_its_vertices_is_refused(vertices, faces, says):
    mesh = _trimesh(vertices, faces)
    for call in (lambda: spectrace.mesh_from_trimesh(mesh), lambda: spectrace.shape(mesh, spectrace.diffuse(0.5))):
        message = _refuses(call, "mesh")
        assert says in message, message


def test_a_trimesh_inside_its_vertices_keeps_them():
    mesh = spectrace.mesh_from_trimesh(_trimesh(TRIANGLE + [[1.0, 1.0, 0.0]], [[0, 1, 2], [1, 3, 2]]))
    assert mesh.faces.tolist() == [[0, 1, 2], [1, 3, 2]] and len(mesh.vertices) == 4


def test_a_triangle_mesh_refuses_faces_outside_its_vertices():
    from spectrace.geometry.mesh import TriangleMesh

    with pytest.raises(ValueError, match="faces index vertex 5"):
        TriangleMesh(np.array(TRIANGLE), np.array([[0, 1, 5]]))


@pytest.mark.parametrize(
    ("call", "says"),
    [
        (lambda: spectrace.load_scene(5), "give its path (a str or a Path), got 5"),
        (lambda: spectrace.load_scene(None), "give its path (a str or a Path), got None"),
        (lambda: spectrace.load_scene("x.toml", overrides=[("film.width", 8)]), "overrides must map"),
        (lambda: spectrace.load_scene("x.toml", overrides={1: 8}), "overrides must map"),
    ],
)
def test_load_scene_refuses_what_is_no_path(call, says):
    message = _refuses(call)
    assert says in message, message


@pytest.mark.parametrize(
    ("argument", "value", "says"),
    [
        ("streams", 0, "streams must be at least 1, got 0"),
        ("streams", 2.5, "streams must be a whole number, got 2.5"),
        ("samples_per_item", "8", "samples_per_item must be a whole number, got '8'"),
        ("seed", True, "seed must be a whole number, got True"),
    ],
)
def test_measure_radiance_refuses_a_wrong_count(scene, no_device, argument, value, says):
    from spectrace.api import measure_radiance

    message = _refuses(lambda: measure_radiance(scene, (0, 0, 5), (0, 0, -1), **{argument: value}))
    assert says in message, message
