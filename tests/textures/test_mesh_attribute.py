"""Mesh attributes as textures (Mitsuba 3's `mesh_attribute`): a quad of triangles seen head-on under a uniform
environment of radiance 1 reflects L(λ) = R(λ) at each point (one bounce), so a region's XYZ is colour-science's of
the reflectance the attribute gives there; a vertex attribute's value at a pixel is the barycentric blend numpy
computes at the pixel centre's point; a PLY file's properties are named as Mitsuba 3 names them, and a scene
written here renders as Mitsuba renders it."""

import subprocess
import sys

import numpy as np
import pytest
from tests.textures.test_textured_render import GRID, _sigmoid_spectrum, _xyz_colour_science

import spectrace
from spectrace.engine.renderer import Renderer
from spectrace.errors import SpectraceError
from spectrace.geometry.mesh import TriangleMesh, load_mesh
from spectrace.scene.model import Camera, Scene
from stats_toolkit import assert_within_standard_errors, mean_and_standard_error

SIDE = 16
TAN_HALF = np.tan(np.radians(15.0))  # the 30° camera on the axis at z = 3 sees exactly the quad [-1, 1]²
# The quad [-1, 1]² at z = 0 facing +z in two halves (x < 0, x > 0) sharing the column x = 0: six vertices, four
# triangles (two per half), wound counter-clockwise seen from +z.
GRID_VERTICES = np.array([[x, y, 0.0] for y in (-1.0, 1.0) for x in (-1.0, 0.0, 1.0)])
HALF_FACES = np.array([[0, 1, 4], [0, 4, 3], [1, 2, 5], [1, 5, 4]])


def _scene(shape, spp: int = 64) -> Scene:
    camera = Camera(origin=(0.0, 0.0, 3.0), target=(0.0, 0.0, 0.0), fov_degrees=30.0)
    return Scene(
        camera=camera,
        width=SIDE,
        height=SIDE,
        shapes=[shape],
        lights=[spectrace.constant_environment(1.0)],
        max_depth=2,
        spp=spp,
        seed=5,
        sampler="independent",
    )


def _halves(xyz: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The pixels well inside the left and right halves of the film (2 pixels from every edge)."""
    half = SIDE // 2
    return xyz[2:-2, 2 : half - 2].reshape(-1, 3), xyz[2:-2, half + 2 : -2].reshape(-1, 3)


def _assert_region(region: np.ndarray, spectrum: np.ndarray, what: str) -> None:
    mean, error = mean_and_standard_error(region - _xyz_colour_science(spectrum))
    assert_within_standard_errors(mean, 0.0, error, slack=2e-4, what=what)


def test_two_vertex_colours_render_each_half_as_its_plain_colour(device):
    """Two separate halves, every vertex of one coloured A and of the other B (vertex_color): blending equal corners
    gives the corner's colour, so each half has the XYZ of its colour's uplifted spectrum (colour-science)."""
    colours = np.array([[0.8, 0.2, 0.1], [0.1, 0.4, 0.7]])
    left, right = GRID_VERTICES[[0, 1, 3, 4]], GRID_VERTICES[[1, 2, 4, 5]]
    faces = np.array([[0, 1, 3], [0, 3, 2]])
    mesh = TriangleMesh(
        np.concatenate([left, right]),
        np.concatenate([faces, faces + 4]),
        attributes={"vertex_color": np.repeat(colours, 4, axis=0)},
    )
    material = spectrace.diffuse(spectrace.mesh_attribute("vertex_color"))
    image = Renderer(_scene(spectrace.shape(mesh, material)), device).render()
    for region, rgb, what in zip(_halves(image.xyz), colours, ("left", "right"), strict=True):
        _assert_region(region, _sigmoid_spectrum(rgb), what)


def test_a_face_attribute_is_constant_per_face_across_shared_vertices(device):
    """The two halves share their middle vertices, yet a face attribute (one number per face, times scale 2) keeps
    each face's own value up to the shared edge: 2 × 0.15 on the left, 2 × 0.4 on the right, grey reflectances."""
    weights = np.array([0.15, 0.15, 0.4, 0.4])
    mesh = TriangleMesh(GRID_VERTICES, HALF_FACES, attributes={"face_weight": weights})
    material = spectrace.diffuse(spectrace.mesh_attribute("face_weight", scale=2.0))
    image = Renderer(_scene(spectrace.shape(mesh, material)), device).render()
    for region, value, what in zip(_halves(image.xyz), (0.3, 0.8), ("left", "right"), strict=True):
        _assert_region(region, np.full_like(GRID, value), what)


@pytest.mark.slow
@pytest.mark.parametrize("integrator", ["light", "bdpt"])
def test_light_paths_read_mesh_attributes_as_camera_paths_do(device, integrator):
    """The light tracer and BDPT read the attributes at their own vertices: a mix of a vertex-coloured diffuse and a
    grey 0.9 by a face weight (0.15 left, 0.4 right) reflects (1 − w) ρ(λ) + 0.9 w in each half (colour-science)."""
    colour = np.array([0.8, 0.2, 0.1])
    weights = np.array([0.15, 0.15, 0.4, 0.4])
    attributes = {"face_weight": weights, "vertex_color": np.tile(colour, (6, 1))}
    mesh = TriangleMesh(GRID_VERTICES, HALF_FACES, attributes=attributes)
    textured = spectrace.diffuse(spectrace.mesh_attribute("vertex_color"))
    material = spectrace.mix([textured, spectrace.diffuse(0.9)], spectrace.mesh_attribute("face_weight"))
    scene = _scene(spectrace.shape(mesh, material), spp=32).with_overrides(integrator=integrator)
    image = Renderer(scene, device).render()
    for region, w, what in zip(_halves(image.xyz), (0.15, 0.4), ("left", "right"), strict=True):
        _assert_region(region, (1.0 - w) * _sigmoid_spectrum(colour) + 0.9 * w, what)


def _distance_to_line(point, p, q) -> float:
    edge, offset = q - p, point - p
    return abs(edge[0] * offset[1] - edge[1] * offset[0]) / float(np.linalg.norm(edge))


def test_a_vertex_attribute_is_the_barycentric_blend_at_each_pixel(device):
    """Six vertices of different grey values: each pixel (away from the triangles' shared edges, where a pixel
    spans two planes) has the value numpy's barycentrics of its centre's point give, the attribute being linear
    across each triangle and the camera looking straight at the quad (so the pixel's mean is its centre's value)."""
    values = np.array([0.1, 0.5, 0.9, 0.7, 0.3, 0.6])
    mesh = TriangleMesh(GRID_VERTICES, HALF_FACES, attributes={"vertex_value": values})
    image = Renderer(
        _scene(spectrace.shape(mesh, spectrace.diffuse(spectrace.mesh_attribute("vertex_value"))), spp=128), device
    ).render()
    centres = (2.0 * (np.arange(SIDE) + 0.5) / SIDE - 1.0) * 3.0 * TAN_HALF
    expected, used = np.zeros((SIDE, SIDE)), np.zeros((SIDE, SIDE), bool)
    pixel = 2.0 * 3.0 * TAN_HALF / SIDE
    for row in range(SIDE):
        for column in range(SIDE):
            point = np.array([centres[column], -centres[row]])  # film rows run down, y up
            for face in HALF_FACES:
                a, b, c = GRID_VERTICES[face, :2]
                b1, b2 = np.linalg.solve(np.column_stack([b - a, c - a]), point - a)
                weights = np.array([1.0 - b1 - b2, b1, b2])
                if weights.min() >= 0.0:
                    expected[row, column] = weights @ values[face]
                    # distance to the triangle's edges, in pixels: keep pixels whose square lies inside it
                    edges = [(a, b), (b, c), (c, a)]
                    distance = min(
                        abs((q - p)[0] * (point - p)[1] - (q - p)[1] * (point - p)[0]) / np.linalg.norm(q - p)
                        for p, q in edges
                    )
                    used[row, column] = distance > 0.75 * pixel
    assert used.sum() > 60
    # Y of a grey reflectance r under the equal-energy environment of 1: r times white's Y (colour-science).
    ys = image.xyz[..., 1][used]
    mean, error = mean_and_standard_error(ys - expected[used] * _xyz_colour_science(np.ones_like(GRID))[1])
    assert_within_standard_errors(mean, 0.0, error, slack=2e-4)
    # Pixel by pixel too: a corner's value put at another corner would keep the mean near but not the pattern.
    assert np.corrcoef(ys, expected[used])[0, 1] > 0.98
    # and pixel by pixel, the largest value where the blend is largest, which a swapped corner would move
    assert np.corrcoef(ys, expected[used])[0, 1] > 0.98


def test_missing_attribute_and_wrong_use_are_refused_naming_the_shape(device):
    """A mesh without the attribute, a colour where a number is needed (a roughness), values above 1 as a
    reflectance or above a mix's amount range, an analytic sphere (which has no mesh): one error each, naming the
    shape."""
    rgb = np.full((6, 3), 0.5)
    mesh = TriangleMesh(GRID_VERTICES, HALF_FACES, attributes={"vertex_color": rgb, "vertex_big": np.full(6, 1.5)})
    pair = [spectrace.diffuse(0.5), spectrace.diffuse(0.2)]
    cases = [
        (mesh, spectrace.diffuse(spectrace.mesh_attribute("vertex_missing")), "has no attribute 'vertex_missing'"),
        (mesh, spectrace.conductor("Au", roughness=spectrace.mesh_attribute("vertex_color")), "needs one"),
        (mesh, spectrace.diffuse(spectrace.mesh_attribute("vertex_big")), "above 1"),
        (mesh, spectrace.mix(pair, spectrace.mesh_attribute("vertex_big")), "above 1"),
        ("sphere", spectrace.diffuse(spectrace.mesh_attribute("vertex_color")), "not a triangle mesh"),
    ]
    for geometry, material, message in cases:
        with pytest.raises(SpectraceError, match=message) as raised:
            Renderer(_scene(spectrace.shape(geometry, material, name="panel"), spp=1), device)
        assert "panel" in str(raised.value)


def _ply(path, vertex_properties: list[str], face_properties: list[str], rng) -> dict:
    """A binary PLY of one quad (two triangles) with float properties as named; returns their values."""
    vertices = np.array([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]], np.float32)
    values = {name: rng.random(4).astype(np.float32) for name in vertex_properties}
    face_values = {name: rng.random(2).astype(np.float32) for name in face_properties}
    header = ["ply", "format binary_little_endian 1.0", "element vertex 4"]
    header += [f"property float {name}" for name in ("x", "y", "z", *vertex_properties)]
    header += ["element face 2", "property list uchar int vertex_indices"]
    header += [f"property float {name}" for name in face_properties]
    body = b""
    for i in range(4):
        body += vertices[i].tobytes() + b"".join(values[n][i].tobytes() for n in vertex_properties)
    for f, face in enumerate(([0, 1, 2], [0, 2, 3])):
        body += bytes([3]) + np.array(face, "<i4").tobytes()
        body += b"".join(face_values[n][f].tobytes() for n in face_properties)
    path.write_bytes(("\n".join(header) + "\nend_header\n").encode() + body)
    return values | face_values


@pytest.mark.peer
def test_ply_properties_become_the_attributes_mitsuba_makes_of_them(tmp_path):
    """Each property naming scheme Mitsuba 3's PLY reader groups (`_0.._2`, `_x.._z`, `_r.._b` -> `<name>_color`,
    bare `r g b` -> `color`, a single `_0`), and those it ignores (no suffix, two channels): the attributes and
    values spectrace reads are Mitsuba's own."""
    mi = pytest.importorskip("mitsuba")
    mi.set_variant("scalar_rgb")
    path = tmp_path / "quad.ply"
    _ply(
        path,
        [
            "c_0",
            "c_1",
            "c_2",
            "n_x",
            "n_y",
            "n_z",
            "r",
            "g",
            "b",
            "w_0",
            "plain",
            "two_0",
            "two_1",
            "k_r",
            "k_g",
            "k_b",
        ],
        ["weight_0", "f_0", "f_1", "f_2", "bare"],
        np.random.default_rng(2),
    )
    ours = load_mesh(path, "quad").attributes or {}
    params = mi.traverse(mi.load_dict({"type": "ply", "filename": str(path)}))
    geometry = {"faces", "vertex_positions", "vertex_normals", "vertex_texcoords"}
    keys = [key for key in params.keys() if key.startswith(("vertex_", "face_"))]  # noqa: SIM118 (no __iter__)
    theirs = {key: np.array(params[key]) for key in keys}
    theirs = {key: value for key, value in theirs.items() if key not in geometry}
    assert set(ours) == set(theirs)
    for name, values in ours.items():
        np.testing.assert_allclose(values.ravel(), theirs[name], rtol=1e-6, err_msg=name)


MITSUBA_SCENE = """<scene version="3.0.0">
  <integrator type="path"><integer name="max_depth" value="3"/></integrator>
  <sensor type="perspective"><float name="fov" value="35"/>
    <transform name="to_world"><lookat origin="0, 0.5, 3.2" target="0, 0, 0" up="0, 1, 0"/></transform>
    <film type="hdrfilm"><integer name="width" value="32"/><integer name="height" value="32"/>
      <rfilter type="box"/></film></sensor>
  <texture type="mesh_attribute" id="weight"><string name="name" value="face_weight"/></texture>
  <shape type="ply"><string name="filename" value="quad.ply"/>
    <bsdf type="blendbsdf"><ref name="weight" id="weight"/>
      <bsdf type="diffuse"><texture type="mesh_attribute" name="reflectance">
        <string name="name" value="vertex_color"/></texture></bsdf>
      <bsdf type="roughconductor"><float name="alpha" value="0.3"/></bsdf></bsdf>
  </shape>
  <shape type="sphere"><point name="center" x="0" y="0" z="0.5"/><float name="radius" value="0.4"/>
    <bsdf type="diffuse"><rgb name="reflectance" value="0.6"/></bsdf></shape>
  <emitter type="directional"><vector name="direction" x="0.3" y="-0.6" z="-1"/><rgb name="irradiance" value="2"/>
  </emitter>
  <emitter type="constant"><rgb name="radiance" value="0.3"/></emitter>
</scene>"""


@pytest.mark.peer
@pytest.mark.slow
def test_vertex_colours_and_face_weights_render_as_mitsuba_renders_them(tmp_path, device, mitsuba_scalar_spectral):
    """A PLY quad of 8 × 8 cells, random vertex colours as a diffuse reflectance blended with a rough conductor by
    a random per-face weight, beside a sphere: Mitsuba 3 and spectrace's import of the same XML agree per 8 × 8
    block within 5 standard errors (8 independent images each)."""
    from replica_agreement import assert_renders_like_mitsuba

    rng = np.random.default_rng(7)
    n = 9
    xs = np.linspace(-1.5, 1.5, n)
    vertices = np.array([[x, y, 0.0] for y in xs for x in xs], np.float32)
    cells = [
        (j * n + i, j * n + i + 1, (j + 1) * n + i + 1, (j + 1) * n + i) for j in range(n - 1) for i in range(n - 1)
    ]
    faces = np.array([tri for a, b, c, d in cells for tri in ((a, b, c), (a, c, d))], np.int32)
    colours, weights = rng.random((len(vertices), 3)).astype(np.float32), rng.random(len(faces)).astype(np.float32)
    header = [
        "ply",
        "format binary_little_endian 1.0",
        f"element vertex {len(vertices)}",
        *(f"property float {p}" for p in ("x", "y", "z", "color_0", "color_1", "color_2")),
        f"element face {len(faces)}",
        "property list uchar int vertex_indices",
        "property float weight_0",
    ]
    body = np.concatenate([vertices, colours], axis=1).astype("<f4").tobytes()
    face_dtype = np.dtype([("n", "u1"), ("i", "<i4", (3,)), ("w", "<f4")])
    face_rows = np.zeros(len(faces), face_dtype)
    face_rows["n"], face_rows["i"], face_rows["w"] = 3, faces, weights
    (tmp_path / "quad.ply").write_bytes(("\n".join(header) + "\nend_header\n").encode() + body + face_rows.tobytes())
    (tmp_path / "scene.xml").write_text(MITSUBA_SCENE)
    theirs = assert_renders_like_mitsuba(mitsuba_scalar_spectral, tmp_path / "scene.xml", device, 8, 16, 8)
    assert np.ptp(theirs.mean(axis=0)[..., 1]) > 0.1  # the comparison saw the colours


@pytest.mark.subprocess
def test_the_scene_format_names_the_attribute_and_refuses_a_bad_name(tmp_path):
    """A scene file's mesh_attribute texture needs a vertex_ or face_ name: another is one line naming the key."""
    scene = tmp_path / "scene.toml"
    scene.write_text(
        "[camera]\norigin = [0, 0, 3]\ntarget = [0, 0, 0]\nfov = 30\n[film]\nwidth = 8\nheight = 8\n"
        '[[shapes]]\ntype = "rectangle"\nmaterial = "m"\n'
        '[materials.m]\ntype = "diffuse"\nreflectance = { texture = "mesh_attribute", attribute = "colour" }\n'
    )
    result = subprocess.run(
        [sys.executable, "-m", "spectrace", "render", str(scene), "-o", str(tmp_path / "out.exr"), "--spp", "1"],
        capture_output=True,
        text=True,
        check=False,
    )
    assert result.returncode != 0
    assert "vertex_ or face_" in result.stderr and "Traceback" not in result.stderr
    assert "attribute" in result.stderr


@pytest.mark.peer
def test_an_exported_mesh_carries_its_attributes_to_mitsuba(tmp_path):
    """The Mitsuba export's PLY writes each attribute as `<name>_0..` properties: Mitsuba 3 reads back the same
    attributes and values (float32), and so does spectrace's reader."""
    from spectrace.interop.mitsuba.export import write_binary_ply

    mi = pytest.importorskip("mitsuba")
    mi.set_variant("scalar_rgb")
    rng = np.random.default_rng(9)
    attributes = {"vertex_color": rng.random((6, 3)), "vertex_w": rng.random(6), "face_weight": rng.random(4)}
    path = tmp_path / "panel.ply"
    write_binary_ply(TriangleMesh(GRID_VERTICES, HALF_FACES, attributes=attributes), path)
    params = mi.traverse(mi.load_dict({"type": "ply", "filename": str(path)}))
    ours = load_mesh(path, "panel").attributes or {}
    assert set(ours) == set(attributes)
    for name, values in attributes.items():
        stored = np.asarray(values, np.float32).ravel()
        np.testing.assert_array_equal(np.array(params[name]), stored, err_msg=name)
        np.testing.assert_array_equal(ours[name].ravel(), stored, err_msg=name)


def test_a_live_edit_that_adds_a_mesh_attribute_is_one_error_and_changes_nothing(tmp_path):
    """A live session's material edit that would add a mesh_attribute texture (whose tables follow the triangles')
    is refused in one error naming the reason, and the session renders on as before."""
    from spectrace.session import Session

    path = tmp_path / "scene.toml"
    path.write_text(
        "[camera]\norigin = [0, 0, 3]\ntarget = [0, 0, 0]\nfov = 30\n[film]\nwidth = 8\nheight = 8\n"
        '[[shapes]]\ntype = "rectangle"\nmaterial = "m"\n'
        '[materials.m]\ntype = "diffuse"\nreflectance = { value = 0.5 }\n'
        '[[lights]]\ntype = "constant"\nradiance = { value = 1 }\n'
    )
    with Session(path) as session:
        session.step(1)
        with pytest.raises(SpectraceError, match="mesh_attribute|has no attribute"):
            session.update({"materials.m.reflectance": {"texture": "mesh_attribute", "attribute": "vertex_color"}})
        session.step(1)
        assert session.image().xyz[..., 1].mean() > 0.0
