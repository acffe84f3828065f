"""The TOML scene loader: resolved values, and one-line errors that name the file and key path."""

import textwrap

import numpy as np
import pytest

from scene_text import camera_film, diffuse
from spectrace.errors import SpectraceError
from spectrace.resources import scenes_dir
from spectrace.scene import load_scene
from spectrace.spectral.colorimetry import reflectance_to_xyz, xyz_to_linear_srgb
from spectrace.spectral.illuminants import d65_normalised


def _minimal(reflectance="value = 0.5", extra=""):
    """A grey rectangle seen by the shared camera, with `reflectance` inside its material's inline table."""
    return (
        camera_film()
        + diffuse("grey", reflectance)
        + """
[[shapes]]
type = "rectangle"
material = "grey"
transform = [{ scale = 2 }, { translate = [0, 0, -1] }]
"""
        + extra
        + "\n"
    )


def _write(tmp_path, reflectance="value = 0.5", extra="", text=None):
    path = tmp_path / "scene.toml"
    path.write_text(text if text is not None else _minimal(reflectance=reflectance, extra=extra))
    return path


def test_cornell_box_loads_with_measured_spectra():
    scene = load_scene(scenes_dir() / "cornell_box.toml")
    assert (scene.width, scene.height, scene.max_depth) == (256, 256, 8)
    names = [s.name for s in scene.shapes]
    assert names == ["white surfaces", "left wall", "right wall", "light"]
    red = scene.shapes[1].material.reflectance
    assert red.evaluate(650.0) > 4 * red.evaluate(500.0)  # the measured red wall reflects long wavelengths
    light = scene.shapes[3].emitter
    assert light is not None and not light.two_sided
    assert light.radiance.evaluate(500.0) == pytest.approx(8.0) and light.radiance.evaluate(600.0) == pytest.approx(
        15.6
    )


def test_transforms_apply_in_order(tmp_path):
    scene = load_scene(_write(tmp_path))
    vertices = scene.shapes[0].mesh.vertices
    # the unit rectangle [-1, 1]² scaled by 2, then moved to z = -1
    assert np.allclose(np.abs(vertices[:, :2]), 2.0)
    assert np.allclose(vertices[:, 2], -1.0)


def test_rgb_reflectance_is_uplifted_to_that_colour(tmp_path):
    scene = load_scene(_write(tmp_path, reflectance="rgb = [0.7, 0.2, 0.1]"))
    spectrum = scene.shapes[0].material.reflectance
    rgb = xyz_to_linear_srgb(reflectance_to_xyz(spectrum, d65_normalised()))
    np.testing.assert_allclose(rgb, [0.7, 0.2, 0.1], atol=1e-3)


def test_emitter_scale_multiplies_the_spectrum(tmp_path):
    extra = 'emitter = { radiance = { values = "400:1, 700:3", scale = 2.5 }, two_sided = true }'
    emitter = load_scene(_write(tmp_path, extra=extra)).shapes[0].emitter
    assert emitter.two_sided
    assert emitter.radiance.evaluate(550.0) == pytest.approx(2.5 * 2.0)


@pytest.mark.parametrize(
    "reflectance, extra, where, message",
    [
        ("value = 0.5", "colour = 1", "shapes[0].colour", "unknown key 'colour'"),
        ("value = 1.5", "", "materials.grey.reflectance", "reflectance exceeds 1"),
        ("rgb = [0.5, -0.1, 0.2]", "", "materials.grey.reflectance.rgb", ">= 0"),
        ("value = 0.5, rgb = [1, 1, 1]", "", "materials.grey.reflectance", "exactly one"),
        ('spectrum = "nope"', "", "materials.grey.reflectance.spectrum", "undefined spectrum 'nope'"),
        ('values = "400:0.1, 380:0.2"', "", "materials.grey.reflectance.values", ""),
        ('file = "missing.csv"', "", "missing.csv", ""),
    ],
)
def test_bad_input_names_file_and_key(tmp_path, reflectance, extra, where, message):
    path = _write(tmp_path, reflectance=reflectance, extra=extra)
    with pytest.raises(SpectraceError) as info:
        load_scene(path)
    text = str(info.value)
    assert "\n" not in text
    assert where in text and message in text


def test_camera_errors(tmp_path):
    text = _minimal(reflectance="value = 0.5", extra="").replace("fov = 40", "fov = 180")
    with pytest.raises(SpectraceError, match=r"scene.toml: camera.fov: .*\(0, 180\)"):
        load_scene(_write(tmp_path, text=text))
    text = _minimal(reflectance="value = 0.5", extra="").replace("origin = [0, 0, 5]", "origin = [0, 0, 0]")
    with pytest.raises(SpectraceError, match="camera.target: camera target equals origin"):
        load_scene(_write(tmp_path, text=text))
    text = _minimal(reflectance="value = 0.5", extra="").replace("fov = 40", "fov = 40\nup = [0, 0, 1]")
    with pytest.raises(SpectraceError, match="camera.up: .*parallel"):
        load_scene(_write(tmp_path, text=text))


def test_toml_syntax_error_gives_line_and_column(tmp_path):
    path = _write(tmp_path, text="[camera\norigin = [0, 0, 0]\n")
    with pytest.raises(SpectraceError, match=r"scene.toml: TOML syntax error: .*line 1, column 8"):
        load_scene(path)


def test_a_byte_order_mark_is_accepted(tmp_path):
    """Notepad and other Windows editors start UTF-8 files with a BOM, which TOML itself does not allow."""
    plain = load_scene(_write(tmp_path, reflectance="value = 0.25"))
    path = tmp_path / "bom.toml"
    path.write_bytes(b"\xef\xbb\xbf" + _minimal(reflectance="value = 0.25", extra="").encode())
    with_bom = load_scene(path)
    np.testing.assert_array_equal(with_bom.shapes[0].mesh.vertices, plain.shapes[0].mesh.vertices)
    assert with_bom.shapes[0].material.reflectance.evaluate(550.0) == pytest.approx(0.25)


@pytest.mark.parametrize(
    "nested",
    [
        "[" * 5000 + "]" * 5000,  # arrays: tomllib recurses and runs out of stack
        "{ a = " * 5000 + "1" + " }" * 5000,  # inline tables: likewise
        "[" * 65 + "]" * 65,  # parses, but deeper than any scene
    ],
)
def test_deep_nesting_is_one_line(tmp_path, nested):
    path = _write(tmp_path, extra=f"deep = {nested}")
    with pytest.raises(SpectraceError, match="nested (too deep to parse|more than 64 levels deep)") as caught:
        load_scene(path)
    assert str(caught.value).startswith(str(path)) and "\n" not in str(caught.value)


def test_named_spectra_and_library_references(tmp_path):
    text = textwrap.dedent(_minimal(reflectance='spectrum = "mine"', extra="")) + textwrap.dedent(
        """
        [spectra.mine]
        values = "360:0.2, 830:0.6"
        """
    )
    spectrum = load_scene(_write(tmp_path, text=text)).shapes[0].material.reflectance
    assert spectrum.evaluate(595.0) == pytest.approx(0.4)


def _with_material(tmp_path, material: str):
    """The minimal scene with [materials.grey] replaced by `material` (its keys after the table header)."""
    text = _minimal(reflectance="value = 0.5", extra="").replace(
        'type = "diffuse"\nreflectance = { value = 0.5 }', textwrap.dedent(material).strip()
    )
    return _write(tmp_path, text=text)


def test_reflective_materials_resolve(tmp_path):
    gold = load_scene(_with_material(tmp_path, 'type = "conductor"\nmetal = "Au"\nroughness = 0.25'))
    material = gold.shapes[0].material
    assert type(material).__name__ == "ConductorMaterial" and material.roughness == 0.25
    # Gold's measured index at 600 nm (spectra/metals/Au.csv lies between these rows).
    assert 0.2 < material.eta.evaluate(600.0) < 0.3 and 2.9 < material.k.evaluate(600.0) < 3.1
    custom = (
        load_scene(
            _with_material(
                tmp_path,
                'type = "conductor"\neta = { value = 1.5 }\nk = { value = 2.0 }\nspecular_tint = { value = 0.5 }',
            )
        )
        .shapes[0]
        .material
    )
    assert custom.k.evaluate(500.0) == 2.0 and custom.specular_tint.evaluate(500.0) == 0.5
    plastic = load_scene(_with_material(tmp_path, 'type = "plastic"\nreflectance = { value = 0.3 }')).shapes[0].material
    assert (plastic.ior, plastic.roughness) == (1.5, 0.0)
    mirror = load_scene(_with_material(tmp_path, 'type = "mirror"')).shapes[0].material
    assert mirror.reflectance.evaluate(550.0) == 1.0
    retro = load_scene(_with_material(tmp_path, 'type = "retroreflector"')).shapes[0].material
    assert retro.roughness == 0.1


@pytest.mark.parametrize(
    "material, where, message",
    [
        ('type = "conductor"\nmetal = "Pt"', "materials.grey.metal", "got 'Pt'"),
        ('type = "conductor"', "materials.grey", "give metal"),
        ('type = "conductor"\nmetal = "Au"\neta = { value = 1 }', "materials.grey", "not both"),
        ('type = "conductor"\neta = { rgb = [1, 1, 1] }\nk = { value = 1 }', "materials.grey.eta", "not a colour"),
        ('type = "conductor"\neta = { value = -0.5 }\nk = { value = 1 }', "materials.grey.eta", "negative"),
        ('type = "conductor"\neta = { value = 1 }\nk = { value = -1 }', "materials.grey.k", "negative"),
        ('type = "conductor"\nmetal = "Au"\nroughness = 2', "materials.grey.roughness", "must be ≤ 1"),
        (
            'type = "conductor"\nmetal = "Au"\nspecular_tint = { value = 2 }',
            "materials.grey.specular_tint",
            "exceeds 1",
        ),
        ('type = "plastic"\nreflectance = { value = 0.5 }\nior = 1.0', "materials.grey.ior", "must be > 1"),
        (
            'type = "plastic"\nreflectance = { value = 0.5 }\nroughnes = 0.1',
            "materials.grey.roughnes",
            "did you mean 'roughness'",
        ),
        ('type = "mirror"\nreflectance = { value = 1.5 }', "materials.grey.reflectance", "exceeds 1"),
        (
            'type = "glass"',
            "materials.grey.type",
            "unknown type 'glass' (one of 'diffuse', 'conductor'",
        ),
        ("reflectance = { value = 0.5 }", "materials.grey.type", "required key is missing"),
    ],
)
def test_bad_material_names_file_and_key(tmp_path, material, where, message):
    with pytest.raises(SpectraceError) as info:
        load_scene(_with_material(tmp_path, material))
    text = str(info.value)
    assert "\n" not in text
    assert f"scene.toml: {where}" in text and message in text, text
