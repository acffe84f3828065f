"""Mitsuba 3 XML read as Mitsuba reads it: $parameters everywhere, <default>, <include>, <path>, <ref> to top-level
objects, 0.x files upgraded, envmap, the moment integrator, conductors given in RGB, properties spectrace does not
know reported. Checked against Mitsuba 3 itself where it is installed (transforms, upgraded values, the envmap's
orientation, the RGB conductor's colour) and against closed forms."""

import math
from pathlib import Path

import numpy as np
import pytest

from spectrace.errors import SpectraceError
from spectrace.geometry.transforms import transform_matrix
from spectrace.interop.mitsuba import import_mitsuba, load_mitsuba_scene, mitsuba_scene_data
from spectrace.interop.mitsuba.tree import camel_to_snake
from spectrace.spectral import reflectance_to_xyz, xyz_to_linear_srgb
from spectrace.spectral.illuminants import cie_illuminant
from spectrace.spectral.spectrum import Spectrum
from spectrace.spectral.uplift import normal_incidence_reflectance

DATA = Path(__file__).resolve().parents[1] / "data" / "mitsuba"
SENSOR = """<sensor type="perspective"><float name="fov" value="45"/>
    <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="6"/></film></sensor>"""
# Gold as RGB renderers take it (the values Mitsuba's and pbrt's RGB scenes use for Au).
GOLD_ETA, GOLD_K = (0.143119, 0.374957, 1.44248), (3.98316, 2.38572, 1.60322)


def _write(folder: Path, body: str, name: str = "scene.xml", version: str = "3.0.0", sensor: str = SENSOR) -> Path:
    path = folder / name
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(f'<scene version="{version}">\n{sensor}\n{body}\n</scene>\n')
    return path


# ---------------------------------------------------------------- $parameters


def test_parameters_are_substituted_in_every_attribute(tmp_path):
    (tmp_path / "meshes").mkdir()
    (tmp_path / "meshes" / "triangle.obj").write_bytes((DATA / "triangle.obj").read_bytes())
    path = _write(
        tmp_path,
        """
        <default name="integrator" value="path"/>
        <default name="shape" value="obj"/>
        <default name="prop" value="max_depth"/>
        <default name="mat" value="white"/>
        <default name="dir" value="meshes"/>
        <default name="depth" value="3"/>
        <integrator type="$integrator"><integer name="$prop" value="$depth"/></integrator>
        <bsdf type="diffuse" id="$mat"><float name="reflectance" value="0.$depth"/></bsdf>
        <shape type="$shape"><string name="filename" value="$dir/triangle.obj"/><ref id="$mat"/></shape>""",
    )
    data, _ = mitsuba_scene_data(path)
    assert data["integrator"] == {"type": "path", "max_depth": 3}
    assert data["materials"]["white"] == {"type": "diffuse", "reflectance": {"value": 0.3}, "two_sided": False}
    assert data["shapes"][0]["file"] == "meshes/triangle.obj"
    # -D wins over <default>, as Mitsuba's -D does; \$ is a literal dollar.
    data, _ = mitsuba_scene_data(path, parameters={"depth": "5"})
    assert data["integrator"]["max_depth"] == 5 and data["materials"]["white"]["reflectance"] == {"value": 0.5}


def test_longer_parameter_names_are_substituted_first(tmp_path):
    path = _write(
        tmp_path,
        '<default name="res" value="4"/><default name="resx" value="9"/>'
        '<integrator type="path"><integer name="max_depth" value="$resx"/></integrator><shape type="cube"/>',
    )
    assert mitsuba_scene_data(path)[0]["integrator"]["max_depth"] == 9


def test_an_undefined_parameter_names_the_file_and_line(tmp_path):
    inner = _write(tmp_path, '<shape type="$kind"/>', name="parts/inner.xml", sensor="")
    path = _write(tmp_path, f'<include filename="{inner.relative_to(tmp_path)}"/>')
    with pytest.raises(SpectraceError) as caught:
        mitsuba_scene_data(path)
    message = str(caught.value)
    assert message.startswith(f"{inner}: shape@type: undefined parameter $kind") and "(line 3)" in message, message
    assert "\n" not in message


# ---------------------------------------------------------------- include, path, ref


def test_include_path_and_references_to_top_level_objects(tmp_path):
    (tmp_path / "assets").mkdir()
    (tmp_path / "assets" / "triangle.obj").write_bytes((DATA / "triangle.obj").read_bytes())
    _write(
        tmp_path,
        """
        <emitter type="area" id="lamp"><rgb name="radiance" value="2, 2, 2"/></emitter>
        <bsdf type="diffuse" id="grey"><float name="reflectance" value="0.25"/></bsdf>""",
        name="parts/lights.xml",
        sensor="",
    )
    # An included file whose root is one object: it is added where the include stands, under its name.
    (tmp_path / "parts" / "red.xml").write_text(
        '<bsdf version="3.0.0" type="diffuse"><rgb name="reflectance" value="0.5, 0.1, 0.1"/></bsdf>'
    )
    path = _write(
        tmp_path,
        """
        <path value="assets"/>
        <include filename="parts/lights.xml"/>
        <shape type="rectangle"><ref id="lamp"/><ref id="grey"/></shape>
        <shape type="obj"><string name="filename" value="triangle.obj"/><include filename="parts/red.xml"/></shape>
        <alias id="grey" as="stone"/>
        <shape type="cube"><ref id="stone"/></shape>""",
    )
    data, _ = mitsuba_scene_data(path)
    lamp, mesh, aliased = data["shapes"]
    assert aliased["material"] == "grey"  # through <alias id="grey" as="stone"/>
    assert lamp["emitter"] == {"radiance": {"rgb": [2.0, 2.0, 2.0]}} and lamp["material"] == "grey"
    assert mesh["file"] == "assets/triangle.obj"
    assert data["materials"][mesh["material"]]["reflectance"] == {"rgb": [0.5, 0.1, 0.1]}
    assert "lights" not in data  # the area light is the rectangle's, not a light of its own


def test_an_include_loop_is_one_line(tmp_path):
    _write(tmp_path, '<include filename="a.xml"/>', name="b.xml", sensor="")
    _write(tmp_path, '<include filename="b.xml"/>', name="a.xml", sensor="")
    path = _write(tmp_path, '<include filename="a.xml"/><shape type="cube"/>')
    with pytest.raises(SpectraceError) as caught:
        mitsuba_scene_data(path)
    assert "includes itself" in str(caught.value) and "\n" not in str(caught.value)
    missing = _write(tmp_path, '<include filename="nowhere.xml"/><shape type="cube"/>', name="missing.xml")
    with pytest.raises(SpectraceError, match=r"missing.xml: include@filename: included file 'nowhere.xml' not found"):
        mitsuba_scene_data(missing)


# ---------------------------------------------------------------- version 0.x


@pytest.mark.parametrize(
    "old, new",
    [
        ("toWorld", "to_world"),
        ("intIOR", "int_ior"),
        ("maxDepth", "max_depth"),
        ("sampleCount", "sample_count"),
        ("specularReflectance", "specular_reflectance"),
        ("fovAxis", "fov_axis"),
        ("rrDepth", "rr_depth"),
        ("width", "width"),
        ("to_world", "to_world"),
    ],
)
def test_camel_case_names_become_snake_case(old, new):
    assert camel_to_snake(old) == new


OLD_SCENE = """
    <integrator type="path"><integer name="maxDepth" value="4"/><integer name="rrDepth" value="3"/></integrator>
    <bsdf type="diffuse" id="paint"><rgb name="diffuseReflectance" value="0.2, 0.4, 0.6"/></bsdf>
    <bsdf type="dielectric" id="glass"><float name="intIOR" value="1.7"/><float name="extIOR" value="1.1"/></bsdf>
    <shape type="rectangle"><ref id="paint"/>
        <transform name="toWorld"><scale x="2" y="0.5"/><rotate x="1" y="1" angle="30"/>
            <matrix value="1 0 0 0.5  0 0 -1 0  0 1 0 2  0 0 0 1"/><translate z="-1"/></transform></shape>
    <shape type="cube"><ref id="glass"/><transform name="toWorld"><rotate z="2" angle="45"/></transform></shape>"""
OLD_SENSOR = """<sensor type="perspective"><float name="fov" value="30"/><string name="fovAxis" value="y"/>
    <transform name="toWorld"><LOOKAT origin="1, 2, 6" target="0, 0.5, 0" up="0, 1, 0.2"/></transform>
    <sampler type="independent"><integer name="sampleCount" value="6"/></sampler>
    <film type="hdrfilm"><integer name="width" value="12"/><integer name="height" value="8"/></film></sensor>"""


def test_an_old_file_is_upgraded(tmp_path):
    """`lookAt` (Mitsuba 0.x) becomes `lookat`, camelCase names snake_case, diffuse's diffuseReflectance its
    reflectance: the same scene as the version 3 file written with the new names."""
    old = _write(tmp_path, OLD_SCENE, name="old.xml", version="0.6.0", sensor=OLD_SENSOR.replace("LOOKAT", "lookAt"))
    new_text = OLD_SCENE
    for before, after in (("maxDepth", "max_depth"), ("rrDepth", "rr_depth"), ("diffuseReflectance", "reflectance")):
        new_text = new_text.replace(before, after)
    new_text = new_text.replace("intIOR", "int_ior").replace("extIOR", "ext_ior").replace("toWorld", "to_world")
    new_sensor = OLD_SENSOR.replace("LOOKAT", "lookat").replace("fovAxis", "fov_axis").replace("toWorld", "to_world")
    new = _write(tmp_path, new_text, name="new.xml", sensor=new_sensor.replace("sampleCount", "sample_count"))
    old_data, old_notes = mitsuba_scene_data(old)
    assert old_data == mitsuba_scene_data(new)[0]
    assert old_data["integrator"] == {"type": "path", "max_depth": 4, "rr_depth": 3}
    assert old_data["sampler"]["spp"] == 6 and old_data["materials"]["paint"]["reflectance"] == {"rgb": [0.2, 0.4, 0.6]}
    assert not [note for note in old_notes if note.startswith("warning")], old_notes


def test_old_texture_offsets_become_to_uv(tmp_path):
    path = _write(
        tmp_path,
        """<shape type="cube"><bsdf type="diffuse"><texture type="checkerboard" name="reflectance">
        <float name="uscale" value="4"/><float name="vscale" value="2"/><float name="uoffset" value="0.25"/>
        </texture></bsdf></shape>""",
        version="0.5.0",
    )
    data, _ = mitsuba_scene_data(path)
    (texture,) = data["textures"].values()
    # Mitsuba's upgrade: to_uv = scale(uscale, vscale) · translate(uoffset, voffset); a checkerboard's squares are
    # twice its uv (docs/mitsuba.md).
    assert texture["uv_scale"] == [8.0, 4.0] and texture["uv_offset"] == [2.0, 0.0]


@pytest.mark.peer
def test_old_file_transforms_and_values_match_mitsuba(tmp_path, mitsuba_scalar_spectral):
    """The upgraded old file against Mitsuba 3 loading the same file (its current parser refuses `lookAt`, so
    Mitsuba reads it with `lookat`): the shapes' to_world matrices (a rotation about an axis that is not a unit
    vector, a 16-value matrix, the order of the steps), the camera's frame and fov, depths and sample count."""
    mi = mitsuba_scalar_spectral
    path = _write(tmp_path, OLD_SCENE, version="0.6.0", sensor=OLD_SENSOR.replace("LOOKAT", "lookat"))
    data, _ = mitsuba_scene_data(path)
    scene = mi.load_file(str(path))
    (rectangle,) = [shape for shape in scene.shapes() if "to_world" in mi.traverse(shape)]
    (cube,) = [shape for shape in scene.shapes() if "vertex_positions" in mi.traverse(shape)]
    ours = transform_matrix(data["shapes"][0]["transform"], where="")
    np.testing.assert_allclose(ours, np.array(mi.traverse(rectangle)["to_world"].matrix, dtype=np.float64), atol=1e-5)
    # Mitsuba bakes a mesh's to_world into its vertices: each of them is one of spectrace's cube's.
    theirs = np.array(mi.traverse(cube)["vertex_positions"], dtype=np.float64).reshape(-1, 3)
    vertices = load_mitsuba_scene(path).shapes[1].mesh.vertices
    distances = np.linalg.norm(theirs[:, None, :] - vertices[None, :, :], axis=2).min(axis=1)
    assert distances.max() < 1e-5, distances.max()
    sensor = scene.sensors()[0]
    frame = np.array(sensor.world_transform().matrix, dtype=np.float64)
    camera = data["camera"]
    np.testing.assert_allclose(camera["origin"], frame[:3, 3], atol=1e-5)
    forward = np.subtract(camera["target"], camera["origin"])
    np.testing.assert_allclose(forward / np.linalg.norm(forward), frame[:3, 2], atol=1e-5)
    np.testing.assert_allclose(camera["up"], frame[:3, 1], atol=1e-5)
    x_fov = float(np.ravel(mi.traverse(sensor)["x_fov"])[0])
    assert camera["fov"] == pytest.approx(x_fov, rel=1e-5)
    assert sensor.sampler().sample_count() == data["sampler"]["spp"] == 6
    integrator = str(scene.integrator())
    assert "max_depth = 4" in integrator and "rr_depth = 3" in integrator
    glass = mi.traverse(cube.bsdf())
    assert data["materials"]["glass"]["ior"] == pytest.approx(float(glass["eta"]), rel=1e-6)


# ---------------------------------------------------------------- integrators


def test_moment_holds_the_integrator_it_renders(tmp_path):
    path = _write(
        tmp_path,
        '<integrator type="moment"><integrator type="direct"/></integrator><shape type="cube"/>',
    )
    data, notes = mitsuba_scene_data(path)
    assert data["integrator"] == {"type": "path", "max_depth": 2}
    assert any("'moment' imported as the integrator it holds" in note for note in notes)


def test_aov_holds_the_integrator_it_renders_and_keeps_the_aovs_spectrace_has(tmp_path):
    """Mitsuba's aov integrator: its nested integrator's image; depth, position, sh_normal and albedo are the film's
    AOVs of the same definitions (kernels/aov.cl); any other type, and an aov integrator without a nested one, is
    a warning naming it, which --strict makes an error."""
    path = _write(
        tmp_path,
        '<integrator type="aov"><string name="aovs" value="dd.y:depth, nn:sh_normal, tex:uv, pos:position"/>'
        '<integrator type="path"><integer name="max_depth" value="5"/></integrator></integrator><shape type="cube"/>',
    )
    data, notes = mitsuba_scene_data(path)
    assert data["integrator"] == {"type": "path", "max_depth": 5}
    assert data["film"]["aovs"] == ["depth", "normal", "position"]
    assert [note for note in notes if note.startswith("warning: ")] == [
        f"warning: {path}:4: integrator 'aov': AOV 'tex:uv' is not imported (spectrace's film keeps the types "
        "albedo, depth, position, sh_normal)"
    ]
    assert load_mitsuba_scene(path).aovs == ("normal", "depth", "position")
    with pytest.raises(SpectraceError, match="'tex:uv'"):
        mitsuba_scene_data(path, strict=True)
    alone = _write(tmp_path, '<integrator type="aov"><string name="aovs" value="a:albedo"/></integrator>')
    data, notes = mitsuba_scene_data(alone)
    assert data["integrator"]["type"] == "path" and data["film"]["aovs"] == ["albedo"]
    assert any("holds no integrator" in note for note in notes if note.startswith("warning: "))


HIDDEN = """<integrator type="path"><boolean name="hide_emitters" value="$hide"/></integrator>
    <emitter type="constant"><rgb name="radiance" value="0.5"/></emitter>
    <shape type="cube"><transform name="to_world"><scale value="0.3"/><translate z="3"/></transform></shape>"""
HIDDEN_SENSOR = """<sensor type="perspective"><float name="fov" value="30"/>
    <transform name="to_world"><lookat origin="0, 0, 0" target="0, 0, 1"/></transform>
    <film type="hdrfilm"><integer name="width" value="12"/><integer name="height" value="12"/>
    <rfilter type="box"/></film></sensor>"""


def test_hide_emitters_hides_the_environment_from_camera_rays_only(tmp_path, device):
    """Mitsuba's hide_emitters: camera rays that leave the scene see black (measured with Mitsuba: its constant
    environment disappears from the background); the light still reaches the cube, which renders the same bits as
    without it (same seed, same samples)."""
    from spectrace.engine.renderer import Renderer

    path = _write(tmp_path, HIDDEN, sensor=HIDDEN_SENSOR)
    images = {}
    for hide in ("false", "true"):
        scene = load_mitsuba_scene(path, parameters={"hide": hide}).with_overrides(spp=8)
        assert scene.hide_emitters == (hide == "true")
        renderer = Renderer(scene, device)
        renderer.render(spp=8, pass_spp=8)
        images[hide] = renderer.image().xyz.astype(np.float64)
    shown, hidden = images["false"], images["true"]
    # The cube's front face covers the central 4 x 4 pixels whole (half-width 0.3 at 2.7: ±2.5 pixels of 12 at a
    # 30° field): the same bits there; pixels on its edge lose their background samples; the rest is background.
    np.testing.assert_array_equal(hidden[4:8, 4:8], shown[4:8, 4:8])
    assert np.all(hidden <= shown)
    background = hidden[..., 1] == 0.0
    assert 50 < background.sum() < 144 - 16, background.sum()
    # Without hide_emitters the background shows the environment: Y = 0.5 (RGB 0.5 emission has luminance 0.5),
    # a Monte Carlo estimate over wavelengths: its mean within 4 standard errors.
    luminance = shown[background][:, 1]
    assert abs(luminance.mean() - 0.5) < 4 * luminance.std(ddof=1) / math.sqrt(luminance.size)


# ---------------------------------------------------------------- what is not imported


def test_unknown_properties_are_warnings_and_strict_refuses_them(tmp_path):
    path = _write(
        tmp_path,
        """<shape type="cube"><float name="glow" value="2"/>
            <bsdf type="diffuse"><float name="reflectance" value="0.5"/><rgb name="sheen" value="1"/></bsdf></shape>""",
    )
    _, notes = mitsuba_scene_data(path)
    warnings = [note for note in notes if note.startswith("warning: ")]
    assert warnings == [
        f"warning: {path}:4: shape 'cube': property 'glow' is not imported (spectrace does not know it)",
        f"warning: {path}:5: bsdf 'diffuse': property 'sheen' is not imported (spectrace does not know it)",
    ]
    with pytest.raises(SpectraceError) as caught:
        mitsuba_scene_data(path, strict=True)
    assert "2 properties not imported (--strict)" in str(caught.value) and "'sheen'" in str(caught.value)
    # The TOML's header carries the warnings; the output of a strict import that fails is not written.
    out = tmp_path / "out.toml"
    import_mitsuba(path, out)
    assert "# warning: " in out.read_text()
    with pytest.raises(SpectraceError):
        import_mitsuba(path, tmp_path / "strict.toml", strict=True)
    assert not (tmp_path / "strict.toml").exists()


def test_unsupported_plugins_are_named_once_with_their_count_and_nested_ones_too(tmp_path):
    shapes = "".join(
        '<shape type="ellipsoids"><string name="filename" value="x.ply"/>'
        '<bsdf type="measured_polarized"/><ref id="odd"/></shape>\n'
        for _ in range(3)
    )
    # custom_bsdf: a plugin of the user's own (Mitsuba 3 loads Python plugins by name)
    path = _write(tmp_path, f'<bsdf type="custom_bsdf" id="odd"/>\n{shapes}<shape type="cube"/>')
    with pytest.raises(SpectraceError) as caught:
        mitsuba_scene_data(path)
    message = caught.value.message
    assert "shape 'ellipsoids' (3 times, first at line 5)" in message, message
    assert "bsdf 'measured_polarized' (3 times, first at line 5)" in message, message
    assert "bsdf 'custom_bsdf' (3 times, first at line 4)" in message, message
    assert message.count("ellipsoids") == 1


# ---------------------------------------------------------------- envmap

ENV_WIDTH, ENV_HEIGHT = 8, 4


def _env_image(folder: Path) -> Path:
    """An 8 x 4 map whose texels are all different: red = column + 1, green = row + 1."""
    from spectrace.io.exr import write_exr

    image = np.zeros((ENV_HEIGHT, ENV_WIDTH, 3), np.float32)
    image[..., 0] = np.arange(ENV_WIDTH)[None, :] + 1
    image[..., 1] = np.arange(ENV_HEIGHT)[:, None] + 1
    image[..., 2] = 0.5
    path = folder / "sky.exr"
    write_exr(path, image, None, {})
    return path


ENV_TRANSFORM = (
    '<transform name="to_world"><rotate x="0.6" y="0.8" angle="70"/><rotate z="1" angle="25"/><translate x="4"/>'
    "</transform>"
)


def test_envmap_is_imported_with_its_orientation(tmp_path):
    _env_image(tmp_path)
    path = _write(
        tmp_path,
        f'<emitter type="envmap"><string name="filename" value="sky.exr"/><float name="scale" value="2"/>'
        f"{ENV_TRANSFORM}</emitter>",
    )
    (light,) = load_mitsuba_scene(path).lights
    # Mitsuba's rows are samples from pole to pole: read as the bands between them (test_mitsuba_envmap_rows.py).
    assert light.scale == 2.0 and light.rgb.shape == (ENV_HEIGHT - 1, ENV_WIDTH, 3)
    # 70° about (0.6, 0.8, 0), then 25° about z (Rodrigues): Mitsuba's local +y (the top row) and +z (the image
    # centre) in the world.

    def rotate(v, axis, degrees):
        v, axis, angle = np.asarray(v, float), np.asarray(axis, float), math.radians(degrees)
        return v * math.cos(angle) + np.cross(axis, v) * math.sin(angle) + axis * (axis @ v) * (1 - math.cos(angle))

    for ours, local in ((light.up, [0, 1, 0]), (light.front, [0, 0, 1])):
        np.testing.assert_allclose(ours, rotate(rotate(local, [0.6, 0.8, 0], 70), [0, 0, 1], 25), atol=1e-9)


@pytest.mark.peer
def test_envmap_shows_the_texels_mitsuba_shows(tmp_path, device, mitsuba_scalar_spectral):
    """A 1-pixel camera with a tiny field of view looks at one band's centre of a turned map; spectrace's render
    (the kernel's lookup) shows the band the import made of the texel rows Mitsuba's emitter interpolates there."""
    mi = mitsuba_scalar_spectral
    image = _env_image(tmp_path)
    from spectrace.engine.renderer import Renderer
    from spectrace.io.images import read_environment_map
    from spectrace.lights.envmap import pole_rows_as_bands

    bands = pole_rows_as_bands(read_environment_map(image, "sky.exr").astype(np.float64))
    mi.set_variant("scalar_rgb")
    emitter_xml = f'<emitter type="envmap"><string name="filename" value="sky.exr"/>{ENV_TRANSFORM}</emitter>'
    mitsuba_emitter = mi.load_string(
        f'<scene version="3.0.0">{emitter_xml}</scene>'.replace("sky.exr", str(tmp_path / "sky.exr"))
    ).emitters()[0]
    to_world = np.array(mi.traverse(mitsuba_emitter)["to_world"].matrix, dtype=np.float64)[:3, :3]
    import drjit as dr

    for column, row in ((0, 1), (2, 2), (5, 0), (6, 2), (3, 1)):
        u, v = (column + 0.5) / ENV_WIDTH, (row + 0.5) / (ENV_HEIGHT - 1)
        local = np.array(
            [
                math.sin(2 * math.pi * u) * math.sin(math.pi * v),
                math.cos(math.pi * v),
                -math.cos(2 * math.pi * u) * math.sin(math.pi * v),
            ]
        )
        direction = to_world @ local
        interaction = mi.SurfaceInteraction3f()
        interaction.wi = -dr.normalize(mi.Vector3f(direction))
        theirs = np.array(mitsuba_emitter.eval(interaction))
        # Columns: Mitsuba's texel centres are spectrace's, so it shows the texel itself. Rows: Mitsuba puts the
        # first and last rows on the poles (θ = π v over height − 1 rows, measured here) and interpolates between:
        # halfway between rows `row` and `row + 1` at the band's centre.
        np.testing.assert_allclose(theirs[:2], (column + 1, row + 1.5), atol=1e-3)
        up = (0.0, 1.0, 0.0) if abs(direction[1]) < 0.9 else (1.0, 0.0, 0.0)
        sensor = f"""<sensor type="perspective"><float name="fov" value="0.01"/>
            <transform name="to_world"><lookat origin="0, 0, 0" target="{", ".join(map(str, direction))}"
                up="{", ".join(map(str, up))}"/></transform>
            <film type="hdrfilm"><integer name="width" value="1"/><integer name="height" value="1"/></film></sensor>"""
        path = _write(tmp_path, emitter_xml, name=f"view{column}{row}.xml", sensor=sensor)
        renderer = Renderer(load_mitsuba_scene(path), device)
        renderer.render(spp=4096, pass_spp=4096)
        ours = xyz_to_linear_srgb(renderer.image().xyz.astype(np.float64).reshape(3))
        # A Monte Carlo estimate over wavelengths (measured within 7e-4 at 4096 spp); neighbouring texels differ by
        # 1 in red, bands by 1 in green.
        np.testing.assert_allclose(ours, (column + 1, bands[row, column, 1], 0.5), atol=0.01)
    mi.set_variant("scalar_spectral")


# ---------------------------------------------------------------- conductors in RGB


def _imported_gold(tmp_path: Path):
    path = _write(
        tmp_path,
        f"""<shape type="cube"><bsdf type="conductor"><rgb name="eta" value="{", ".join(map(str, GOLD_ETA))}"/>
            <rgb name="k" value="{", ".join(map(str, GOLD_K))}"/></bsdf></shape>""",
    )
    return load_mitsuba_scene(path).shapes[0].material


def _normal_incidence_colour(material) -> np.ndarray:
    reflectance = normal_incidence_reflectance(material.eta.values, material.k.values)
    return xyz_to_linear_srgb(reflectance_to_xyz(Spectrum(reflectance), cie_illuminant("D65")))


def test_a_number_beside_an_rgb_counts_as_a_grey_triple(tmp_path):
    path = _write(
        tmp_path,
        """<shape type="cube"><bsdf type="conductor"><float name="eta" value="0.2"/>
            <rgb name="k" value="3.9, 2.4, 2.1"/></bsdf></shape>""",
    )
    material = load_mitsuba_scene(path).shapes[0].material
    expected = normal_incidence_reflectance((0.2, 0.2, 0.2), (3.9, 2.4, 2.1))
    np.testing.assert_allclose(_normal_incidence_colour(material), expected, atol=1e-3)


def test_an_rgb_conductor_has_the_rgb_renderers_colour_at_normal_incidence(tmp_path):
    """The imported η(λ), k(λ) (written at 5 nm and read back) reflect, at normal incidence and seen under D65, the
    colour R_c = ((η_c−1)² + k_c²) / ((η_c+1)² + k_c²) an RGB renderer reflects per channel, within 1e-3."""
    material = _imported_gold(tmp_path)
    expected = normal_incidence_reflectance(GOLD_ETA, GOLD_K)
    np.testing.assert_allclose(_normal_incidence_colour(material), expected, atol=1e-3)
    assert material.eta.min() > 0 and material.k.min() >= 0


@pytest.mark.peer
def test_an_rgb_conductor_matches_mitsubas_rgb_variant(tmp_path, mitsuba_scalar_spectral):
    """Mitsuba's scalar_rgb conductor, sampled at normal incidence, reflects the colour of spectrace's imported
    spectra within 1e-3."""
    mi = mitsuba_scalar_spectral
    mi.set_variant("scalar_rgb")
    bsdf = mi.load_dict(
        {"type": "conductor", "eta": {"type": "rgb", "value": GOLD_ETA}, "k": {"type": "rgb", "value": GOLD_K}}
    )
    interaction = mi.SurfaceInteraction3f()
    interaction.wi = mi.Vector3f(0, 0, 1)
    _, weight = bsdf.sample(mi.BSDFContext(), interaction, 0.5, mi.Point2f(0.5, 0.5))
    mi.set_variant("scalar_spectral")
    np.testing.assert_allclose(_normal_incidence_colour(_imported_gold(tmp_path)), np.array(weight), atol=1e-3)


# ---------------------------------------------------------------- Radiance HDR maps (Mitsuba's envmap reads them)


def test_a_flat_rgbe_file_decodes_by_its_definition(tmp_path):
    """Mantissa · 2^(exponent − 136): (128, 64, 32) with exponent 129 is (1, 0.5, 0.25); exponent 0 is black."""
    from spectrace.io.rgbe import read_rgbe

    path = tmp_path / "flat.hdr"
    path.write_bytes(b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 1 +X 2\n" + bytes([128, 64, 32, 129, 9, 9, 9, 0]))
    np.testing.assert_array_equal(read_rgbe(path, "x"), [[[1.0, 0.5, 0.25], [0.0, 0.0, 0.0]]])
    path.write_bytes(b"#?RADIANCE\n\n-Y 2 +X 2\n" + bytes(8))
    with pytest.raises(SpectraceError, match="ends before its last row"):
        read_rgbe(path, "x")


@pytest.mark.peer
def test_rgbe_files_mitsuba_writes_read_back_as_mitsuba_reads_them(tmp_path, mitsuba_scalar_spectral):
    """Run-length encoded rows (Mitsuba writes them for widths of 8 and more): the same floats as Mitsuba's reader."""
    from spectrace.io.rgbe import read_rgbe

    mi = mitsuba_scalar_spectral
    image = (np.random.default_rng(1).random((5, 40, 3)) ** 3 * 50).astype(np.float32)
    image[0, :20] = 1.0  # runs
    path = tmp_path / "map.hdr"
    mi.Bitmap(image).write(str(path))
    np.testing.assert_array_equal(read_rgbe(path, "x"), np.array(mi.Bitmap(str(path)))[..., :3])


LIT_BY_ENVMAP = """<integrator type="path"><integer name="max_depth" value="3"/></integrator>
  <emitter type="envmap"><string name="filename" value="sky.exr"/><float name="scale" value="0.7"/>
    <transform name="to_world"><rotate x="0.6" y="0.8" angle="50"/><rotate y="1" angle="$turn"/></transform></emitter>
  <shape type="rectangle"><transform name="to_world"><rotate x="1" angle="-90"/></transform>
    <bsdf type="diffuse"><rgb name="reflectance" value="0.5"/></bsdf></shape>"""
LOOKING_DOWN = """<sensor type="perspective"><float name="fov" value="50"/>
    <transform name="to_world"><lookat origin="0, 3, 0.01" target="0, 0, 0" up="0, 0, 1"/></transform>
    <film type="hdrfilm"><integer name="width" value="16"/><integer name="height" value="16"/>
    <rfilter type="box"/></film></sensor>"""


@pytest.mark.peer
@pytest.mark.slow
def test_a_floor_lit_by_a_turned_envmap_renders_like_mitsuba(tmp_path, device, mitsuba_scalar_spectral):
    """A diffuse floor under a turned map with a small bright patch (light arriving through both the map's sampling
    and BSDF sampling, so the lookup, its density and their rotation must agree): 16 replicas of 16 spp from each
    renderer agree over 4 x 4-pixel blocks and the whole image within 5 standard errors (measured: whole-image
    ratio 0.999 to 1.003 per channel; the map turned 180° the other way fails at 146 standard errors).

    Mitsuba renders it in RGB: its spectral envmap interpolates its uplift's spectra and its texels' scales apart,
    so where neighbouring texels differ in colour (the grey patch on the coloured sky) it shows another light than
    the map's (here red −1.5 %, blue −2.2 % against its own RGB render, which is linear in the texels, as the
    floor's light is; a map of alternating red and grey-blue columns: red −11 %, blue +55 %)."""
    from replica_agreement import assert_replicas_agree, spectrace_replicas
    from spectrace.engine.renderer import Renderer
    from spectrace.io.exr import write_exr

    mi = mitsuba_scalar_spectral
    height, width = 32, 64
    u, v = (np.arange(width) + 0.5) / width, (np.arange(height) + 0.5) / height
    sky = np.zeros((height, width, 3), np.float32)
    sky[..., 0] = 1 + 0.8 * np.sin(2 * np.pi * u)[None, :]
    sky[..., 1] = 1 + 0.8 * np.cos(np.pi * v)[:, None]
    sky[..., 2] = 0.5 + 0.4 * np.cos(2 * np.pi * u)[None, :] * np.sin(np.pi * v)[:, None]
    sky[4:8, 40:48] = 20.0
    write_exr(tmp_path / "sky.exr", sky, None, {})
    path = _write(tmp_path, LIT_BY_ENVMAP.replace("$turn", "-100"), sensor=LOOKING_DOWN)
    replicas, replica_spp = 16, 16
    mi.set_variant("scalar_rgb")
    try:
        scene = mi.load_file(str(path))
        theirs = np.stack([np.array(mi.render(scene, spp=replica_spp, seed=seed)) for seed in range(replicas)])
    finally:
        mi.set_variant("scalar_spectral")
    ours = spectrace_replicas(Renderer(load_mitsuba_scene(path), device), replicas, replica_spp)
    assert_replicas_agree(xyz_to_linear_srgb(ours), theirs, 4)


MISSPELT = """
    <emiter type="point"><rgb name="intensity" value="1"/></emiter>
    <shape type="cube"><shpe type="sphere"/>
        <transform name="to_world"><translat x="1"/><scale value="2"/></transform>
        <bsdf type="diffuse"><rgb name="reflectance" value="0.5"><colour/></rgb></bsdf></shape>
    <bsdf type="diffuse" id="unused"><flaot name="x" value="1"/></bsdf>
    <include filename="part.xml"/>"""
# The same scene as Mitsuba would read it if it skipped the unknown tags (a <default> keeps the shape's index,
# which its imported name is made from).
SPELT = """
    <default name="placeholder" value="0"/>
    <shape type="cube">
        <transform name="to_world"><scale value="2"/></transform>
        <bsdf type="diffuse"><rgb name="reflectance" value="0.5"/></bsdf></shape>
    <bsdf type="diffuse" id="unused"/>
    <include filename="part.xml"/>"""


def test_unknown_tags_are_reported_at_every_level_and_strict_refuses_them(tmp_path):
    (tmp_path / "part.xml").write_text('<scene version="3.0.0">\n<emitter type="constant"><spectrm/></emitter></scene>')
    path = _write(tmp_path, MISSPELT)
    data, notes = mitsuba_scene_data(path)
    part = tmp_path / "part.xml"
    assert [note for note in notes if note.startswith("warning: ")] == [
        f"warning: {path}:5: emiter: unknown tag <emiter> is not imported (Mitsuba 3 has no such element)",
        f"warning: {path}:6: shape/shpe: unknown tag <shpe> is not imported (Mitsuba 3 has no such element)",
        f"warning: {path}:7: shape/transform/translat: unknown tag <translat> is not imported (Mitsuba 3 has no "
        "such element)",
        f"warning: {path}:8: shape/bsdf/rgb/colour: unknown tag <colour> is not imported (Mitsuba 3 has no such "
        "element)",
        f"warning: {path}:9: bsdf/flaot: unknown tag <flaot> is not imported (Mitsuba 3 has no such element)",
        f"warning: {part}:2: emitter/spectrm: unknown tag <spectrm> is not imported (Mitsuba 3 has no such element)",
    ]
    spelt, _ = mitsuba_scene_data(_write(tmp_path, SPELT, name="spelt.xml"))
    assert data == spelt
    with pytest.raises(SpectraceError) as caught:
        mitsuba_scene_data(path, strict=True)
    message = str(caught.value)
    assert message.startswith(f"{path}: 6 unknown tags not imported (--strict): {path}:5: emiter: unknown tag")
    assert "\n" not in message
    both = _write(tmp_path, '<shape type="cube"><float name="glow" value="2"/><shpe/></shape>', name="both.xml")
    with pytest.raises(SpectraceError, match=r"1 property and 1 unknown tag not imported \(--strict\)"):
        mitsuba_scene_data(both, strict=True)


@pytest.mark.subprocess
@pytest.mark.slow
def test_strict_refuses_a_misspelt_tag_on_the_command_line(tmp_path):
    from cli_runner import run_spectrace

    path = _write(tmp_path, '<emiter type="point"><rgb name="intensity" value="1"/></emiter><shape type="cube"/>')
    result = run_spectrace("import-mitsuba", str(path), "-o", str(tmp_path / "out.toml"), "--strict", timeout=120)
    assert result.returncode == 2 and result.stderr.count("\n") == 1, result.stderr
    assert f"{path}: 1 unknown tag not imported (--strict): {path}:4: emiter: unknown tag <emiter>" in result.stderr
    assert "Traceback" not in result.stderr and not (tmp_path / "out.toml").exists()
    result = run_spectrace("import-mitsuba", str(path), "-o", str(tmp_path / "out.toml"), timeout=120)
    assert result.returncode == 0 and f"warning: {path}:4: emiter: unknown tag <emiter>" in result.stderr


def test_the_command_takes_defines_prints_warnings_and_refuses_with_strict(tmp_path, monkeypatch, capsys):
    from cli_runner import run_in_process

    path = _write(
        tmp_path,
        '<default name="kind" value="sphere"/><shape type="$kind"><float name="glow" value="1"/></shape>',
    )
    out = tmp_path / "out.toml"
    argv = ["import-mitsuba", str(path), "-o", str(out), "-D", "kind=cube"]
    status, stderr = run_in_process(monkeypatch, capsys, argv)
    assert status == 0, stderr
    assert 'type = "cube"' in out.read_text()
    assert f"warning: {path}:4: shape 'cube': property 'glow' is not imported" in stderr
    strict = tmp_path / "strict.toml"
    status, stderr = run_in_process(monkeypatch, capsys, ["import-mitsuba", str(path), "-o", str(strict), "--strict"])
    assert status == 2 and stderr.count("\n") == 1 and "1 property not imported (--strict)" in stderr, stderr
    assert not strict.exists()


def test_a_duplicate_id_is_refused_and_notes_name_included_files(tmp_path):
    path = _write(tmp_path, '<bsdf type="diffuse" id="a"/><shape type="cube"><bsdf type="diffuse" id="a"/></shape>')
    with pytest.raises(SpectraceError, match=r"shape/bsdf@id: duplicate id 'a' \(also at line 4\)"):
        mitsuba_scene_data(path)
    _write(tmp_path, '<integrator type="direct"/>', name="parts/integrator.xml", sensor="")
    path = _write(tmp_path, '<include filename="parts/integrator.xml"/><shape type="cube"/>', name="main.xml")
    _, notes = mitsuba_scene_data(path)
    assert any(note.startswith("line 3 of integrator.xml: integrator 'direct'") for note in notes), notes


def test_near_clip_is_the_cameras(tmp_path):
    """The sensor's near_clip reaches the camera (tests/render/test_near_clip.py shows what it does); a negative one
    is refused with its line."""
    sensor = SENSOR.replace('value="45"/>', 'value="45"/><float name="near_clip" value="2.5"/>')
    data, notes = mitsuba_scene_data(_write(tmp_path, "", sensor=sensor))
    assert data["camera"]["near_clip"] == 2.5 and not any("near_clip" in note for note in notes)
    with pytest.raises(SpectraceError, match="near_clip must be 0 or more"):
        mitsuba_scene_data(_write(tmp_path, "", name="bad.xml", sensor=sensor.replace("2.5", "-1")))
