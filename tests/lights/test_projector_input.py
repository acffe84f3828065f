"""A projector's bad keys: one line naming the file and key path; from the command line exit status 2, no traceback,
the output not written."""

import pytest

import spectrace
from cli_runner import run_spectrace
from spectrace.errors import SpectraceError

SCENE = """[camera]
origin = [0, 0, 5]
target = [0, 0, 0]
fov = 40

[film]
width = 8
height = 8

[materials.m]
type = "diffuse"
reflectance = {{ value = 0.5 }}

[[shapes]]
type = "sphere"
material = "m"

[[lights]]
type = "projector"
position = [0, 0, 2]
target = [0, 0, 0]
intensity = {{ value = 1 }}
{key}
"""


BAD = [
    ('profile = "foo"', "lights[0].profile: profile must be one of irradiance, intensity"),
    ('fov_axis = "diagonal"', "lights[0].fov_axis: fov_axis must be one of width, shorter"),
    ("up = [0, 0, 1]", "lights[0].up: up must not lie along the axis"),
    ("image = { value = 0.5 }", "lights[0].image: an image is a texture"),
    ("fov = 180", "lights[0].fov: must be < 180"),
]


@pytest.mark.parametrize(("key", "message"), BAD, ids=["profile", "fov_axis", "up", "image", "fov"])
def test_bad_projector_keys_name_file_and_key(tmp_path, key, message):
    scene = tmp_path / "projector.toml"
    scene.write_text(SCENE.format(key=key))
    with pytest.raises(SpectraceError) as error:
        spectrace.load_scene(scene)
    assert "projector.toml" in str(error.value) and message in str(error.value) and "\n" not in str(error.value)


@pytest.mark.subprocess
@pytest.mark.slow
def test_a_bad_projector_key_exits_with_one_line(tmp_path):
    key, message = BAD[0]
    scene = tmp_path / "projector.toml"
    scene.write_text(SCENE.format(key=key))
    out = tmp_path / "out.png"
    result = run_spectrace("render", str(scene), "-o", str(out), "-q")
    assert result.returncode == 2, result.stderr
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and "projector.toml" in lines[0] and message in lines[0], result.stderr
    assert "Traceback" not in result.stderr and not out.exists()
