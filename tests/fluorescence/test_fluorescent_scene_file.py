"""A fluorescent material in a scene file: its base named like a mix's materials, its keys' errors naming the key
path, and the integrators that keep each wavelength refusing it in one line through the command line."""

import pytest

import spectrace
from cli_runner import run_spectrace
from scene_text import camera_film
from spectrace.errors import SpectraceError
from spectrace.materials.fluorescent import FluorescentMaterial
from spectrace.scene.loader import load_scene

SCENE = (
    camera_film(width="8", height="8")
    + """[integrator]
type = "{integrator}"
[sampler]
spp = 2
[materials.paper]
type = "diffuse"
reflectance = {{ value = 0.8 }}
[materials.dye]
type = "fluorescent"
base = "{base}"
excitation = {{ values = [[360, 0.9], [420, 0.9], [440, 0.0], [830, 0.0]] }}
emission = {{ values = [[360, 0.0], [430, 0.0], [450, 1.0], [500, 0.0], [830, 0.0]] }}
quantum_yield = {quantum_yield}
[[shapes]]
type = "sphere"
material = "dye"
[[lights]]
type = "constant"
radiance = {{ value = 1.0 }}
"""
)


def _scene_file(tmp_path, integrator="path", base="paper", quantum_yield="0.7"):
    path = tmp_path / "dye.toml"
    path.write_text(SCENE.format(integrator=integrator, base=base, quantum_yield=quantum_yield), encoding="utf-8")
    return path


def test_the_scene_file_and_the_api_resolve_the_same_material(tmp_path):
    material = load_scene(_scene_file(tmp_path)).shapes[0].material
    assert isinstance(material, FluorescentMaterial) and material.key == "materials.dye"
    made = spectrace.fluorescent(spectrace.diffuse(0.8), material.excitation, material.emission, 0.7)
    assert made == material


def test_the_yield_takes_a_grey_texture(tmp_path):
    texture = '{ texture = "checkerboard", color0 = { value = 0.2 }, color1 = { value = 0.9 } }'
    material = load_scene(_scene_file(tmp_path, quantum_yield=texture)).shapes[0].material
    assert spectrace.textures.is_texture(material.quantum_yield)


@pytest.mark.parametrize(
    "base, quantum_yield, key",
    [("nothing", "0.7", "materials.dye.base"), ("dye", "0.7", "materials.dye.base"), ("paper", "2", "quantum_yield")],
)
def test_a_bad_key_is_named(tmp_path, base, quantum_yield, key):
    with pytest.raises(SpectraceError) as error:
        load_scene(_scene_file(tmp_path, base=base, quantum_yield=quantum_yield))
    assert key in str(error.value)


@pytest.mark.subprocess
@pytest.mark.slow
def test_sppm_refuses_it_in_one_line_and_writes_nothing(tmp_path):
    out = tmp_path / "out.png"
    out.write_bytes(b"kept")
    result = run_spectrace("render", str(_scene_file(tmp_path, integrator="sppm")), "-o", str(out))
    assert result.returncode != 0
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and "materials.dye" in lines[0] and "integrator 'sppm'" in lines[0], result.stderr
    assert "Traceback" not in result.stderr
    assert out.read_bytes() == b"kept"
