"""pbrt-v4 import: the tokenizer and the transforms against values derived here (SciPy's rotations, matrices written
out by hand), pbrt-v4's conventions against their definitions (fov on the shorter axis, image right = camera +x,
maxdepth counting bounces, lights normalised to luminance), a point light over a diffuse plane against the closed
form, and a small scene against the same scene written as Mitsuba XML (imported and rendered by spectrace)."""

import math
from pathlib import Path

import numpy as np
import pytest

import spectrace
from cli_runner import run_in_process
from replica_agreement import assert_replicas_agree, spectrace_replicas
from spectrace.errors import SpectraceError
from spectrace.interop.pbrt import import_pbrt, load_pbrt_scene, pbrt_scene_data
from spectrace.interop.pbrt.graphics_state import column_major, look_at, read_scene, rotate
from spectrace.interop.pbrt.parser import Location, tokenize
from spectrace.spectral import spectrum_to_xyz

HEADER = """LookAt 0 0 5  0 0 0  0 1 0
Camera "perspective" "float fov" 30
Film "rgb" "integer xresolution" 8 "integer yresolution" 6
WorldBegin
"""
PLANE = 'Shape "trianglemesh" "point3 P" [-9 -9 0  9 -9 0  9 9 0  -9 9 0] "integer indices" [0 1 2 0 2 3]\n'


def _write(folder: Path, body: str, header: str = HEADER, name: str = "scene.pbrt") -> Path:
    path = folder / name
    path.write_text(header + body)
    return path


# ---------------------------------------------------------------- tokenizer and parameters


def test_tokens_strings_numbers_brackets_and_comments():
    text = 'Shape "sphere" # a comment "not a string"\n  "float radius" [ -1.5e2 ] "string n" "a \\"q\\" b"\n'
    text += '["s" 7 # note\n]\n[.5\n 2]\nWorldBegin'
    tokens = list(tokenize(text, Path("x.pbrt")))
    assert [(t.text, t.kind, t.location.line) for t in tokens] == [
        ("Shape", "word", 1),
        ("sphere", "string", 1),
        ("float radius", "string", 2),
        (" -1.5e2 ", "array", 2),  # brackets without strings or comments: one token, split later
        ("string n", "string", 2),
        ('a "q" b', "string", 2),
        ("[", "[", 3),
        ("s", "string", 3),
        ("7", "number", 3),
        ("]", "]", 4),
        (".5\n 2", "array", 5),
        ("WorldBegin", "word", 7),
    ]


def test_parameter_lists_with_and_without_brackets(tmp_path):
    path = _write(
        tmp_path,
        'Shape "sphere" "float radius" 2 "bool flag" true "string s" ["x"] "spectrum eta" "glass-BK7"\n'
        '  "rgb c" [0.1 0.2 0.3] "integer n" [1 2 3]\n',
    )
    (shape,) = read_scene(path).shapes
    values = {p.name: (p.type, p.values, p.location.line) for p in shape.entity.parameters}
    assert values == {
        "radius": ("float", [2.0], 5),
        "flag": ("bool", [True], 5),
        "s": ("string", ["x"], 5),
        "eta": ("spectrum", ["glass-BK7"], 5),
        "c": ("rgb", [0.1, 0.2, 0.3], 6),
        "n": ("integer", [1.0, 2.0, 3.0], 6),
    }


@pytest.mark.parametrize(
    ("body", "line", "message"),
    [
        ('Shape "sphere" "float radius" "x\n', 5, "unterminated string"),
        ("Translate 1 2\nShape", 6, "expected a number after Translate"),
        ("Frobnicate 1\n", 5, "unknown directive 'Frobnicate'"),
        ("AttributeBegin\nAttributeEnd\nAttributeEnd\n", 7, "AttributeEnd without a matching AttributeBegin"),
        ('Shape "sphere" "floot radius" 1\n', 5, "unknown parameter type 'floot'"),
        ('Shape "sphere" "rgb c" [1 2]\n', 5, "needs a multiple of 3 values"),
        ('Shape "sphere" "point3 P" [1 2\n 3 x 5 6]\n', 5, "expected a number for \"point3 P\", got 'x'"),
        ('Shape "sphere" "float r" [1.2.3]\n', 5, "got '1.2.3'"),
        ("Transform [1 0 0 0  0 1 0 0  0 0 1 0]\n", 5, "Transform takes 16 numbers"),
        ('Include "missing.pbrt"\n', 5, "not a file"),
        ("AttributeBegin\n", 5, "AttributeBegin is never closed"),
        ('ObjectInstance "nothing"\n', 5, "which no ObjectBegin defined"),
        ('ObjectBegin "a"\nObjectEnd\nObjectBegin "b"\nObjectInstance "a"\n', 8, "pbrt-v4 does not nest instances"),
    ],
)
def test_bad_input_names_file_and_line(tmp_path, body, line, message):
    path = _write(tmp_path, body)
    with pytest.raises(SpectraceError) as failure:
        read_scene(path)
    assert failure.value.where == f"{path}:{line}"
    assert message in failure.value.message


def test_include_reads_relative_to_the_including_file(tmp_path):
    (tmp_path / "parts").mkdir()
    (tmp_path / "parts" / "a.pbrt").write_text('Translate 1 0 0\nInclude "b.pbrt"\n')
    (tmp_path / "parts" / "b.pbrt").write_text('Shape "sphere"\n')
    scene = read_scene(_write(tmp_path, 'AttributeBegin\nImport "parts/a.pbrt"\nAttributeEnd\nShape "sphere"\n'))
    first, second = scene.shapes
    assert first.entity.location == Location(tmp_path / "parts" / "b.pbrt", 1)
    np.testing.assert_allclose(first.world_from_object[:3, 3], (1, 0, 0))
    np.testing.assert_allclose(second.world_from_object, np.eye(4))  # AttributeEnd restored the CTM


# ---------------------------------------------------------------- transforms


@pytest.mark.parametrize(("angle", "axis"), [(30.0, (0, 1, 0)), (-75.0, (1, 2, 3)), (180.0, (0, 0, 5))])
def test_rotate_matches_scipy_and_normalises_the_axis(angle, axis):
    from scipy.spatial.transform import Rotation

    unit = np.asarray(axis, float) / np.linalg.norm(axis)
    expected = Rotation.from_rotvec(math.radians(angle) * unit).as_matrix()
    np.testing.assert_allclose(rotate(angle, *axis, Location(Path("x"), 1))[:3, :3], expected, atol=1e-12)


def test_transform_lists_the_matrix_column_by_column():
    matrix = column_major([1, 0, 0, 0, 0, 2, 0, 0, 0, 0, 3, 0, 4, 5, 6, 1])
    np.testing.assert_array_equal(matrix @ [1, 1, 1, 1], [5, 7, 9, 1])


def test_look_at_maps_eye_to_origin_and_target_to_plus_z():
    camera_from_world = look_at([1, 2, 3, 1, 2, 8, 0, 1, 0], Location(Path("x"), 1))
    np.testing.assert_allclose(camera_from_world @ [1, 2, 3, 1], [0, 0, 0, 1], atol=1e-12)
    np.testing.assert_allclose(camera_from_world @ [1, 2, 8, 1], [0, 0, 5, 1], atol=1e-12)
    # pbrt's camera +x is up × forward: world +x here (forward +z, up +y), so its image right is world +x.
    np.testing.assert_allclose(camera_from_world @ [2, 2, 3, 1], [1, 0, 0, 1], atol=1e-12)


def test_directives_compose_right_to_left_on_points(tmp_path):
    body = """Translate 1 0 0
Scale 2 2 2
Rotate 90 0 0 1
CoordinateSystem "here"
Identity
Shape "sphere"
CoordSysTransform "here"
ConcatTransform [1 0 0 0  0 1 0 0  0 0 1 0  0 0 3 1]
Shape "sphere"
"""
    first, second = read_scene(_write(tmp_path, body)).shapes
    np.testing.assert_allclose(first.world_from_object, np.eye(4))
    # T(1,0,0) S(2) Rz(90°) T(0,0,3) applied to the origin: (0,0,3) -> (0,0,3) -> (0,0,6) -> (1,0,6).
    np.testing.assert_allclose(second.world_from_object @ [0, 0, 0, 1], [1, 0, 6, 1], atol=1e-12)
    # and to +x: Rz turns it to +y, S doubles it, T moves it: (1, 2, 6).
    np.testing.assert_allclose(second.world_from_object @ [1, 0, 0, 1], [1, 2, 6, 1], atol=1e-12)


def test_instances_are_copies_under_the_instance_transform(tmp_path):
    body = """ObjectBegin "thing"
Translate 0 1 0
Shape "sphere"
ObjectEnd
Shape "sphere"
Translate 5 0 0
ObjectInstance "thing"
Rotate 90 0 0 1
ObjectInstance "thing"
"""
    scene = read_scene(_write(tmp_path, body))
    assert len(scene.shapes) == 1 and [use.name for use in scene.object_uses] == ["thing", "thing"]
    (inside,) = scene.objects["thing"]
    placed = [use.world_from_instance @ inside.world_from_object for use in scene.object_uses]
    centres = [m @ [0, 0, 0, 1] for m in [scene.shapes[0].world_from_object, *placed]]
    np.testing.assert_allclose(centres, [[0, 0, 0, 1], [5, 1, 0, 1], [4, 0, 0, 1]], atol=1e-12)


def _placed_triangles(scene) -> np.ndarray:
    """Every triangle of a loaded scene in world space, instances placed as copies, sorted for comparison."""
    from spectrace.geometry.transforms import apply_transform

    meshes = [shape.mesh for shape in scene.shapes]
    meshes += [apply_transform(s.mesh, i.to_world) for i in scene.instances for s in i.object.shapes]
    triangles = np.concatenate([np.stack(m.triangles(), axis=1) for m in meshes])  # (M, 3 corners, 3)
    # Corners in a fixed order: a mirrored copy's front (pbrt flips it by the placement's handedness) may wind a
    # triangle the other way round than its instanced twin, whose front follows the object's own placement.
    corners = np.round(triangles, 9)
    order = np.lexsort((corners[..., 2], corners[..., 1], corners[..., 0]), axis=1)
    triangles = np.take_along_axis(triangles, order[..., None], axis=1)
    triangles = np.sort(np.round(triangles, 9).reshape(len(triangles), -1).view("f8,f8,f8,f8,f8,f8,f8,f8,f8"), axis=0)
    return triangles.view(np.float64).reshape(-1, 9)


def test_objects_are_imported_once_and_placed_by_instances(tmp_path):
    """An object of a mesh and a partial disk placed three times (once mirrored) imports as one spectrace object with
    three instances, its mesh written once, and places the same triangles as the same shapes written out in
    world space; an area light in an object is left out, as pbrt-v4 leaves it out."""
    mesh = 'Shape "trianglemesh" "point3 P" [0 0 0  1 0 0  0 1 0  1 1 0] "integer indices" [0 1 2 2 1 3]\n'
    sphere = 'Shape "disk" "float radius" 0.5 "float phimax" 300\n'
    placements = ["Translate 1 0 0", "Rotate 30 0 1 0\nScale 2 1 1", "Scale -1 1 1\nTranslate 0 2 0"]
    defined = 'ObjectBegin "thing"\nTranslate 0 0 1\n' + mesh + sphere + "ObjectEnd\n"
    uses = "".join(f'AttributeBegin\n{p}\nObjectInstance "thing"\nAttributeEnd\n' for p in placements)
    written_out = "".join(f"AttributeBegin\n{p}\nTranslate 0 0 1\n{mesh}{sphere}AttributeEnd\n" for p in placements)
    toml = tmp_path / "out" / "scene.toml"
    import_pbrt(_write(tmp_path, PLANE + defined + uses), toml)
    from spectrace.scene import load_scene

    instanced = load_scene(toml)
    assert len(instanced.instances) == 3 and len({id(i.object) for i in instanced.instances}) == 1
    # The plane and the object's mesh; its partial disk is analytic.
    assert len(instanced.shapes) == 1 and len(list((tmp_path / "out").rglob("*.ply"))) == 2
    assert instanced.instances[0].object.shapes[1].analytic.phi_max == pytest.approx(np.radians(300))
    toml2 = tmp_path / "out2" / "scene.toml"
    import_pbrt(_write(tmp_path, PLANE + written_out, name="copies.pbrt"), toml2)
    copies = load_scene(toml2)
    assert not copies.instances
    np.testing.assert_allclose(_placed_triangles(instanced), _placed_triangles(copies), atol=1e-6)

    # pbrt-v4 instances no area lights (it warns and places the shapes unlit): so does the import.
    light = 'ObjectBegin "lamp"\nAreaLightSource "diffuse"\n' + mesh + "ObjectEnd\n"
    data, importer = pbrt_scene_data(_write(tmp_path, light + uses.replace("thing", "lamp"), name="lamp.pbrt"))
    assert len(data["instances"]) == 3 and not any("emitter" in s for s in data["objects"]["lamp"]["shapes"])
    assert any("Area lights not supported with object instancing" in w for w in importer.warnings)


def test_object_spheres_stay_analytic_under_any_instance_transform(tmp_path, kernel_runner):
    """A whole sphere in an object is spectrace's analytic sphere in the object's space; instances that stretch it
    into ellipsoids place it by their maps, and rays meet the ellipsoids at the float64 closed form's distances."""
    from tests.geometry.test_analytic_shapes import _reference_hits
    from tests.geometry.test_instances import _trace

    from spectrace.geometry.analytic import AnalyticSurface

    defined = 'ObjectBegin "ball"\nTranslate 0 0 1\nShape "sphere" "float radius" 0.5\nObjectEnd\n'
    placements = ["Translate 1 0 0\nScale 2 1 0.5", "Rotate 30 0 1 0\nScale 1 1.5 1", "Translate -1.5 0.5 0"]
    uses = "".join(f'AttributeBegin\n{p}\nObjectInstance "ball"\nAttributeEnd\n' for p in placements)
    marker = 'AttributeBegin\nTranslate 4 0 0\nShape "sphere" "float radius" 0.1\nAttributeEnd\n'
    scene = load_pbrt_scene(_write(tmp_path, marker + defined + uses))
    (ball,) = {id(i.object): i.object for i in scene.instances}.values()
    assert [s.analytic.kind for s in ball.shapes] == ["sphere"]
    # pbrt's left-handed world is mirrored through x = 0 or not (the marker at pbrt's x = 4 says which).
    mirror = np.diag([np.sign(scene.shapes[0].analytic.to_world[0, 3]), 1.0, 1.0, 1.0])

    def t(x, y, z):
        m = np.eye(4)
        m[:3, 3] = x, y, z
        return m

    def s(x, y, z):
        return np.diag([x, y, z, 1.0])

    c, r = np.cos(np.radians(30)), np.sin(np.radians(30))
    rotate_y = np.array([[c, 0, r, 0], [0, 1, 0, 0], [-r, 0, c, 0], [0, 0, 0, 1]])
    expected = [t(1, 0, 0) @ s(2, 1, 0.5), rotate_y @ s(1, 1.5, 1), t(-1.5, 0.5, 0)]
    in_object = t(0, 0, 1) @ s(0.5, 0.5, 0.5)
    for instance, placement in zip(scene.instances, expected):
        np.testing.assert_allclose(
            instance.to_world @ ball.shapes[0].analytic.to_world, mirror @ placement @ in_object, atol=1e-12
        )
    rng = np.random.default_rng(2)
    origins = rng.normal(size=(1500, 3)) * 3 + [0, 0, 4]
    directions = rng.uniform([-2.5, -1, 0], [2.5, 1.5, 1.5], (1500, 3)) - origins
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    t_ref = np.min(
        [_reference_hits(AnalyticSurface("sphere", mirror @ p @ in_object), origins, directions)[0] for p in expected],
        axis=0,
    )
    only_balls = spectrace.Scene(camera=scene.camera, width=4, height=4, shapes=[], instances=scene.instances)
    hit = _trace(kernel_runner, only_balls, origins, directions, np.full(len(origins), 1e9))[1][0]
    assert np.isfinite(t_ref).mean() > 0.2 and np.mean(np.isfinite(hit[:, 0]) != np.isfinite(t_ref)) < 0.003
    both = np.isfinite(t_ref) & np.isfinite(hit[:, 0])
    np.testing.assert_allclose(hit[both, 0], t_ref[both], rtol=5e-5)


# ---------------------------------------------------------------- conventions


def test_fov_spans_the_shorter_axis(tmp_path):
    for width, height, axis in ((8, 6, "y"), (6, 8, "x")):
        header = HEADER.replace('xresolution" 8', f'xresolution" {width}').replace(
            'yresolution" 6', f'yresolution" {height}'
        )
        data, _ = pbrt_scene_data(_write(tmp_path, PLANE, header))
        assert (data["camera"]["fov"], data["camera"]["fov_axis"]) == (30.0, axis)
    # The horizontal field of view of the 8 x 6 image, from the vertical 30 degrees.
    data, _ = pbrt_scene_data(_write(tmp_path, PLANE))
    assert (data["film"]["width"], data["film"]["height"]) == (8, 6)


def test_maxdepth_counts_bounces_and_defaults(tmp_path):
    data, _ = pbrt_scene_data(_write(tmp_path, PLANE))
    assert data["integrator"] == {"type": "path", "max_depth": 6}  # pbrt-v4's default maxdepth 5
    assert data["sampler"]["spp"] == 16
    header = HEADER.replace("WorldBegin", 'Integrator "path" "integer maxdepth" 1\nWorldBegin')
    data, _ = pbrt_scene_data(_write(tmp_path, PLANE, header))
    assert data["integrator"]["max_depth"] == 2  # direct light only


@pytest.mark.parametrize(
    "spectrum",
    ['"blackbody I" 3000', '"spectrum I" "stdillum-A"', '"spectrum I" [400 1 500 3 700 2]', ""],
)
def test_lights_are_normalised_to_luminance_scale(tmp_path, spectrum):
    """pbrt-v4 divides a light's spectrum by its photometric integral: its luminance factor is `scale`."""
    body = f'LightSource "point" "point3 from" [0 0 1] {spectrum} "float scale" 2.5\n' + PLANE
    scene = load_pbrt_scene(_write(tmp_path, body))
    (light,) = scene.lights
    assert spectrum_to_xyz(light.intensity)[1] == pytest.approx(2.5, rel=1e-6)


def test_blackbody_light_matches_planck_normalised_with_colour_science(tmp_path):
    """pbrt-v4's I(λ) = scale · B(λ) / ∫ȳB: Planck's law written here, the luminance factor from colour-science's
    CIE 1931 ȳ (spectrace's film: Y = ∫ȳL / ∫ȳ)."""
    import colour

    body = 'LightSource "point" "blackbody I" 2700 "float scale" 4\n' + PLANE
    (light,) = load_pbrt_scene(_write(tmp_path, body)).lights
    wavelengths = np.arange(360.0, 831.0)
    h, c, k = 6.62607015e-34, 299792458.0, 1.380649e-23
    metres = wavelengths * 1e-9
    planck = 2 * h * c**2 / metres**5 / np.expm1(h * c / (metres * k * 2700.0))
    ybar = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"].copy().align(colour.SpectralShape(360, 830, 1))
    ybar = ybar.values[:, 1]
    expected = 4.0 * planck / (np.sum(ybar * planck) / np.sum(ybar))
    np.testing.assert_allclose(light.intensity.values, expected, rtol=2e-3)


def test_light_power_follows_pbrt(tmp_path):
    body = 'LightSource "point" "float power" 100 "rgb I" [1 1 1]\n' + PLANE
    data, _ = pbrt_scene_data(_write(tmp_path, body))
    assert data["lights"][0]["intensity"]["scale"] == pytest.approx(100 / (4 * math.pi))
    # A spot's power spreads over 2π((1 - cos θs) + (cos θs - cos θc)/2), θc = coneangle, θs = coneangle - delta.
    body = 'LightSource "spot" "float power" 50 "float coneangle" 40 "float conedeltaangle" 10 "rgb I" [1 1 1]\n'
    data, _ = pbrt_scene_data(_write(tmp_path, body + PLANE))
    cos_c, cos_s = math.cos(math.radians(40)), math.cos(math.radians(30))
    spot = data["lights"][0]
    assert spot["intensity"]["scale"] == pytest.approx(50 / (2 * math.pi * ((1 - cos_s) + (cos_s - cos_c) / 2)))
    assert (spot["cutoff_angle"], spot["falloff_start"]) == (40, 30)
    # An area light's power: over the shape's area (a 2 x 3 quad), π, and two sides.
    body = 'AreaLightSource "diffuse" "float power" 60 "bool twosided" true "rgb L" [1 1 1]\n'
    body += 'Shape "trianglemesh" "point3 P" [0 0 0  2 0 0  2 3 0  0 3 0] "integer indices" [0 1 2 0 2 3]\n'
    data, _ = pbrt_scene_data(_write(tmp_path, body))
    emitter = data["shapes"][0]["emitter"]
    assert emitter["radiance"]["scale"] == pytest.approx(60 / (2 * 6 * math.pi)) and emitter["two_sided"]
    # A distant light travels from `from` to `to`; `illuminance` multiplies its unit-luminance spectrum.
    body = 'LightSource "distant" "point3 from" [0 5 0] "point3 to" [0 0 0] "float illuminance" 3 "rgb L" [1 1 1]\n'
    data, _ = pbrt_scene_data(_write(tmp_path, body + PLANE))
    distant = data["lights"][0]
    np.testing.assert_allclose(distant["direction"], [0, -1, 0], atol=1e-12)
    assert distant["irradiance"]["scale"] == pytest.approx(3.0)


def test_named_spectra_map_to_spectrace_data(tmp_path):
    body = """Material "conductor" "spectrum eta" "metal-Ag-eta" "spectrum k" "metal-Ag-k" "float roughness" 0.04
Shape "sphere"
Material "conductor" "spectrum eta" "metal-Au-eta" "spectrum k" [400 2 700 3]
Shape "sphere"
Material "dielectric" "spectrum eta" "glass-F11" "float roughness" 0.01 "bool remaproughness" false
Shape "sphere"
Material "coateddiffuse" "rgb reflectance" [0.2 0.3 0.4] "float eta" 1.4
Shape "sphere"
Material "thindielectric" "float eta" 1.33
Shape "sphere"
Material "coateddiffuse" "float roughness" 0.09
Shape "sphere"
"""
    data, importer = pbrt_scene_data(_write(tmp_path, body))
    materials = list(data["materials"].values())
    assert materials[0] == {"type": "conductor", "metal": "Ag", "roughness": pytest.approx(0.2)}  # sqrt(0.04)
    assert materials[1]["eta"] == {"spectrum": "metals/Au:eta"}
    # An index given over 400-700 nm holds its end values beyond (pbrt's zero there would be no index: a metal of
    # η = k = 0 reflects everything), with a note.
    assert materials[1]["k"]["values"] == [[400.0, 2.0], [700.0, 3.0]]
    assert any("400-700 nm" in note for note in importer.notes)
    assert materials[2] == {"type": "dielectric", "ior": "N-SF11", "roughness": 0.01}
    # pbrt's random walk between coat and base: the same layered model, with pbrt's defaults for its slab and walk.
    assert materials[3] == {
        "type": "coateddiffuse",
        "reflectance": {"rgb": [0.2, 0.3, 0.4]},
        "ior": 1.4,
        "thickness": 0.01,
        "g": 0.0,
        "max_depth": 10,
        "samples": 1,
    }
    assert materials[4] == {"type": "thindielectric", "ior": 1.33}
    assert materials[5]["type"] == "coateddiffuse" and materials[5]["roughness"] == pytest.approx(0.3)
    assert load_pbrt_scene(_write(tmp_path, body)).shapes[4].material == spectrace.thindielectric(1.33)


def test_every_named_spectrum_pbrt_shares_with_spectrace_loads(tmp_path):
    """pbrt-v4's stdillum-* and metal-{Ag,Al,Au,Cu}-* names (its spectrum.cpp table) all resolve to spectrace data."""
    illuminants = ["stdillum-A", "stdillum-D50", "stdillum-D65", *(f"stdillum-F{i}" for i in range(1, 13))]
    body = "".join(f'LightSource "point" "spectrum I" "{name}" "float scale" 2\n' for name in illuminants)
    for metal in ("Ag", "Al", "Au", "Cu"):
        body += f'Material "conductor" "spectrum eta" "metal-{metal}-eta" "spectrum k" "metal-{metal}-k"\n'
        body += 'Shape "sphere"\n'
    scene = load_pbrt_scene(_write(tmp_path, body))
    assert [spectrum_to_xyz(light.intensity)[1] for light in scene.lights] == pytest.approx([2.0] * len(illuminants))
    assert len({id(shape.material) for shape in scene.shapes}) == 4


# SCHOTT's catalogue n_d (587.5618 nm) of the glass each of pbrt-v4's glass names tabulates (SCHOTT Zemax catalogue
# 2017-01-20b, as quoted by refractiveindex.info; pbrt's tables agree with these glasses' formulas within 2e-4).
PBRT_GLASS_ND = {
    "glass-BK7": ("N-BK7", 1.5168),
    "glass-BAF10": ("N-BAF10", 1.67003),
    "glass-FK51A": ("N-FK51A", 1.48656),
    "glass-LASF9": ("N-LASF9", 1.85025),
    "glass-F5": ("N-SF5", 1.67271),
    "glass-F10": ("N-SF10", 1.72828),
    "glass-F11": ("N-SF11", 1.78472),
}


def test_all_seven_pbrt_glasses_and_pbrt_s_other_metals_import(tmp_path):
    """Every named glass and metal of pbrt-v4's table (spectrum.cpp's named spectra) resolves: a glass to the SCHOTT
    glass whose catalogue n_d its index reproduces, CuZn / MgO / TiO2 to their tabulated η and k."""
    body = "".join(f'Material "dielectric" "spectrum eta" "{name}"\nShape "sphere"\n' for name in PBRT_GLASS_ND)
    metals = ("CuZn", "MgO", "TiO2")
    for metal in metals:
        body += f'Material "conductor" "spectrum eta" "metal-{metal}-eta" "spectrum k" "metal-{metal}-k"\n'
        body += 'Shape "sphere"\n'
    data, _ = pbrt_scene_data(_write(tmp_path, body))
    tables = list(data["materials"].values())
    assert [table["ior"] for table in tables[:7]] == [glass for glass, _ in PBRT_GLASS_ND.values()]
    assert [table["eta"] for table in tables[7:]] == [{"spectrum": f"metals/{m}:eta"} for m in metals]
    scene = load_pbrt_scene(_write(tmp_path, body))
    for shape, (_, n_d) in zip(scene.shapes[:7], PBRT_GLASS_ND.values()):
        assert shape.material.ior.at(587.5618) == pytest.approx(n_d, abs=2e-5)
    # Brass at 550 nm, a row of pbrt's table (η 0.527, k 2.765): a metal; MgO and TiO2 are dielectrics (k about 0).
    brass, mgo, tio2 = (shape.material for shape in scene.shapes[7:])
    assert brass.eta.evaluate(550.0) == pytest.approx(0.527) and brass.k.evaluate(550.0) == pytest.approx(2.765)
    assert mgo.k.max() <= 1e-6 and 1.7 < mgo.eta.evaluate(550.0) < 1.8 and tio2.k.evaluate(550.0) < 1e-3


def test_reverse_orientation_and_bilinear_patches_keep_pbrt_fronts(tmp_path):
    body = """Shape "bilinearmesh" "point3 P" [0 0 0  1 0 0  0 1 0  1 1 0]
ReverseOrientation
Shape "bilinearmesh" "point3 P" [0 0 0  1 0 0  0 1 0  1 1 0]
Shape "trianglemesh" "point3 P" [0 0 0  1 0 0  0 1 0] "normal N" [0 0 1  0 0 1  0 0 1]
"""
    toml = tmp_path / "out" / "scene.toml"
    import_pbrt(_write(tmp_path, body), toml)
    from spectrace.scene import load_scene

    normals = []
    for shape in load_scene(toml).shapes:
        v0, v1, v2 = shape.mesh.triangles()
        normals.append(np.cross(v1 - v0, v2 - v0))
    # (p10 - p00) × (p01 - p00) = +z in pbrt's world: spectrace's world is mirrored (x -> -x) and keeps fronts.
    assert np.all(normals[0][:, 2] > 0) and np.all(normals[1][:, 2] < 0)
    # A reversed triangle with normals +z: pbrt turns the face toward its (reversed) shading normals, -z.
    assert np.all(normals[2][:, 2] < 0)


def test_partial_and_reversed_spheres_import_as_pbrt_defines_them(tmp_path):
    """A hemisphere (zmax 0) of radius 2 is the analytic sphere cut at the unit sphere's z = 0, of area 2π r²;
    ReverseOrientation turns a sphere's front in (the analytic sphere's flip_normals, or a tessellation's winding);
    a whole, plain sphere stays spectrace's built-in one; an ellipsoid with cuts needs triangles."""
    from spectrace.scene import load_scene

    body = 'Shape "sphere" "float radius" 2 "float zmax" 0\nShape "sphere"\nReverseOrientation\nShape "sphere"\n'
    body += 'Scale 1 2 1\nShape "sphere"\nShape "sphere" "float phimax" 90\n'
    data, importer = pbrt_scene_data(_write(tmp_path, body))
    hemisphere, plain, reversed_sphere, reversed_ellipsoid, cut_ellipsoid = data["shapes"]
    assert plain["type"] == reversed_sphere["type"] == hemisphere["type"] == "sphere" and "flip_normals" not in plain
    assert reversed_sphere["flip_normals"] is True
    assert (hemisphere["z_min"], hemisphere["z_max"]) == (-1.0, 0.0)
    assert reversed_ellipsoid["type"] == cut_ellipsoid["type"] == "mesh"
    mesh = importer.meshes[Path(reversed_ellipsoid["file"]).name]
    a, b, c = (mesh.vertices[mesh.faces[:, i]] for i in range(3))
    assert np.all(np.einsum("ij,ij->i", np.cross(b - a, c - a), a + b + c) < 0)
    toml = tmp_path / "out" / "scene.toml"
    import_pbrt(_write(tmp_path, 'Shape "sphere" "float radius" 2 "float zmax" 0\n', name="h.pbrt"), toml)
    (shape,) = load_scene(toml).shapes
    assert shape.analytic.area() == pytest.approx(2 * math.pi * 4, rel=1e-9)


def test_loop_subdivision_refines_the_control_mesh(tmp_path):
    """Each Loop step adds a vertex per edge and splits each triangle in four (an octahedron: 6 vertices, 12 edges,
    8 faces -> 18, 48, 32 -> 66 vertices, 128 faces); the surface stays inside the control mesh's hull and, closed
    and convex, faces outward."""
    body = """Shape "loopsubdiv" "integer levels" 2
  "point3 P" [1 0 0  -1 0 0  0 1 0  0 -1 0  0 0 1  0 0 -1]
  "integer indices" [0 2 4  2 1 4  1 3 4  3 0 4  2 0 5  1 2 5  3 1 5  0 3 5]
"""
    data, importer = pbrt_scene_data(_write(tmp_path, body))
    mesh = importer.meshes[Path(data["shapes"][0]["file"]).name]
    assert (len(mesh.vertices), len(mesh.faces)) == (66, 128)
    assert np.abs(mesh.vertices).sum(axis=1).max() <= 1 + 1e-12  # inside the octahedron |x| + |y| + |z| <= 1
    a, b, c = (mesh.vertices[mesh.faces[:, i]] for i in range(3))
    assert np.all(np.einsum("ij,ij->i", np.cross(b - a, c - a), a + b + c) > 0)
    assert np.all(np.einsum("ij,ij->i", mesh.normals, mesh.vertices) > 0)
    assert any("loopsubdiv refined 2 times" in note for note in importer.notes)


def _cube(half: float) -> str:
    """A pbrt trianglemesh of the cube [-half, half]³ with outward windings (checked here)."""
    corners = np.array([[x, y, z] for z in (-half, half) for y in (-half, half) for x in (-half, half)])
    quads = [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]
    faces = [tri for a, b, c, d in quads for tri in ((a, b, c), (a, c, d))]
    for a, b, c in faces:
        assert (
            np.dot(np.cross(corners[b] - corners[a], corners[c] - corners[a]), corners[a] + corners[b] + corners[c]) > 0
        )
    points = " ".join(f"{v:g}" for v in corners.ravel())
    return (
        f'Shape "trianglemesh" "point3 P" [{points}] "integer indices" [{" ".join(str(i) for f in faces for i in f)}]\n'
    )


def test_media_and_attributes_map_onto_interiors(tmp_path):
    body = """MakeNamedMedium "ink" "string type" "homogeneous" "rgb sigma_a" [0.5 1 2] "float scale" 3 "float g" 0.2
MakeNamedMedium "skin" "string type" "homogeneous" "string preset" "Skin1"
MakeNamedMedium "fog" "string type" "homogeneous"
Attribute "shape" "float radius" 2
AttributeBegin
  MediumInterface "ink" ""
  Material "interface"
  Shape "sphere"
  MediumInterface "skin" "fog"
  Material "dielectric" "float eta" 1.4
  Shape "sphere" "float radius" 3
AttributeEnd
MediumInterface "fog" ""
Shape "sphere"
"""
    data, importer = pbrt_scene_data(_write(tmp_path, body))
    ink, skin, fog = data["shapes"]
    assert "material" not in ink and ink["interior"] == {
        "sigma_a": {"rgb": [0.5, 1.0, 2.0]},
        "sigma_s": {"value": 1.0},  # pbrt's default coefficient is 1, spectrace's 0
        "scale": 3.0,
        "g": 0.2,
    }
    assert ink["transform"][0] == {"scale": 2.0} and skin["transform"][0] == {"scale": 3.0}  # Attribute default
    assert skin["interior"] == {"preset": "skin1"} and data["materials"][skin["material"]]["type"] == "dielectric"
    assert fog["interior"] == {"sigma_a": {"value": 1.0}, "sigma_s": {"value": 1.0}}
    assert any("outside medium 'fog' not imported" in warning for warning in importer.warnings)


def test_absorbing_medium_transmits_exp_minus_sigma_d(tmp_path, device):
    """Through a cube of side 2 filled with σa = 0.5, σs = 0 behind an index-matched boundary (pbrt's interface
    material), a light of luminance 1 shows exp(-0.5 · 2)."""
    header = """LookAt 0 0 -5  0 0 0  0 1 0
Camera "perspective" "float fov" 5
Film "rgb" "integer xresolution" 4 "integer yresolution" 4
WorldBegin
"""
    # AreaLightSource holds until AttributeEnd: the light's own block keeps it off the cube.
    body = 'AttributeBegin\nAreaLightSource "diffuse" "rgb L" [1 1 1] "bool twosided" true\n'
    body += 'Shape "bilinearmesh" "point3 P" [-5 -5 3  5 -5 3  -5 5 3  5 5 3]\nAttributeEnd\n'
    body += 'MakeNamedMedium "ink" "string type" "homogeneous" "spectrum sigma_a" [360 0.5 830 0.5]\n'
    body += '  "spectrum sigma_s" [360 0 830 0]\nMediumInterface "ink" ""\nMaterial "interface"\n' + _cube(1.0)
    y = _render_y(load_pbrt_scene(_write(tmp_path, body, header)), device, 16)
    standard_error = y.std(ddof=1) / math.sqrt(y.size)
    assert abs(y.mean() - math.exp(-1.0)) <= 4 * standard_error + 2e-3, (y.mean(), math.exp(-1.0), standard_error)


def test_plymesh_quads_normals_uv_and_gzip(tmp_path):
    """A PLY quad (split in two triangles) with normals facing -z against its +z winding, and uv as stored: pbrt
    turns the front toward the normals; the same file gzipped reads the same."""
    import gzip

    ply = """ply
format ascii 1.0
element vertex 4
property float x
property float y
property float z
property float nx
property float ny
property float nz
property float u
property float v
element face 1
property list uchar int vertex_indices
end_header
0 0 0 0 0 -1 0 0
1 0 0 0 0 -1 1 0
1 1 0 0 0 -1 1 1
0 1 0 0 0 -1 0 1
4 0 1 2 3
"""
    (tmp_path / "quad.ply").write_text(ply)
    (tmp_path / "quad.ply.gz").write_bytes(gzip.compress(ply.encode()))
    body = 'Shape "plymesh" "string filename" "quad.ply"\nShape "plymesh" "string filename" "quad.ply.gz"\n'
    data, importer = pbrt_scene_data(_write(tmp_path, body))
    meshes = [importer.meshes[Path(shape["file"]).name] for shape in data["shapes"]]
    for mesh in meshes:
        assert len(mesh.faces) == 2
        a, b, c = (mesh.vertices[mesh.faces[:, i]] for i in range(3))
        assert np.all(np.cross(b - a, c - a)[:, 2] < 0)  # toward the normals
        uv_of = {tuple(v): tuple(uv) for v, uv in zip(mesh.vertices, mesh.uvs, strict=True)}
        assert uv_of == {(0, 0, 0): (0, 0), (1, 0, 0): (1, 0), (1, 1, 0): (1, 1), (0, 1, 0): (0, 1)}
    np.testing.assert_array_equal(meshes[0].faces, meshes[1].faces)


def test_written_meshes_keep_normals_and_uv(tmp_path):
    """Through the PLY file the importer writes: the normals turned with the scene's mirror (x -> -x), v as
    spectrace stores it (1 - v)."""
    body = 'Shape "trianglemesh" "point3 P" [0 0 0  1 0 0  0 1 0] "normal N" [0 0 1  0.6 0 0.8  0 0.6 0.8]\n'
    body += '  "point2 uv" [0 0  1 0  0 1]\n'
    (shape,) = load_pbrt_scene(_write(tmp_path, body)).shapes
    np.testing.assert_allclose(shape.mesh.vertices, [[0, 0, 0], [-1, 0, 0], [0, 1, 0]], atol=1e-7)
    np.testing.assert_allclose(shape.mesh.normals, [[0, 0, 1], [-0.6, 0, 0.8], [0, 0.6, 0.8]], atol=1e-7)
    np.testing.assert_allclose(shape.mesh.uvs, [[0, 1], [1, 1], [0, 0]], atol=1e-7)


def test_unsupported_parameters_warn_and_strict_refuses(tmp_path):
    body = 'PixelFilter "sinc"\nShape "sphere" "float radius" 1 "float frobs" 3\n' + PLANE
    path = _write(tmp_path, body)
    warnings, _ = import_pbrt(path, tmp_path / "a.toml")
    assert f'{path}:6: Shape "sphere": parameter "float frobs" not imported' in warnings
    assert any(w.startswith(f"{path}:5: pixel filter 'sinc' not imported") for w in warnings)
    # The same message at many lines is one warning.
    body = "".join(f'Shape "sphere" "float frobs" {i}\n' for i in range(50)) + 'LightSource "point"\n'
    warnings, _ = import_pbrt(_write(tmp_path, body), tmp_path / "c.toml")
    assert warnings == [f'{path}:5: Shape "sphere": parameter "float frobs" not imported (and 49 more like it)']
    with pytest.raises(SpectraceError, match="frobs"):
        import_pbrt(path, tmp_path / "b.toml", strict=True)
    assert not (tmp_path / "b.toml").exists()


@pytest.mark.parametrize(
    ("body", "line", "message"),
    [
        ('Material "mix"\nShape "sphere"\n', 5, 'Material "mix" needs "string materials" naming two materials'),
        ('Material "thindielectric" "spectrum eta" "glass-BK7"\nShape "sphere"\n', 5, "eta must be a number"),
        ('Material "coatedconductor" "float interface.eta" 5\nShape "sphere"\n', 5, "ior must lie in [1, 4]"),
        ('Material "coatedconductor" "integer nsamples" 0\nShape "sphere"\n', 5, "must be an integer >= 1"),
        ('Shape "hyperboloid"\n', 5, "shape 'hyperboloid'"),
        ('Shape "curve"\n', 5, 'a curve needs "point3 P"'),
        ('Shape "loopsubdiv" "point3 P" [0 0 0  1 0 0  0 1 0] "integer indices" [0 1 3]\n', 5, "whole numbers below 3"),
        ('LightSource "sunsky"\n', 5, "light 'sunsky'"),
        # pbrt-v4 resolves named materials after reading the whole file: the shape using one is at fault.
        ('NamedMaterial "x"\nShape "sphere"\n', 6, "which no MakeNamedMaterial defined"),
        ('Material "dielectric" "rgb eta" [1.5 1.5 1.5]\nShape "sphere"\n', 5, "spectrace takes a number or a named"),
    ],
)
def test_what_spectrace_cannot_represent_is_refused_at_its_line(tmp_path, body, line, message):
    path = _write(tmp_path, body)
    with pytest.raises(SpectraceError) as failure:
        pbrt_scene_data(path)
    assert failure.value.where == f"{path}:{line}"
    assert message in failure.value.message


def test_command_prints_warnings_and_strict_fails_in_one_line(tmp_path, monkeypatch, capsys):
    # The first Material is replaced before any shape uses it: pbrt never reads it, nor is it reported.
    body = 'Material "diffuse" "float frobs" 1\nMaterial "diffuse" "rgb reflectance" [.5 .5 .5] "float sigma" 20\n'
    path = _write(tmp_path, body + PLANE)
    out = tmp_path / "x.toml"
    code, stderr = run_in_process(monkeypatch, capsys, ["import-pbrt", str(path), "-o", str(out)])
    assert code == 0 and out.is_file()
    lines = stderr.strip().splitlines()
    assert f'warning: {path}:6: Material "diffuse": parameter "float sigma" not imported' in lines
    assert not any("frobs" in line for line in lines)
    assert lines[-1] == f"wrote {out}"
    code, stderr = run_in_process(monkeypatch, capsys, ["import-pbrt", str(path), "-o", str(out), "--strict"])
    assert code != 0 and len(stderr.strip().splitlines()) == 1 and "sigma" in stderr


def test_realistic_camera_without_its_lens_file_is_one_line(tmp_path, monkeypatch, capsys):
    path = _write(tmp_path, PLANE, HEADER.replace('"perspective"', '"realistic"'))
    code, stderr = run_in_process(monkeypatch, capsys, ["import-pbrt", str(path), "-o", str(tmp_path / "x.toml")])
    assert code != 0
    assert stderr.strip() == f'error: {path}:2: the realistic camera needs "string lensfile" (as pbrt-v4)'


SQUARE_PLY_WITHOUT_UV = """ply
format ascii 1.0
element vertex 4
property float x
property float y
property float z
element face 2
property list uchar int vertex_indices
end_header
-9 -9 0
9 -9 0
9 9 0
-9 9 0
3 0 1 2
3 0 2 3
"""
TEXTURED_MIX = """Texture "white" "spectrum" "checkerboard" "rgb tex1" [1 1 1] "rgb tex2" [1 1 1]
MakeNamedMaterial "textured" "string type" "diffuse" "texture reflectance" "white"
MakeNamedMaterial "black" "string type" "diffuse" "rgb reflectance" [0 0 0]
MakeNamedMaterial "inner" "string type" "mix" "string materials" ["textured" "black"] "float amount" AMOUNT
MakeNamedMaterial "outer" "string type" "mix" "string materials" ["black" "inner"] "float amount" 0.5
"""


@pytest.mark.parametrize("material", ["inner", "outer"])
def test_a_plymesh_without_uv_under_a_mix_with_a_textured_part_gets_pbrt_default_uv(material, tmp_path):
    """Rendering a mix reads the texture coordinates wherever one of its materials (at any depth) is textured, so a
    mesh without uv under it gets pbrt's default ones, (0, 0), (1, 0), (1, 1) at each triangle's corners, as
    under a textured material of its own (pbrt-v4's Triangle does the same), instead of a TOML that fails to load."""
    from spectrace.scene import load_scene

    (tmp_path / "square.ply").write_text(SQUARE_PLY_WITHOUT_UV)
    body = TEXTURED_MIX.replace("AMOUNT", "0.5") + f'NamedMaterial "{material}"\n'
    body += 'Shape "plymesh" "string filename" "square.ply"\n'
    toml = tmp_path / "out" / "scene.toml"
    import_pbrt(_write(tmp_path, body), toml)
    (shape,) = load_scene(toml).shapes
    # Per triangle, each corner (x mirrored by the import, v stored as 1 - v) with the uv pbrt gives it.
    mesh = shape.mesh
    triangles = {
        frozenset((tuple(np.round(mesh.vertices[i], 6)), tuple(mesh.uvs[i])) for i in face) for face in mesh.faces
    }
    assert triangles == {
        frozenset({((9, -9, 0), (0, 1)), ((-9, -9, 0), (1, 1)), ((-9, 9, 0), (1, 0))}),
        frozenset({((9, -9, 0), (0, 1)), ((-9, 9, 0), (1, 1)), ((9, 9, 0), (1, 0))}),
    }


# ---------------------------------------------------------------- renders


def _render_y(scene, device, spp: int) -> np.ndarray:
    from spectrace.engine.renderer import Renderer

    renderer = Renderer(scene, device)
    renderer.render(spp=spp)
    return renderer.image().xyz[..., 1].astype(np.float64)


def test_point_light_over_a_diffuse_plane_matches_the_closed_form(tmp_path, device):
    """L = ρ/π · I cosθ / r², with pbrt's I of luminance `scale`: straight below a light at height h, ρ k / (π h²)."""
    header = """LookAt 0 0 6  0 0 0  0 1 0
Camera "perspective" "float fov" 1
Film "rgb" "integer xresolution" 4 "integer yresolution" 4
Integrator "path" "integer maxdepth" 1
WorldBegin
"""
    body = 'LightSource "point" "point3 from" [0 0 2] "blackbody I" 4000 "float scale" 3\n'
    body += 'Material "diffuse" "spectrum reflectance" [360 0.5 830 0.5]\n' + PLANE
    y = _render_y(load_pbrt_scene(_write(tmp_path, body, header)), device, 64)
    # The image spans 6 tan(0.5°) = 0.05 around the axis: r² and cosθ differ from h² and 1 by under 0.1 %. The
    # pixels vary only by the sampled wavelengths: independent estimates of the same value.
    expected = 0.5 / math.pi * 3.0 / 2.0**2
    standard_error = y.std(ddof=1) / math.sqrt(y.size)
    assert abs(y.mean() - expected) <= 4 * standard_error + 1e-3 * expected, (y.mean(), expected, standard_error)


@pytest.mark.parametrize(("mirror", "bright_side"), [("", "right"), ("Scale -1 1 1\n", "left")])
def test_image_right_is_the_camera_plus_x(tmp_path, device, mirror, bright_side):
    """pbrt's raster x grows with camera-space +x: a light at world +x (camera looking along +z, up +y) is on the
    right of the image; `Scale -1 1 1` before LookAt (as exporters write) moves it to the left."""
    header = (
        mirror
        + """LookAt 0 0 0  0 0 1  0 1 0
Camera "perspective" "float fov" 60
Film "rgb" "integer xresolution" 8 "integer yresolution" 4
WorldBegin
"""
    )
    body = 'AreaLightSource "diffuse" "rgb L" [1 1 1] "bool twosided" true\n'
    body += 'Shape "bilinearmesh" "point3 P" [0.5 -0.5 3  1.5 -0.5 3  0.5 0.5 3  1.5 0.5 3]\n'
    y = _render_y(load_pbrt_scene(_write(tmp_path, body, header)), device, 4)
    left, right = y[:, :4].sum(), y[:, 4:].sum()
    assert (right if bright_side == "right" else left) > 0 and (left if bright_side == "right" else right) == 0


MITSUBA_XML = """<scene version="3.0.0">
<sensor type="perspective"><float name="fov" value="45"/>
  <transform name="to_world"><lookat origin="0, 1, 4" target="0, 1, 0" up="0, 1, 0"/></transform>
  <film type="hdrfilm"><integer name="width" value="16"/><integer name="height" value="16"/>
    <rfilter type="box"/></film></sensor>
<integrator type="path"><integer name="max_depth" value="4"/></integrator>
<shape type="rectangle"><transform name="to_world"><scale value="2"/><rotate x="1" angle="-90"/></transform>
  <bsdf type="diffuse"><rgb name="reflectance" value="0.7, 0.7, 0.7"/></bsdf></shape>
<shape type="rectangle"><transform name="to_world"><scale value="2"/><translate x="0" y="1" z="-1"/></transform>
  <bsdf type="diffuse"><rgb name="reflectance" value="0.2, 0.6, 0.2"/></bsdf></shape>
<shape type="rectangle"><transform name="to_world"><scale value="0.5"/><rotate x="1" angle="90"/>
  <translate x="-0.5" y="2.5" z="0.5"/></transform>
  <bsdf type="diffuse"><rgb name="reflectance" value="0.5, 0.5, 0.5"/></bsdf>
  <emitter type="area"><rgb name="radiance" value="8, 8, 8"/></emitter></shape>
<shape type="sphere"><point name="center" x="0.7" y="0.5" z="0"/><float name="radius" value="0.5"/>
  <bsdf type="diffuse"><rgb name="reflectance" value="0.8, 0.2, 0.2"/></bsdf></shape>
</scene>
"""
# The same scene in pbrt-v4's terms: `Scale -1 1 1` makes pbrt's left-handed camera image the scene as Mitsuba's
# does; rectangles are bilinear patches (p00, p10, p01, p11) facing (p10 - p00) × (p01 - p00); maxdepth counts
# bounces (Mitsuba's max_depth 4 = 3 bounces).
PBRT_SCENE = """Scale -1 1 1
LookAt 0 1 4  0 1 0  0 1 0
Camera "perspective" "float fov" 45
Film "rgb" "integer xresolution" 16 "integer yresolution" 16
PixelFilter "box"
Integrator "volpath" "integer maxdepth" 3
WorldBegin
Material "diffuse" "rgb reflectance" [0.7 0.7 0.7]
Shape "bilinearmesh" "point3 P" [-2 0 2  2 0 2  -2 0 -2  2 0 -2]
Material "diffuse" "rgb reflectance" [0.2 0.6 0.2]
Shape "bilinearmesh" "point3 P" [-2 -1 -1  2 -1 -1  -2 3 -1  2 3 -1]
AttributeBegin
  Translate -0.5 2.5 0.5
  AreaLightSource "diffuse" "rgb L" [8 8 8]
  Material "diffuse" "rgb reflectance" [0.5 0.5 0.5]
  Shape "bilinearmesh" "point3 P" [-0.5 0 -0.5  0.5 0 -0.5  -0.5 0 0.5  0.5 0 0.5]
AttributeEnd
AttributeBegin
  Translate 0.7 0.5 0
  Material "diffuse" "rgb reflectance" [0.8 0.2 0.2]
  Shape "sphere" "float radius" 0.5
AttributeEnd
"""


def test_scene_renders_as_the_same_scene_imported_from_mitsuba_xml(tmp_path, device):
    from spectrace.engine.renderer import Renderer
    from spectrace.interop.mitsuba import load_mitsuba_scene

    (tmp_path / "scene.xml").write_text(MITSUBA_XML)
    (tmp_path / "scene.pbrt").write_text(PBRT_SCENE)
    from_xml = load_mitsuba_scene(tmp_path / "scene.xml").with_overrides(seed=1)
    from_pbrt = load_pbrt_scene(tmp_path / "scene.pbrt").with_overrides(seed=2)
    assert from_pbrt.max_depth == from_xml.max_depth == 4
    ours = spectrace_replicas(Renderer(from_pbrt, device), replicas=8, replica_spp=24)
    theirs = spectrace_replicas(Renderer(from_xml, device), replicas=8, replica_spp=24)
    assert ours[..., 1].mean() > 0.05  # the scene is lit
    assert_replicas_agree(ours, theirs, block=4)


@pytest.mark.peer
def test_scene_renders_as_mitsuba_renders_the_same_scene(tmp_path, device, mitsuba_scalar_spectral):
    """The pbrt scene imported and rendered by spectrace against Mitsuba 3 (scalar_spectral) rendering the XML."""
    from spectrace.engine.renderer import Renderer
    from spectrace.spectral import xyz_to_linear_srgb

    mi = mitsuba_scalar_spectral
    (tmp_path / "scene.xml").write_text(MITSUBA_XML)
    (tmp_path / "scene.pbrt").write_text(PBRT_SCENE)
    replicas, replica_spp = 16, 40
    mitsuba_scene = mi.load_file(str(tmp_path / "scene.xml"))
    by_mitsuba = np.stack([np.array(mi.render(mitsuba_scene, spp=replica_spp, seed=seed)) for seed in range(replicas)])
    ours = spectrace_replicas(Renderer(load_pbrt_scene(tmp_path / "scene.pbrt"), device), replicas, replica_spp)
    assert by_mitsuba.mean() > 0.05
    assert_replicas_agree(xyz_to_linear_srgb(ours), by_mitsuba, block=4)


# ---------------------------------------------------------------- image infinite lights


def test_equal_area_square_covers_the_sphere_uniformly():
    """Clarberg's map is equal-area: a uniform grid on the square gives z uniform on [-1, 1] (mean 0, mean z² 1/3);
    its centre is +z, the corners -z, the edge midpoints the ±x and ±y axes; sphere_to_square inverts it."""
    from spectrace.interop.pbrt.envmap import sphere_to_square, square_to_sphere

    side = 200
    grid = (np.stack(np.meshgrid(np.arange(side), np.arange(side)), -1).reshape(-1, 2) + 0.5) / side
    z = square_to_sphere(grid)[:, 2]
    assert abs(z.mean()) < 1e-3 and z.var() == pytest.approx(1 / 3, abs=1e-3)
    special = square_to_sphere(np.array([[0.5, 0.5], [0.0, 0.0], [1.0, 0.5], [0.5, 1.0], [0.0, 0.5]]))
    np.testing.assert_allclose(special, [[0, 0, 1], [0, 0, -1], [1, 0, 0], [0, 1, 0], [-1, 0, 0]], atol=1e-12)
    directions = square_to_sphere(grid)
    np.testing.assert_allclose(sphere_to_square(directions), grid, atol=1e-9)


def _square_map(path: Path, side: int, upper: float, lower: float) -> None:
    """A square equal-area map: `upper` where the texel's direction has z > 0, `lower` elsewhere (grey)."""
    from spectrace.interop.pbrt.envmap import square_to_sphere
    from spectrace.io.exr import write_exr

    grid = (np.stack(np.meshgrid(np.arange(side), np.arange(side)), -1).reshape(-1, 2) + 0.5) / side
    values = np.where(square_to_sphere(grid)[:, 2] > 0, upper, lower).reshape(side, side, 1)
    write_exr(path, np.repeat(values, 3, axis=2).astype(np.float32), None, {})


def test_image_infinite_light_becomes_a_latitude_longitude_map(tmp_path):
    _square_map(tmp_path / "sky.exr", 64, 2.0, 0.0)
    # pbrt scenes with y up turn the map's +z to +y.
    body = 'AttributeBegin\nRotate -90 1 0 0\nLightSource "infinite" "string filename" "sky.exr" "float scale" 3\n'
    body += "AttributeEnd\n" + PLANE
    data, importer = pbrt_scene_data(_write(tmp_path, body), tmp_path / "out.toml")
    (light,) = data["lights"]
    assert light["type"] == "envmap" and light["scale"] == 3.0
    image = importer.files[Path(light["file"]).name]
    assert image.shape == (64, 128, 3)
    # Rows run from the zenith (θ = 0) down: the upper half is the sky, the lower half the dark ground (the rows
    # within 10° of the horizon blend the two: the square's texels along its horizon diamond are filtered).
    assert np.all(image[:28] == 2.0) and np.all(image[36:] == 0.0)


def test_environment_over_a_diffuse_plane_matches_the_closed_form(tmp_path, device):
    """Under a uniform sky of radiance L (pbrt: RGB texels c, luminance c × scale) a Lambertian plane reflects ρ L."""
    _square_map(tmp_path / "sky.exr", 32, 1.5, 1.5)
    header = HEADER.replace('"float fov" 30', '"float fov" 5').replace(
        "WorldBegin", 'Integrator "path" "integer maxdepth" 1\nWorldBegin'
    )
    body = 'LightSource "infinite" "string filename" "sky.exr" "float scale" 2\n'
    body += 'Material "diffuse" "spectrum reflectance" [360 0.4 830 0.4]\n' + PLANE
    y = _render_y(load_pbrt_scene(_write(tmp_path, body, header)), device, 32)
    expected = 0.4 * 1.5 * 2.0
    standard_error = y.std(ddof=1) / math.sqrt(y.size)
    assert abs(y.mean() - expected) <= 4 * standard_error + 2e-3 * expected, (y.mean(), expected, standard_error)


# ---------------------------------------------------------------- textures

TEXTURED_QUAD = """LookAt 0 0 -3  0 0 0  0 1 0
Camera "perspective" "float fov" 60
Film "rgb" "integer xresolution" 8 "integer yresolution" 8
Integrator "path" "integer maxdepth" 1
WorldBegin
LightSource "distant" "point3 from" [0 0 -1] "point3 to" [0 0 0]
"""
QUAD = (
    'Shape "trianglemesh" "point3 P" [-1 -1 0  1 -1 0  1 1 0  -1 1 0] "integer indices" [0 1 2 0 2 3]\n'
    '  "point2 uv" [0 0  1 0  1 1  0 1]\n'
)


def _quadrant_colours(scene, device) -> dict[str, np.ndarray]:
    """Linear sRGB of the quad's four quadrants as they appear in the image (the quad spans pixels 1..6)."""
    from spectrace.engine.renderer import Renderer
    from spectrace.spectral import xyz_to_linear_srgb

    renderer = Renderer(scene, device)
    renderer.render(spp=4)
    rgb = xyz_to_linear_srgb(renderer.image().xyz.astype(np.float64))
    return {
        "upper left": rgb[2:4, 2:4].mean(axis=(0, 1)),
        "upper right": rgb[2:4, 4:6].mean(axis=(0, 1)),
        "lower left": rgb[4:6, 2:4].mean(axis=(0, 1)),
        "lower right": rgb[4:6, 4:6].mean(axis=(0, 1)),
    }


def _redder(colour: np.ndarray) -> bool:
    return bool(colour[0] > 3 * colour[2])


def test_image_texture_is_upright_as_in_pbrt(tmp_path, device):
    """pbrt looks an image up at (s, 1 - t): its first row lies along t = 1, the quad's top (uv (0, 0) at its lower
    left, world +x to the image's right: pbrt's camera +x)."""
    from PIL import Image

    Image.fromarray(np.array([[[255, 0, 0]] * 2, [[0, 0, 255]] * 2], np.uint8)).save(tmp_path / "rb.png")
    body = 'Texture "t" "spectrum" "imagemap" "string filename" "rb.png" "string filter" "point"\n'
    body += 'Material "diffuse" "texture reflectance" "t"\n' + QUAD
    colours = _quadrant_colours(load_pbrt_scene(_write(tmp_path, body, TEXTURED_QUAD)), device)
    assert _redder(colours["upper left"]) and _redder(colours["upper right"])
    assert not _redder(colours["lower left"]) and not _redder(colours["lower right"])


def test_checkerboard_starts_with_tex1_at_the_origin(tmp_path, device):
    """pbrt's checkerboard takes tex1 where floor(s) + floor(t) is even: the quadrant at uv (0, 0) (lower left)."""
    body = 'Texture "c" "spectrum" "checkerboard" "float uscale" 2 "float vscale" 2\n'
    body += '  "rgb tex1" [0.8 0.05 0.05] "rgb tex2" [0.05 0.05 0.8]\nMaterial "diffuse" "texture reflectance" "c"\n'
    colours = _quadrant_colours(load_pbrt_scene(_write(tmp_path, body + QUAD, TEXTURED_QUAD)), device)
    assert _redder(colours["lower left"]) and _redder(colours["upper right"])
    assert not _redder(colours["lower right"]) and not _redder(colours["upper left"])


def test_scaled_image_texture_is_a_linear_copy(tmp_path):
    """`scale` over an 8-bit sRGB image: the copy holds the decoded values (IEC 61966-2-1) times the scale."""
    from PIL import Image

    from spectrace.io.images import read_texture_image

    codes = np.array([[[0, 64, 128], [192, 255, 10]]], np.uint8)
    Image.fromarray(codes).save(tmp_path / "img.png")
    body = 'Texture "i" "spectrum" "imagemap" "string filename" "img.png"\n'
    body += 'Texture "s" "spectrum" "scale" "texture tex" "i" "float scale" 0.5\n'
    body += 'Material "diffuse" "texture reflectance" "s"\n' + QUAD
    toml = tmp_path / "out" / "scene.toml"
    import_pbrt(_write(tmp_path, body), toml)
    data, _ = pbrt_scene_data(tmp_path / "scene.pbrt", toml)
    (texture,) = data["textures"].values()
    values, encoded = read_texture_image(toml.parent / texture["file"], "x")
    c = codes / 255.0
    linear = np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)
    assert not encoded
    np.testing.assert_allclose(values, 0.5 * linear, rtol=1e-6, atol=1e-7)


def test_meshes_without_uv_get_pbrt_default_coordinates(tmp_path):
    """pbrt gives a triangle without uv (0, 0), (1, 0), (1, 1) at its corners, a bilinear patch (0, 0)..(1, 1)."""
    from spectrace.scene import load_scene

    body = 'Texture "c" "spectrum" "checkerboard"\nMaterial "diffuse" "texture reflectance" "c"\n'
    body += 'Shape "trianglemesh" "point3 P" [0 0 0  2 0 0  2 2 0]\n'
    body += 'Shape "bilinearmesh" "point3 P" [0 0 1  2 0 1  0 2 1  2 2 1]\n'
    toml = tmp_path / "out" / "scene.toml"
    import_pbrt(_write(tmp_path, body), toml)
    triangle, patch = load_scene(toml).shapes
    # spectrace stores v' = 1 - v; the scene is mirrored in x (pbrt's camera handedness), which keeps the corners.
    uv_of = {tuple(np.round(v, 6)): tuple(uv) for v, uv in zip(triangle.mesh.vertices, triangle.mesh.uvs, strict=True)}
    assert uv_of == {(0, 0, 0): (0, 1), (-2, 0, 0): (1, 1), (-2, 2, 0): (1, 0)}
    uv_of = {tuple(np.round(v, 6)): tuple(uv) for v, uv in zip(patch.mesh.vertices, patch.mesh.uvs, strict=True)}
    assert uv_of == {(0, 0, 1): (0, 1), (-2, 0, 1): (1, 1), (0, 2, 1): (0, 0), (-2, 2, 1): (1, 0)}


def test_a_textured_mix_on_a_mesh_without_uv_renders_the_mixed_albedo(tmp_path, device):
    """Furnace: under a uniform sky, a diffuse plane of albedo a seen from its front is a times the sky (the plane
    shadows nothing it sees). pbrt-v4's mix takes its second material with probability `amount`, so the plymesh
    without uv under mix(black, mix(white checkerboard, black, 3/4), 1/2) has albedo 1/2 · 1/4 = 1/8; the white
    plane (albedo 1) gives the sky itself. Their ratio is held to 1/8 within 4 standard errors of the mix's pixel
    mean (the white plane's estimate has next to no variance: every sample is the sky)."""
    from spectrace.scene import load_scene

    (tmp_path / "square.ply").write_text(SQUARE_PLY_WITHOUT_UV)
    sky = 'LightSource "infinite" "rgb L" [1 1 1]\n'
    means = {}
    for name, material in [
        ("mix", 'NamedMaterial "outer"\n'),
        ("white", 'Material "diffuse" "rgb reflectance" [1 1 1]\n'),
    ]:
        body = (
            sky + TEXTURED_MIX.replace("AMOUNT", "0.75") + material + 'Shape "plymesh" "string filename" "square.ply"\n'
        )
        toml = tmp_path / name / "scene.toml"
        import_pbrt(_write(tmp_path, body, name=f"{name}.pbrt"), toml)
        y = _render_y(load_scene(toml).with_overrides(seed=7), device, spp=64)
        means[name] = (y.mean(), y.std(ddof=1) / math.sqrt(y.size))
    (mixed, error), (white, _) = means["mix"], means["white"]
    assert white > 0 and abs(mixed / white - 1 / 8) < 4 * error / white, (means, mixed / white)
