"""The Python API: a scene built from Python objects (trimesh meshes, colour-science and numpy spectra) renders
exactly like the same scene written as TOML; the helpers' conversions and checks."""

import io

import colour
import numpy as np
import pytest
import trimesh
from PIL import Image as PILImage

import spectrace
from scene_text import camera_film
from spectrace.engine.renderer import Renderer
from spectrace.errors import SpectraceError
from spectrace.spectral.grid import GRID_NM

SCENE_TOML = (
    camera_film(origin="[0.0, 1.0, -4.0]", target="[0.0, 0.6, 0.0]", fov="50.0", width="20", height="15")
    + """
[integrator]
max_depth = 5

[sampler]
spp = 4
seed = 3

[materials.clay]
type = "diffuse"
reflectance = { rgb = [0.7, 0.3, 0.2] }

[materials.floor]
type = "diffuse"
reflectance = { values = "400:0.2, 550:0.5, 700:0.8" }

[[shapes]]
type = "rectangle"
material = "floor"
transform = [{ rotate = { axis = [1, 0, 0], angle = -90 } }, { scale = 3 }]

[[shapes]]
type = "mesh"
file = "box.obj"
material = "clay"
transform = [{ rotate = { axis = [0, 1, 0], angle = 30 } }, { translate = [0.3, 0.5, 0.5] }]

[[shapes]]
type = "rectangle"
material = "floor"
transform = [{ scale = 0.4 }, { rotate = { axis = [1, 0, 0], angle = 90 } }, { translate = [0, 2.5, 0] }]
emitter = { radiance = { spectrum = "cie:A", scale = 0.05 } }

[[lights]]
type = "point"
position = [-1.5, 2.0, -1.0]
power = 30.0
spectrum = { values = [[400, 1.0], [600, 2.0], [700, 0.5]] }

[[lights]]
type = "constant"
radiance = { value = 0.02 }
"""
)


def _box() -> trimesh.Trimesh:
    return trimesh.creation.box(extents=(1.0, 1.0, 1.0))


def _scene_in_python() -> spectrace.Scene:
    floor = spectrace.diffuse(colour.SpectralDistribution({400: 0.2, 550: 0.5, 700: 0.8}))
    clay = spectrace.diffuse((0.7, 0.3, 0.2))
    shapes = [
        spectrace.shape("rectangle", floor, transform=[{"rotate": {"axis": [1, 0, 0], "angle": -90}}, {"scale": 3}]),
        spectrace.shape(
            _box(), clay, transform=[{"rotate": {"axis": [0, 1, 0], "angle": 30}}, {"translate": [0.3, 0.5, 0.5]}]
        ),
        spectrace.shape(
            "rectangle",
            floor,
            emitter=spectrace.area_emitter(spectrace.spectrum("cie:A", scale=0.05)),
            transform=[{"scale": 0.4}, {"rotate": {"axis": [1, 0, 0], "angle": 90}}, {"translate": [0, 2.5, 0]}],
        ),
    ]
    lights = [
        spectrace.point_light(
            (-1.5, 2.0, -1.0), power_w=30.0, spectrum=(np.array([400.0, 600.0, 700.0]), np.array([1.0, 2.0, 0.5]))
        ),
        spectrace.constant_environment(0.02),
    ]
    camera = spectrace.Camera(origin=(0.0, 1.0, -4.0), target=(0.0, 0.6, 0.0), fov_degrees=50.0)
    return spectrace.Scene(camera=camera, width=20, height=15, shapes=shapes, lights=lights, max_depth=5, spp=4, seed=3)


def test_python_scene_renders_like_the_same_toml_scene(tmp_path, device):
    _box().export(tmp_path / "box.obj")
    (tmp_path / "scene.toml").write_text(SCENE_TOML)
    from_toml = Renderer(spectrace.load_scene(tmp_path / "scene.toml"), device).render()
    calls = []
    from_python = spectrace.render(
        _scene_in_python(), device=device, progress=lambda done, total: calls.append((done, total))
    )
    assert from_toml.xyz[..., 1].mean() > 0
    np.testing.assert_array_equal(from_python.xyz, from_toml.xyz)  # the sampler is deterministic: bit for bit
    assert calls and calls[-1] == (4, 4) and [done for done, _ in calls] == sorted(done for done, _ in calls)


def test_per_wavelength_data_when_asked(device):
    scene = _scene_in_python().with_overrides(spp=2)
    image = spectrace.render(scene, device=device, spectral_bins=10)
    assert image.spectral.radiance.shape == (15, 20, 10)
    np.testing.assert_allclose(image.spectral.edges_nm[[0, -1]], (360.0, 830.0))


def test_spectrum_forms_agree():
    wavelengths, values = np.array([380.0, 500.0, 760.0]), np.array([0.1, 0.9, 0.4])
    expected = np.interp(GRID_NM, wavelengths, values)  # linear between samples, end values held
    forms = [
        (wavelengths, values),
        np.stack([wavelengths, values], axis=1),
        [[380, 0.1], [500, 0.9], [760, 0.4]],
        {380: 0.1, 500: 0.9, 760: 0.4},
        colour.SpectralDistribution(dict(zip(wavelengths, values))),
        expected,
    ]
    for form in forms:
        np.testing.assert_allclose(spectrace.spectrum(form).values, expected, rtol=0, atol=1e-12)
    assert spectrace.spectrum(2.5, scale=2.0).values == pytest.approx(np.full(GRID_NM.size, 5.0))
    assert spectrace.spectrum("cie:D65").values[GRID_NM == 560][0] == pytest.approx(100.0)  # CIE's own scale
    with pytest.raises(SpectraceError):
        spectrace.spectrum({"a": 1})
    with pytest.raises(SpectraceError):
        spectrace.spectrum(object())


def test_rgb_helpers_reproduce_their_colour():
    from spectrace.spectral import reflectance_to_xyz, spectrum_to_xyz, xyz_to_linear_srgb
    from spectrace.spectral.illuminants import cie_illuminant

    reflectance = spectrace.rgb_reflectance((0.2, 0.5, 0.8))
    rgb = xyz_to_linear_srgb(reflectance_to_xyz(reflectance, cie_illuminant("D65")))
    np.testing.assert_allclose(rgb, (0.2, 0.5, 0.8), atol=1e-5)
    emission = spectrace.rgb_emission((2.0, 1.0, 0.5), scale=3.0)
    np.testing.assert_allclose(xyz_to_linear_srgb(spectrum_to_xyz(emission)), (6.0, 3.0, 1.5), rtol=1e-4)


def test_mesh_from_trimesh_keeps_geometry_and_winding():
    source = trimesh.creation.icosphere(subdivisions=1)
    mesh = spectrace.mesh_from_trimesh(source)
    assert mesh.area() == pytest.approx(source.area)
    v0, v1, v2 = mesh.triangles()
    normals = np.cross(v1 - v0, v2 - v0)
    np.testing.assert_allclose(normals / np.linalg.norm(normals, axis=1, keepdims=True), source.face_normals, atol=1e-9)
    merged = spectrace.mesh_from_trimesh(trimesh.Scene([source, _box()]))
    assert len(merged.faces) == len(source.faces) + 12


def test_power_of_a_point_light():
    # Φ = ∫ 4π I(λ) dλ must give back the power asked for, for any spectral shape.
    light = spectrace.point_light((0, 0, 0), power_w=60.0, spectrum="cie:A")
    from spectrace.spectral.grid import integrate_on_grid

    assert 4 * np.pi * integrate_on_grid(light.intensity.values) == pytest.approx(60.0)
    with pytest.raises(SpectraceError):
        spectrace.point_light((0, 0, 0))


def test_bad_input_is_a_spectrace_error():
    with pytest.raises(SpectraceError, match="reflectance"):
        spectrace.diffuse(1.5)
    with pytest.raises(SpectraceError):
        spectrace.area_emitter(-1.0)
    with pytest.raises(SpectraceError):
        spectrace.shape("torus", spectrace.diffuse(0.5))
    with pytest.raises(SpectraceError):
        spectrace.render("scene.toml")
    scene = _scene_in_python()
    from dataclasses import replace

    tilted = replace(scene, camera=spectrace.Camera(origin=(0, 0, 0), target=(0, 1, 0), up=(0, 1, 0)))
    with pytest.raises(SpectraceError, match="camera.up"):
        spectrace.render(tilted)


def test_image_shows_in_a_notebook(device):
    image = spectrace.render(_scene_in_python().with_overrides(spp=1), device=device, progress=False)
    with PILImage.open(io.BytesIO(image._repr_png_())) as png:
        assert png.size == (20, 15) and png.mode == "RGB"
    assert image.to_srgb().shape == (15, 20, 3) and image.to_srgb().min() >= 0 and image.to_srgb().max() <= 1


def test_progress_bar_draws_and_finishes(device):
    # tqdm's bar when tqdm is installed (the notebook extra), else rich's; either must reach the full count.
    image = spectrace.render(_scene_in_python().with_overrides(spp=3), device=device, progress=True, pass_spp=1)
    assert image.spp == 3


MATERIALS_TOML = (
    camera_film(origin="[0.0, 0.0, -6.0]", target="[0.0, 0.0, 0.0]", fov="60.0", width="16", height="8")
    + """
[sampler]
spp = 2
seed = 5

[materials.mirror]
type = "mirror"
reflectance = { value = 0.9 }

[materials.gold]
type = "conductor"
metal = "Au"
roughness = 0.3

[materials.custom_metal]
type = "conductor"
eta = { values = "400:1.2, 700:0.3" }
k = { value = 3.0 }
specular_tint = { value = 0.8 }

[materials.plastic]
type = "plastic"
reflectance = { rgb = [0.2, 0.5, 0.7] }
ior = 1.6
roughness = 0.2

[materials.sign]
type = "retroreflector"
reflectance = { value = 0.7 }
roughness = 0.2

[[shapes]]
type = "sphere"
material = "mirror"
transform = [{ translate = [-3.0, 0.0, 0.0] }]

[[shapes]]
type = "sphere"
material = "gold"
transform = [{ translate = [-1.0, 0.0, 0.0] }]

[[shapes]]
type = "sphere"
material = "custom_metal"
transform = [{ translate = [1.0, 0.0, 0.0] }]

[[shapes]]
type = "sphere"
material = "plastic"
transform = [{ translate = [3.0, 0.0, 0.0] }]

[[shapes]]
type = "rectangle"
material = "sign"
transform = [{ scale = 5.0 }, { translate = [0.0, 0.0, 2.0] }]

[[lights]]
type = "constant"
radiance = { value = 0.5 }

[[lights]]
type = "point"
position = [0.0, 2.0, -5.0]
intensity = { value = 3.0 }
"""
)


def test_reflective_materials_render_like_the_same_toml_scene(tmp_path, device):
    (tmp_path / "materials.toml").write_text(MATERIALS_TOML)
    from_toml = Renderer(spectrace.load_scene(tmp_path / "materials.toml"), device).render()
    materials = [
        spectrace.mirror(0.9),
        spectrace.conductor("Au", roughness=0.3),
        spectrace.conductor(eta={400: 1.2, 700: 0.3}, k=3.0, specular_tint=0.8),
        spectrace.plastic((0.2, 0.5, 0.7), ior=1.6, roughness=0.2),
    ]
    shapes = [
        spectrace.shape("sphere", m, transform=[{"translate": [x, 0.0, 0.0]}])
        for m, x in zip(materials, (-3.0, -1.0, 1.0, 3.0))
    ]
    shapes.append(
        spectrace.shape(
            "rectangle",
            spectrace.retroreflector(0.7, roughness=0.2),
            transform=[{"scale": 5.0}, {"translate": [0.0, 0.0, 2.0]}],
        )
    )
    lights = [spectrace.constant_environment(0.5), spectrace.point_light((0.0, 2.0, -5.0), intensity=3.0)]
    scene = spectrace.Scene(
        camera=spectrace.Camera(origin=(0.0, 0.0, -6.0), target=(0.0, 0.0, 0.0), fov_degrees=60.0),
        width=16,
        height=8,
        shapes=shapes,
        lights=lights,
        spp=2,
        seed=5,
    )
    from_python = spectrace.render(scene, device=device, progress=False)
    assert from_toml.xyz[..., 1].mean() > 0
    np.testing.assert_array_equal(from_python.xyz, from_toml.xyz)


def test_bad_material_input_is_a_spectrace_error():
    with pytest.raises(SpectraceError, match="roughness"):
        spectrace.conductor("Au", roughness=1.5)
    with pytest.raises(SpectraceError, match="unknown metal"):
        spectrace.conductor("Pt")
    with pytest.raises(SpectraceError, match="either metal or eta and k, not both"):
        spectrace.conductor("Au", eta=1.5, k=2.0)
    with pytest.raises(SpectraceError, match=r"give metal \(.*\) or both eta and k"):
        spectrace.conductor(eta=1.5)
    with pytest.raises(SpectraceError, match="eta"):
        spectrace.conductor(eta=-0.5, k=1.0)
    with pytest.raises(SpectraceError, match="ior"):
        spectrace.plastic(0.5, ior=1.0)
    with pytest.raises(SpectraceError, match="reflectance"):
        spectrace.mirror(1.2)
    with pytest.raises(SpectraceError, match="reflectance"):
        spectrace.retroreflector(-0.1)


@pytest.mark.parametrize(
    ("toml_value", "make"),
    [
        ("{ value = 1.5 }", lambda: spectrace.diffuse(1.5)),
        ("{ value = -0.5 }", lambda: spectrace.plastic(-0.5)),
        ("{ rgb = [1.2, 0.5, 0.5] }", lambda: spectrace.diffuse((1.2, 0.5, 0.5))),
        ("{ rgb = [-0.1, 0.5, 0.5] }", lambda: spectrace.mirror([-0.1, 0.5, 0.5])),
        ("{ values = [[400, 0.5], [700, 1.3]] }", lambda: spectrace.retroreflector([[400, 0.5], [700, 1.3]])),
    ],
)
def test_the_api_and_the_loader_refuse_a_reflectance_with_the_same_message(tmp_path, toml_value, make):
    """A reflectance goes through one path (spectral/spectrum_input.py) from a scene file and from Python."""
    path = tmp_path / "scene.toml"
    path.write_text(
        camera_film()
        + f'[materials.m]\ntype = "diffuse"\nreflectance = {toml_value}\n'
        + '[[shapes]]\ntype = "sphere"\nmaterial = "m"\n',
        encoding="utf-8",
    )
    with pytest.raises(SpectraceError) as from_file:
        spectrace.load_scene(path)
    with pytest.raises(SpectraceError) as from_python:
        make()
    assert from_python.value.message == from_file.value.message
    assert from_python.value.where == "reflectance"
    assert from_file.value.where.startswith(f"{path}: materials.m.reflectance")


def test_the_api_and_the_loader_make_the_same_spectra(tmp_path):
    path = tmp_path / "scene.toml"
    path.write_text(
        camera_film()
        + '[materials.m]\ntype = "diffuse"\nreflectance = { rgb = [0.2, 0.5, 0.7] }\n'
        + '[[shapes]]\ntype = "sphere"\nmaterial = "m"\nemitter = { radiance = { rgb = [2.0, 1.0, 0.5] } }\n',
        encoding="utf-8",
    )
    loaded = spectrace.load_scene(path).shapes[0]
    assert np.array_equal(spectrace.diffuse((0.2, 0.5, 0.7)).reflectance.values, loaded.material.reflectance.values)
    assert np.array_equal(spectrace.area_emitter([2.0, 1.0, 0.5]).radiance.values, loaded.emitter.radiance.values)
