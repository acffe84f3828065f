"""Mitsuba 3 XML import: Mitsuba's own Cornell box scene, imported, against its stated geometry; conversions against
closed forms; unsupported plugins named; and, where the `mitsuba` package is installed (the `mitsuba` extra), the
imported scene rendered by spectrace against Mitsuba's own spectral render of the same file."""

import math
import os
from pathlib import Path

import numpy as np
import pytest

from cli_runner import run_in_process as _run_in_process
from cli_runner import run_spectrace
from replica_agreement import assert_replicas_agree, spectrace_replicas
from spectrace.errors import SpectraceError
from spectrace.interop.mitsuba import load_mitsuba_scene, mitsuba_scene_data
from spectrace.spectral import spectrum_to_xyz, xyz_to_linear_srgb
from spectrace.spectral.blackbody import planck_radiance

CORNELL_XML = Path(__file__).resolve().parents[1] / "data" / "mitsuba" / "cornell_box.xml"


def _write(folder: Path, body: str, sensor: str | None = None) -> Path:
    sensor = (
        sensor
        or """<sensor type="perspective"><float name="fov" value="45"/>
        <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="6"/></film></sensor>"""
    )
    path = folder / "scene.xml"
    path.write_text(f'<scene version="3.0.0">\n{sensor}\n{body}\n</scene>\n')
    return path


def test_cornell_box_geometry_and_light(device):
    scene = load_mitsuba_scene(CORNELL_XML, parameters={"resx": "16", "resy": "16"})
    assert (scene.width, scene.height, scene.spp, scene.max_depth) == (16, 16, 64, 8)
    assert scene.camera.origin == pytest.approx((0, 0, 3.9)) and scene.camera.fov_degrees == pytest.approx(39.3077)
    light = next(shape for shape in scene.shapes if shape.emitter is not None)
    # Mitsuba's rectangle is [-1, 1]² at z = 0 facing +z; scaled by (0.23, 0.19) and turned 90° about x it faces
    # down (-y) at y = 0.99.
    assert light.mesh.area() == pytest.approx(4 * 0.23 * 0.19, rel=1e-6)
    v0, v1, v2 = light.mesh.triangles()
    normal = np.cross(v1 - v0, v2 - v0)[0]
    np.testing.assert_allclose(normal / np.linalg.norm(normal), (0, -1, 0), atol=1e-6)
    np.testing.assert_allclose(light.mesh.vertices[:, 1], 0.99, atol=1e-6)
    # RGB radiance is uplifted so that its linear sRGB is the file's triple (18.387, 13.9873, 6.75357).
    rgb = xyz_to_linear_srgb(spectrum_to_xyz(light.emitter.radiance))
    np.testing.assert_allclose(rgb, (18.387, 13.9873, 6.75357), rtol=1e-4)
    # Five walls: the faces of [-1, 1]³; the large box: a cube scaled by 0.61 in y, moved to y = -0.4, so it spans
    # y = -1.01..0.21 (it reaches 1 cm into the floor in Mitsuba's scene too).
    shapes = {shape.name: shape.mesh.vertices for shape in scene.shapes}
    assert len(shapes) == 8
    for wall in ("floor", "ceiling", "back", "green-wall", "red-wall"):
        assert np.abs(shapes[wall]).max() == pytest.approx(1.0, abs=1e-6)
    assert shapes["large-box"][:, 1].min() == pytest.approx(-1.01, abs=1e-6)
    assert shapes["large-box"][:, 1].max() == pytest.approx(0.21, abs=1e-6)


@pytest.mark.slow
@pytest.mark.subprocess
def test_import_command_writes_a_scene_that_renders(tmp_path):
    out = tmp_path / "imported" / "cornell.toml"
    result = run_spectrace("import-mitsuba", str(CORNELL_XML), "-o", str(out), "-D", "spp=2")
    assert result.returncode == 0, result.stderr
    assert "filter" not in result.stderr, result.stderr  # the Gaussian filter imported, not reported as left out
    assert "spp = 2" in out.read_text() and 'type = "gaussian"' in out.read_text()
    image = tmp_path / "cornell.png"
    rendered = run_spectrace("render", str(out), "-o", str(image), "--width", "8", "--height", "8", "-q")
    assert rendered.returncode == 0, rendered.stderr


def test_unsupported_plugins_are_all_named(tmp_path):
    path = _write(
        tmp_path,
        """
        <bsdf type="custom_bsdf" id="metal"/>
        <shape type="ellipsoids"><string name="filename" value="x.ply"/></shape>
        <shape type="cube"><ref id="metal"/></shape>
        <emitter type="sky"><float name="turbidity" value="3"/></emitter>""",
    )
    with pytest.raises(SpectraceError) as error:
        mitsuba_scene_data(path)
    message = str(error.value)
    for named in (
        "shape 'ellipsoids' (line 6)",
        "bsdf 'custom_bsdf' (line 5)",
        "emitter 'sky' (line 8)",
    ):
        assert named in message
    assert "\n" not in message


def test_conductor_and_plastic_bsdfs_are_mapped(tmp_path):
    path = _write(
        tmp_path,
        """
        <bsdf type="roughconductor" id="gold"><string name="material" value="Au"/>
            <float name="alpha" value="0.2"/><string name="distribution" value="ggx"/></bsdf>
        <bsdf type="conductor" id="mirror"><float name="specular_reflectance" value="0.8"/></bsdf>
        <bsdf type="conductor" id="measured"><spectrum name="eta" value="400:1.2, 700:0.2"/>
            <spectrum name="k" value="400:2.2, 700:3.5"/></bsdf>
        <bsdf type="twosided" id="red"><bsdf type="roughplastic"><rgb name="diffuse_reflectance" value="0.5, 0.1, 0.1"/>
            <string name="int_ior" value="bk7"/></bsdf></bsdf>
        <bsdf type="plastic" id="white"><float name="int_ior" value="1.6"/><float name="ext_ior" value="1.0"/></bsdf>
        <shape type="sphere"><ref id="gold"/></shape>
        <shape type="sphere"><ref id="mirror"/></shape>
        <shape type="sphere"><ref id="measured"/></shape>
        <shape type="sphere"><ref id="red"/></shape>
        <shape type="sphere"><ref id="white"/></shape>
        <emitter type="constant"/>""",
    )
    data, notes = mitsuba_scene_data(path)
    materials = data["materials"]
    # Outside `twosided`, Mitsuba's reflecting BSDFs are black from the back.
    assert materials["gold"] == {"type": "conductor", "metal": "Au", "roughness": 0.2, "two_sided": False}
    assert materials["mirror"] == {  # Mitsuba's material "none"
        "type": "mirror",
        "reflectance": {"value": 0.8},
        "two_sided": False,
    }
    assert materials["measured"]["eta"] == {"values": [[400.0, 1.2], [700.0, 0.2]]}
    # Mitsuba's roughplastic defaults: alpha 0.1, Beckmann; ior = bk7 / air.
    assert materials["red"] == {
        "type": "plastic",
        "reflectance": {"rgb": [0.5, 0.1, 0.1]},
        "ior": pytest.approx(1.5046 / 1.000277),
        "roughness": 0.1,
        "distribution": "beckmann",
        "coat_transmission": "rough",
    }
    assert materials["white"] == {"type": "plastic", "reflectance": {"value": 0.5}, "ior": 1.6, "two_sided": False}
    assert not any("GGX" in note for note in notes)
    scene = load_mitsuba_scene(path)
    assert {type(shape.material).__name__ for shape in scene.shapes} == {
        "ConductorMaterial",
        "MirrorMaterial",
        "PlasticMaterial",
    }


def test_distribution_and_nonlinear_are_mapped(tmp_path):
    """Mitsuba's distribution (default beckmann) on every rough BSDF; plastic's nonlinear; an unknown distribution
    is one error naming the element."""
    body = """
        <shape type="sphere"><bsdf type="roughconductor"><string name="material" value="Cu"/></bsdf></shape>
        <shape type="sphere"><bsdf type="roughplastic"><string name="distribution" value="ggx"/>
            <boolean name="nonlinear" value="true"/></bsdf></shape>
        <shape type="sphere"><bsdf type="plastic"><boolean name="nonlinear" value="false"/></bsdf></shape>
        <shape type="sphere"><bsdf type="roughdielectric"><float name="alpha" value="0.3"/></bsdf></shape>"""
    materials = list(mitsuba_scene_data(_write(tmp_path, body))[0]["materials"].values())
    assert materials[0]["distribution"] == "beckmann" and materials[0]["roughness"] == 0.1
    assert "distribution" not in materials[1] and materials[1]["nonlinear"] is True  # ggx: spectrace's default
    assert "nonlinear" not in materials[2]
    assert materials[3]["distribution"] == "beckmann"
    scene = load_mitsuba_scene(_write(tmp_path, body))
    kinds = [(shape.material.distribution, getattr(shape.material, "nonlinear", None)) for shape in scene.shapes]
    assert kinds == [("beckmann", None), ("ggx", True), ("ggx", False), ("beckmann", None)]
    bad = _write(
        tmp_path,
        '<shape type="sphere"><bsdf type="roughconductor"><string name="material" value="Au"/>'
        '<string name="distribution" value="phong"/></bsdf></shape>',
    )
    with pytest.raises(SpectraceError, match="unknown distribution 'phong'") as error:
        mitsuba_scene_data(bad)
    assert "\n" not in str(error.value) and "line" in str(error.value)


def test_unrepresentable_conductors_are_named(tmp_path):
    path = _write(
        tmp_path,
        """
        <bsdf type="conductor" id="chrome"><string name="material" value="Pt"/></bsdf>
        <shape type="cube"><ref id="chrome"/></shape>""",
    )
    with pytest.raises(SpectraceError) as error:
        mitsuba_scene_data(path)
    assert "with material 'Pt'" in str(error.value)


def test_anisotropic_roughconductor_carries_both_alphas(tmp_path):
    """A roughconductor's alpha_u and alpha_v become roughness and roughness_v (spectrace's anisotropic lobe, along
    dp/du and the bitangent as Mitsuba's), with no warning, so --strict takes it; either one alone stands for both,
    as in Mitsuba, and equal ones make an isotropic lobe."""
    path = _write(
        tmp_path,
        """
        <bsdf type="roughconductor" id="brushed"><string name="material" value="Al"/>
            <float name="alpha_u" value="0.1"/><float name="alpha_v" value="0.4"/></bsdf>
        <bsdf type="roughconductor" id="one"><float name="alpha_v" value="0.3"/></bsdf>
        <shape type="cube"><ref id="brushed"/></shape>
        <shape type="sphere"><ref id="one"/></shape>""",
    )
    for strict in (False, True):
        data, notes = mitsuba_scene_data(path, strict=strict)
        assert not [note for note in notes if note.startswith("warning: ")]
        brushed, one = data["materials"]["brushed"], data["materials"]["one"]
        assert (brushed["roughness"], brushed["roughness_v"]) == (pytest.approx(0.1), pytest.approx(0.4))
        assert one["roughness"] == pytest.approx(0.3) and "roughness_v" not in one


def test_textured_anisotropic_roughconductor_imports_its_texture(tmp_path):
    """A textured alpha_u is the conductor's roughness texture, alpha_v its number."""
    path = _write(
        tmp_path,
        """
        <bsdf type="roughconductor" id="brushed"><texture type="checkerboard" name="alpha_u">
            <float name="color0" value="0.05"/><float name="color1" value="0.3"/></texture>
            <float name="alpha_v" value="0.4"/></bsdf>
        <shape type="sphere"><ref id="brushed"/></shape>""",
    )
    data, notes = mitsuba_scene_data(path, strict=True)
    brushed = data["materials"]["brushed"]
    assert brushed["roughness_v"] == pytest.approx(0.4)
    assert data["textures"][brushed["roughness"]["texture"]]["type"] == "checkerboard"


@pytest.mark.parametrize(
    "fov_xml, aspect_width, expected_tan_half_x",
    [
        ('<float name="fov" value="40"/><string name="fov_axis" value="y"/>', 16, 2 * math.tan(math.radians(20))),
        ('<float name="fov" value="40"/><string name="fov_axis" value="smaller"/>', 16, 2 * math.tan(math.radians(20))),
        ('<float name="fov" value="40"/><string name="fov_axis" value="larger"/>', 16, math.tan(math.radians(20))),
        (
            '<float name="fov" value="40"/><string name="fov_axis" value="diagonal"/>',
            16,
            math.tan(math.radians(20)) * 2 / math.sqrt(5),
        ),
        # 35 mm equivalent: the 36 x 24 mm frame's diagonal at 50 mm, then as a diagonal fov.
        ('<string name="focal_length" value="50mm"/>', 16, math.hypot(36, 24) / 100 * 2 / math.sqrt(5)),
        ('<float name="fov" value="40"/><string name="fov_axis" value="smaller"/>', 4, math.tan(math.radians(20))),
    ],
)
def test_field_of_view_conversions(tmp_path, fov_xml, aspect_width, expected_tan_half_x):
    sensor = f"""<sensor type="perspective">{fov_xml}
        <film type="hdrfilm"><integer name="width" value="{aspect_width}"/><integer name="height" value="8"/></film>
        </sensor>"""
    data, _ = mitsuba_scene_data(_write(tmp_path, '<shape type="cube"/>', sensor))
    assert math.tan(math.radians(data["camera"]["fov"]) / 2) == pytest.approx(expected_tan_half_x, rel=1e-12)


def test_lookat_sensor_and_transforms(tmp_path):
    sensor = """<sensor type="perspective"><float name="fov" value="30"/>
        <transform name="to_world"><lookat origin="1, 2, 3" target="1, 2, 10" up="0, 1, 0"/></transform></sensor>"""
    body = """<shape type="sphere"><point name="center" x="1" y="2" z="9"/><float name="radius" value="0.5"/></shape>
        <shape type="rectangle"><boolean name="flip_normals" value="true"/>
            <transform name="to_world"><translate value="0 0 12"/></transform></shape>"""
    scene = load_mitsuba_scene(_write(tmp_path, body, sensor))
    assert scene.camera.origin == pytest.approx((1, 2, 3))
    np.testing.assert_allclose(np.subtract(scene.camera.target, scene.camera.origin), (0, 0, 1), atol=1e-12)
    assert (scene.width, scene.height) == (768, 576)  # hdrfilm's defaults
    sphere, rectangle = scene.shapes
    distances = np.linalg.norm(sphere.mesh.vertices - (1, 2, 9), axis=1)  # on the sphere, or a seam cut's chord
    assert np.all(distances <= 0.5 * (1 + 1e-12)) and np.max(distances) == pytest.approx(0.5, rel=1e-12)
    assert np.mean(np.isclose(distances, 0.5, rtol=1e-12)) > 0.95
    v0, v1, v2 = rectangle.mesh.triangles()
    assert np.cross(v1 - v0, v2 - v0)[0][2] < 0  # flip_normals: the rectangle faces -z, toward the camera
    assert scene.max_depth == -1  # no <integrator>: Mitsuba's path tracer, unbounded depth


def test_face_normals_follow_mitsuba(tmp_path):
    """Mitsuba 3 shades obj and ply meshes smoothly (computing normals for a file without them) unless face_normals
    is set; its sphere is smooth. The import writes spectrace's key so that the same holds."""
    ball = "".join(
        f"v {np.cos(a) * np.cos(b):.9f} {np.sin(b):.9f} {np.sin(a) * np.cos(b):.9f}\n"
        for b in (-0.5, 0.0, 0.5)
        for a in np.linspace(0, 2 * np.pi, 9)[:-1]
    ) + "".join(
        f"f {r * 8 + i + 1} {r * 8 + (i + 1) % 8 + 1} {(r + 1) * 8 + i + 1}\n" for r in (0, 1) for i in range(8)
    )
    (tmp_path / "band.obj").write_text(ball)
    body = """<shape type="obj"><string name="filename" value="band.obj"/></shape>
        <shape type="obj"><string name="filename" value="band.obj"/><boolean name="face_normals" value="true"/></shape>
        <shape type="sphere"/>
        <shape type="sphere"><boolean name="face_normals" value="true"/></shape>"""
    xml = _write(tmp_path, body)
    tables = mitsuba_scene_data(xml)[0]["shapes"]
    assert [t.get("face_normals") for t in tables] == [False, True, None, True]
    smooth_mesh, faceted_mesh, smooth_sphere, faceted_sphere = (s.mesh for s in load_mitsuba_scene(xml).shapes)
    assert smooth_mesh.normals is not None and smooth_sphere.normals is not None
    assert faceted_mesh.normals is None and faceted_sphere.normals is None


def test_spectra_and_lights(tmp_path):
    (tmp_path / "lamp.spd").write_text("# wavelength value\n400 1.0\n500 2.0\n700 3.0\n")
    body = """
        <shape type="cube"><bsdf type="twosided"><bsdf type="diffuse">
            <spectrum name="reflectance" value="400:0.1, 700:0.9"/></bsdf></bsdf></shape>
        <emitter type="point"><point name="position" value="0, 3, 0"/>
            <spectrum name="intensity" filename="lamp.spd"/></emitter>
        <emitter type="directional"><vector name="direction" x="0" y="-1" z="0"/>
            <spectrum type="blackbody" name="irradiance"><float name="temperature" value="5000"/></spectrum></emitter>
        <emitter type="constant"><float name="radiance" value="0.25"/></emitter>"""
    scene = load_mitsuba_scene(_write(tmp_path, body))
    reflectance = scene.shapes[0].material.reflectance
    assert reflectance.evaluate(550.0) == pytest.approx(0.5) and reflectance.evaluate(380.0) == pytest.approx(0.1)
    point, distant, environment = scene.lights
    assert point.position == (0, 3, 0) and point.intensity.evaluate(600.0) == pytest.approx(2.5)
    # Mitsuba's black body is Planck's law in W/(m² sr nm): 2hc²/λ⁵ / (exp(hc/λkT) - 1), CODATA constants.
    h, c, k = 6.62607015e-34, 299792458.0, 1.380649e-23
    lam = 555e-9
    planck = 2 * h * c**2 / lam**5 / math.expm1(h * c / (lam * k * 5000.0)) * 1e-9
    assert distant.irradiance.evaluate(555.0) == pytest.approx(planck, rel=1e-9)
    assert planck_radiance(np.array([555.0]), 5000.0)[0] == pytest.approx(planck, rel=1e-12)
    assert distant.direction == pytest.approx((0, -1, 0))
    assert environment.radiance.mean() == pytest.approx(0.25)


def test_dielectrics(tmp_path):
    """Mitsuba's dielectric index is int_ior / ext_ior, named (its table, Hecht's values) or numeric; bk7 in air
    by default; roughdielectric's alpha (default 0.1) becomes the roughness of its distribution (default
    beckmann)."""
    body = """
        <shape type="sphere"><bsdf type="dielectric"/></shape>
        <shape type="sphere"><bsdf type="dielectric"><string name="int_ior" value="water"/>
            <float name="ext_ior" value="1.0"/></bsdf></shape>
        <shape type="sphere"><bsdf type="roughdielectric"><string name="distribution" value="ggx"/>
            <float name="alpha" value="0.25"/><float name="int_ior" value="1.7"/>
            <rgb name="specular_reflectance" value="0.9"/>
            <rgb name="specular_transmittance" value="0.9"/></bsdf></shape>
        <shape type="sphere"><bsdf type="roughdielectric"/></shape>"""
    data, notes = mitsuba_scene_data(_write(tmp_path, body))
    materials = list(data["materials"].values())
    assert materials[0] == {"type": "dielectric", "ior": pytest.approx(1.5046 / 1.000277)}
    assert materials[1] == {"type": "dielectric", "ior": pytest.approx(1.333)}
    assert materials[2] == {
        "type": "dielectric",
        "ior": pytest.approx(1.7 / 1.000277),
        "roughness": 0.25,
        "specular_tint": {"rgb": [0.9, 0.9, 0.9]},
    }
    assert materials[3]["roughness"] == 0.1 and materials[3]["distribution"] == "beckmann"  # Mitsuba's defaults
    scene = load_mitsuba_scene(_write(tmp_path, body))
    assert scene.shapes[1].material.ior.at(500.0) == pytest.approx(1.333)

    # Mitsuba's relative η = int_ior / ext_ior below 1 (an air bubble in water) is the ior as it is; equal indices
    # give 1 (straight through), except on a roughdielectric, which Mitsuba 3 refuses too; 0.1 is out of range.
    bubble = _write(
        tmp_path,
        """<shape type="cube"><bsdf type="dielectric"><string name="int_ior" value="air"/>
        <string name="ext_ior" value="water"/></bsdf></shape>
        <shape type="cube"><bsdf type="dielectric"><float name="int_ior" value="1.33"/>
        <float name="ext_ior" value="1.33"/></bsdf></shape>
        <shape type="cube"><bsdf type="thindielectric"><float name="int_ior" value="1"/>
        <float name="ext_ior" value="1.33"/></bsdf></shape>""",
    )
    iors = [material["ior"] for material in mitsuba_scene_data(bubble)[0]["materials"].values()]
    assert iors == [pytest.approx(1.000277 / 1.333), 1.0, pytest.approx(1 / 1.33)]
    for bsdf, message in (
        (
            '<bsdf type="roughdielectric"><float name="int_ior" value="1.2"/><float name="ext_ior" value="1.2"/>',
            "roughdielectric with int_ior equal to ext_ior",
        ),
        (
            '<bsdf type="dielectric"><float name="int_ior" value="0.1"/><float name="ext_ior" value="1"/>',
            "needs a ratio in",
        ),
    ):
        with pytest.raises(SpectraceError, match=message) as error:
            mitsuba_scene_data(_write(tmp_path, f'<shape type="cube">{bsdf}</bsdf></shape>'))
        assert "\n" not in str(error.value)
    # A dielectric's lobe is isotropic: its anisotropic roughness is approximated (the geometric mean), with a warning.
    brushed = _write(
        tmp_path,
        """<shape type="cube"><bsdf type="roughdielectric"><float name="alpha_u" value="0.1"/>
            <float name="alpha_v" value="0.4"/></bsdf></shape>""",
    )
    data, notes = mitsuba_scene_data(brushed)
    assert next(iter(data["materials"].values()))["roughness"] == pytest.approx(0.2)
    assert any(note.startswith("warning: ") and "anisotropic" in note for note in notes)


@pytest.mark.peer
@pytest.mark.slow
def test_imported_cornell_box_renders_like_mitsuba(tmp_path, device, mitsuba_scalar_spectral):
    """Mitsuba's Cornell box (its own scene dict, written as XML by its own serialiser, at 32 x 32 with a box pixel
    filter so both renderers average over the same pixel areas) rendered by both in spectral mode. Each renderer
    gives REPLICAS independent images of REPLICA_SPP samples; the mean over 8 x 8-pixel blocks and over the whole
    image, in linear sRGB, must agree within 5 standard errors of the difference (from the replicas' spread)."""
    mi = mitsuba_scalar_spectral
    replicas, replica_spp, size, block = 24, 8, 32, 8
    scene_dict = mi.cornell_box()
    scene_dict["sensor"]["film"].update({"width": size, "height": size, "rfilter": {"type": "box"}})
    config = mi.parser.ParserConfig("scalar_spectral")
    xml_path = tmp_path / "cornell_box.xml"
    xml_path.write_text(mi.parser.write_string(mi.parser.parse_dict(config, scene_dict)))

    mitsuba_scene = mi.load_file(str(xml_path))
    by_mitsuba = np.stack([np.array(mi.render(mitsuba_scene, spp=replica_spp, seed=seed)) for seed in range(replicas)])

    from spectrace.engine.renderer import Renderer

    xyz_replicas = spectrace_replicas(Renderer(load_mitsuba_scene(xml_path), device), replicas, replica_spp)
    assert_replicas_agree(xyz_to_linear_srgb(xyz_replicas), by_mitsuba, block)
    assert by_mitsuba.mean() > 0.05  # the comparison saw a lit image


# ---------------------------------------------------------------- bad input: one line, file and element path

CUBE = '<shape type="cube"/>'
BAD_INPUT = [
    # (name, body, element/attribute path, what the line says)
    (
        "non-numeric",
        CUBE * 2 + '<shape type="cube"><transform name="to_world"><translate x="abc"/></transform></shape>',
        "shape[2]/transform/translate@x",
        "expected a finite number, got 'abc'",
    ),
    (
        "word-angle",
        '<shape type="cube"><transform name="to_world"><rotate y="1" angle="ninety"/></transform></shape>',
        "shape/transform/rotate@angle",
        "expected a finite number, got 'ninety'",
    ),
    (
        "integer-overflow",
        CUBE + '<integrator type="path"><integer name="max_depth" value="1e400"/></integrator>',
        "integrator/integer@value",
        "1e400 is beyond the float32 range",
    ),
    (
        "integer-not-integral",
        CUBE + '<integrator type="path"><integer name="max_depth" value="2.5"/></integrator>',
        "integrator/integer@value",
        "expected an integer, got '2.5'",
    ),
    (
        "integer-beyond-64-bit",
        CUBE + '<integrator type="path"><integer name="max_depth" value="99999999999999999999"/></integrator>',
        "integrator/integer@value",
        "is out of range",
    ),
    (
        "nan",
        '<shape type="sphere"><float name="radius" value="nan"/></shape>',
        "shape/float@value",
        "expected a finite number, got 'nan'",
    ),
    (
        "inf",
        '<shape type="sphere"><point name="center" x="0" y="inf" z="0"/></shape>',
        "shape/point@y",
        "expected a finite number, got 'inf'",
    ),
    (
        "float32-overflow",
        '<shape type="sphere"><float name="radius" value="1e39"/></shape>',
        "shape/float@value",
        "1e39 is beyond the float32 range",
    ),
    (
        "float64-overflow",
        '<shape type="cube"><transform name="to_world"><scale value="2 1e400 2"/></transform></shape>',
        "shape/transform/scale@value",
        "1e400 is beyond the float32 range",
    ),
    (
        "spectrum-three-fields",
        '<shape type="cube"><bsdf type="diffuse"><spectrum name="reflectance" value="400:1:2"/></bsdf></shape>',
        "shape/bsdf/spectrum@value",
        "expected 'wavelength:value' pairs",
    ),
    (
        "spectrum-word",
        '<shape type="cube"><bsdf type="diffuse"><spectrum name="reflectance" value="abc:2"/></bsdf></shape>',
        "shape/bsdf/spectrum@value",
        "expected a finite number, got 'abc'",
    ),
    (
        "spectrum-empty",
        '<shape type="cube"><bsdf type="diffuse"><spectrum name="reflectance" value=""/></bsdf></shape>',
        "shape/bsdf/spectrum@value",
        "expected numbers, got an empty value",
    ),
    (
        "spectrum-unsorted",
        '<shape type="cube"><bsdf type="diffuse"><spectrum name="reflectance" '
        'value="700:0.5, 400:0.2"/></bsdf></shape>',
        "shape/bsdf/spectrum@value",
        "wavelengths must increase, got 700 then 400",
    ),
    (
        "spectrum-duplicate",
        '<shape type="cube"><bsdf type="diffuse"><spectrum name="reflectance" '
        'value="400:0.5, 550:0.3, 550:0.2"/></bsdf></shape>',
        "shape/bsdf/spectrum@value",
        "wavelengths must increase, got 550 then 550",
    ),
    (
        "spectrum-negative",
        '<shape type="cube"><bsdf type="diffuse"><spectrum name="reflectance" '
        'value="400:-0.5, 700:0.2"/></bsdf></shape>',
        "shape/bsdf/spectrum@value",
        "negative value -0.5",
    ),
    (
        "rgb-negative",
        '<shape type="cube"><emitter type="area"><rgb name="radiance" value="1, -2, 1"/></emitter></shape>',
        "shape/emitter/rgb@value",
        "negative value -2",
    ),
    (
        "irregular-lengths",
        '<emitter type="constant"><spectrum name="radiance" type="irregular">'
        '<string name="wavelengths" value="400, 500, 600"/><string name="values" value="1, 2"/></spectrum></emitter>',
        "emitter/spectrum/string[1]@value",
        "3 wavelengths but 2 values",
    ),
    (
        "blackbody-zero",
        '<emitter type="constant"><spectrum name="radiance" type="blackbody">'
        '<float name="temperature" value="0"/></spectrum></emitter>',
        "emitter/spectrum/float@value",
        "temperature must be > 0 K, got 0",
    ),
    (
        "blackbody-negative",
        '<emitter type="constant"><spectrum name="radiance" type="blackbody">'
        '<float name="temperature" value="-300"/></spectrum></emitter>',
        "emitter/spectrum/float@value",
        "temperature must be > 0 K, got -300",
    ),
    (
        "blackbody-missing",
        '<emitter type="constant"><spectrum name="radiance" type="blackbody"/></emitter>',
        "emitter/spectrum",
        "spectrum 'blackbody' needs a property named 'temperature'",
    ),
    (
        "missing-value",
        '<shape type="sphere"><float name="radius"/></shape>',
        "shape/float@value",
        "<float> needs the attribute 'value'",
    ),
    (
        "missing-type",
        CUBE + '<shape><float name="radius" value="2"/></shape>',
        "shape[1]@type",
        "<shape> needs the attribute 'type'",
    ),
    (
        "missing-name",
        '<shape type="sphere"><float value="2"/></shape>',
        "shape/float@name",
        "<float> needs the attribute 'name'",
    ),
    (
        "missing-ref-id",
        '<shape type="cube"><ref name="bsdf"/></shape>',
        "shape/ref@id",
        "<ref> needs the attribute 'id'",
    ),
    ("missing-default-value", '<default name="r"/>' + CUBE, "default@value", "<default> needs the attribute 'value'"),
    ("missing-filename", '<shape type="obj"/>', "shape", "shape 'obj' needs a property named 'filename'"),
    (
        "unknown-parameter",
        '<shape type="sphere"><float name="radius" value="$r"/></shape>',
        "shape/float@value",
        "undefined parameter $r",
    ),
    (
        "reference-cycle",
        '<bsdf type="twosided" id="a"><ref id="a"/></bsdf><shape type="cube"><ref id="a"/></shape>',
        "bsdf",
        "bsdf 'twosided' refers to itself",
    ),
    ("zero-width", CUBE, "sensor/film/integer[0]@value", "must be at least 1, got 0"),
    (
        "face-normals-not-boolean",
        '<shape type="sphere"><boolean name="face_normals" value="yes"/></shape>',
        "shape/boolean@value",
        "expected true or false, got 'yes'",
    ),
    (
        "reflectance-above-one",
        '<shape type="cube"><bsdf type="diffuse" id="hot"><rgb name="reflectance" '
        'value="1.5, 0.2, 0.2"/></bsdf></shape>',
        "shape/bsdf",
        "a reflectance rgb must lie in [0, 1], got [1.5, 0.2, 0.2] (imported as materials.hot.reflectance.rgb)",
    ),
    (
        "spd-line",
        '<emitter type="point"><spectrum name="intensity" filename="bad.spd"/></emitter>',
        "emitter/spectrum@filename",
        "line 3 of 'bad.spd': expected 'wavelength value', got '500 2 7'",
    ),
]
ZERO_WIDTH_SENSOR = """<sensor type="perspective"><float name="fov" value="45"/>
    <film type="hdrfilm"><integer name="width" value="0"/><integer name="height" value="6"/></film></sensor>"""


def _assert_one_error_line(status: int, stderr: str, place: str, says: str) -> None:
    assert status == 2, stderr
    assert "Traceback" not in stderr and stderr.count("\n") == 1, stderr
    assert stderr.startswith(f"error: {place}: "), stderr
    assert says in stderr, stderr


@pytest.mark.parametrize("name, body, path, says", BAD_INPUT, ids=[case[0] for case in BAD_INPUT])
def test_bad_input_is_one_line_naming_file_and_element(tmp_path, monkeypatch, capsys, name, body, path, says):
    (tmp_path / "bad.spd").write_text("400 1\n# a comment\n500 2 7\n")
    xml = _write(tmp_path, body, ZERO_WIDTH_SENSOR if name == "zero-width" else None)
    out = tmp_path / "out.toml"
    status, stderr = _run_in_process(monkeypatch, capsys, ["import-mitsuba", str(xml), "-o", str(out)])
    _assert_one_error_line(status, stderr, f"{xml}: {path}", says)
    assert not out.exists()


@pytest.mark.parametrize(
    "text, says",
    [
        ('<scene version="3.0.0"><shape type="cube"></scene>', "XML syntax error: mismatched tag (line 1, column "),
        ("<scene>" + "<bsdf>" * 2000 + "</bsdf>" * 2000 + "</scene>", "elements nested more than 64 deep (line 1)"),
        ('<shape type="cube"/>', "not a Mitsuba scene: the root element must be <scene>"),
    ],
    ids=["malformed", "nested-2000-deep", "not-a-scene"],
)
def test_unreadable_xml_is_one_line(tmp_path, monkeypatch, capsys, text, says):
    xml = tmp_path / "scene.xml"
    xml.write_text(text)
    status, stderr = _run_in_process(monkeypatch, capsys, ["import-mitsuba", str(xml), "-o", str(tmp_path / "o.toml")])
    _assert_one_error_line(status, stderr, str(xml), says)


@pytest.mark.subprocess
@pytest.mark.slow
def test_a_real_process_prints_only_the_line_and_keeps_the_old_output(tmp_path):
    """A failed import (elements 2000 deep, once a RecursionError; a value the loader refuses in the final check)
    exits with status 2 and one line, and the TOML already there is left as it was, with no temporary file."""
    out = tmp_path / "scene.toml"
    out.write_text("# the previous import\n")
    for body, says in [
        ("<bsdf>" * 2000 + "</bsdf>" * 2000 + CUBE, "elements nested more than 64 deep"),
        (
            '<shape type="cube"><bsdf type="diffuse"><float name="reflectance" value="2"/></bsdf></shape>',
            "reflectance exceeds 1",
        ),
    ]:
        xml = _write(tmp_path, body)
        result = run_spectrace("import-mitsuba", str(xml), "-o", str(out), timeout=300)
        assert result.returncode == 2 and result.stdout == "", result.stderr
        assert result.stderr.count("\n") == 1 and result.stderr.startswith(f"error: {xml}"), result.stderr
        assert says in result.stderr and "Traceback" not in result.stderr
        assert out.read_text() == "# the previous import\n"
        assert sorted(path.name for path in tmp_path.iterdir()) == ["scene.toml", "scene.xml"]


def test_outputs_that_cannot_be_written_are_refused_before_the_import(tmp_path, monkeypatch, capsys):
    xml = _write(tmp_path, CUBE)
    (tmp_path / "folder").mkdir()
    (tmp_path / "file.txt").write_text("")
    for output, place, says in [
        (tmp_path / "folder", tmp_path / "folder", "--output names a folder; name a file in it"),
        (f"{tmp_path / 'new'}/", f"{tmp_path / 'new'}/", "names a folder"),
        (tmp_path / "file.txt" / "out.toml", tmp_path / "file.txt" / "out.toml", "is not a folder"),
        (xml, xml, "is the Mitsuba scene being imported"),
    ]:
        status, stderr = _run_in_process(monkeypatch, capsys, ["import-mitsuba", str(xml), "-o", str(output)])
        _assert_one_error_line(status, stderr, str(place), says)
    assert xml.read_text().startswith("<scene")
    # A missing folder is created, as `spectrace render` creates the image's.
    status, stderr = _run_in_process(
        monkeypatch, capsys, ["import-mitsuba", str(xml), "-o", str(tmp_path / "a" / "b" / "out.toml")]
    )
    assert status == 0 and (tmp_path / "a" / "b" / "out.toml").is_file(), stderr


def test_a_read_only_folder_is_refused_before_the_import(tmp_path, monkeypatch, capsys):
    xml = _write(tmp_path, '<shape type="cube"><float name="fov" value="nan"/></shape>')  # never read
    locked = tmp_path / "locked"
    locked.mkdir()
    locked.chmod(0o555)
    try:
        # root may write to a read-only folder; Linux's /proc/sys is read-only even for root.
        folder = next((f for f in (locked, Path("/proc/sys")) if f.is_dir() and not os.access(f, os.W_OK)), None)
        if folder is None:
            pytest.skip("no read-only folder for this user")
        status, stderr = _run_in_process(
            monkeypatch, capsys, ["import-mitsuba", str(xml), "-o", str(folder / "out.toml")]
        )
        _assert_one_error_line(
            status, stderr, str(folder / "out.toml"), f"cannot create files in the folder {folder} for --output"
        )
    finally:
        locked.chmod(0o755)


def test_a_failed_check_leaves_the_existing_output(tmp_path):
    """The import succeeds but the loader refuses the result (a film too large): the old file stays."""
    from spectrace.interop.mitsuba import import_mitsuba

    sensor = """<sensor type="perspective"><film type="hdrfilm"><integer name="width" value="100000"/></film>
        </sensor>"""
    xml = _write(tmp_path, CUBE, sensor)
    out = tmp_path / "out.toml"
    out.write_text("# keep\n")
    with pytest.raises(SpectraceError) as error:
        import_mitsuba(xml, out)
    assert error.value.where == f"{xml}: sensor/film" and "(imported as film.width" in error.value.message
    assert out.read_text() == "# keep\n" and sorted(p.name for p in tmp_path.iterdir()) == ["out.toml", "scene.xml"]


# ---------------------------------------------------------------- numbers read back as written


def test_numbers_are_written_as_in_the_xml_and_read_back_exactly(tmp_path):
    """3.9 stays 3.9; Mitsuba's serialiser writes the float32 nearest 3.9 as 3.9000000953674316, which comes out
    as 3.9 too, and reads back as the same float32. Values that are not float32 read back as the same double."""
    import tomllib

    from spectrace.interop.mitsuba import import_mitsuba

    sensor = """<sensor type="perspective"><float name="fov" value="40"/>
        <transform name="to_world"><lookat origin="0, 0, 3.9" target="0, 0, 0" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="6"/></film></sensor>"""
    body = """<shape type="cube"><transform name="to_world">
            <translate x="0.1" y="3.9000000953674316" z="-1.2345678901234567"/></transform></shape>
        <emitter type="directional"><vector name="direction" value="0, -1, 0"/>
            <spectrum name="irradiance" type="blackbody"><float name="temperature" value="6504"/></spectrum>
        </emitter>"""
    xml = _write(tmp_path, body, sensor)
    out = tmp_path / "out.toml"
    import_mitsuba(xml, out)
    text = out.read_text()
    assert "origin = [0.0, 0.0, 3.9]" in text
    assert "translate = [0.1, 3.9, -1.2345678901234567]" in text
    assert "3.9000000953674316" not in text
    data = tomllib.loads(text)
    assert data["camera"]["origin"][2] == 3.9  # exactly the double the XML's text means
    translate = data["shapes"][0]["transform"][0]["translate"]
    assert translate[0] == 0.1 and translate[2] == -1.2345678901234567
    assert np.float32(translate[1]) == np.float32(3.9000000953674316)
    expected, _ = mitsuba_scene_data(xml)
    assert data["lights"][0]["irradiance"]["scale"] == expected["lights"][0]["irradiance"]["scale"]


def test_float_text_reads_back_at_the_precision_of_the_value():
    from spectrace.interop.toml_writer import float_text

    rng = np.random.default_rng(7)
    doubles = rng.standard_normal(2000) * 10.0 ** rng.integers(-30, 30, 2000)
    singles = doubles.astype(np.float32).astype(float)
    for value in doubles:
        assert float(float_text(float(value))) == value
    for value in singles:
        text = float_text(float(value))
        assert np.float32(float(text)) == np.float32(value)
        assert len(text) <= len(repr(float(value)))
    assert float_text(0.1) == "0.1" and float_text(float(np.float32(0.1))) == "0.1"
    assert float_text(1e300) == "1e+300" and float_text(-0.0) == "-0.0"
    # numpy's float64 is a float, but its repr is not TOML: an rgb medium coefficient uplifted by numpy was written so
    value = np.float64(0.06643712080068864)
    assert float(float_text(value)) == value and "np" not in float_text(value)
