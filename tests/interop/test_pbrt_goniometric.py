"""pbrt-v4's goniometric light imported as spectrace's: for directions all round, the texel the imported light's
frame reads (spectrace's map frame, its handedness mirror included) is the one pbrt-v4 reads (its light-space
direction with y and z swapped, Clarberg's map written from the paper, the RGB averaged), whether or not the scene is
mirrored into spectrace's world; `power` gives the flux pbrt-v4's normalisation gives."""

import numpy as np
import pytest
from tests.cameras.test_equal_area_camera import sphere_to_square
from tests.interop.test_pbrt_analytic_shapes import MARKER, _rotate, _translate

from spectrace.interop.pbrt import load_pbrt_scene
from spectrace.io.exr import write_exr
from spectrace.lights.goniometric import GoniometricLight

N = 8
IMAGE = np.random.default_rng(3).uniform(0.1, 2.0, (N, N, 3)).astype(np.float32)


def _load(tmp_path, light_line: str, mirror: bool):
    write_exr(tmp_path / "gonio.exr", IMAGE, None, {})
    text = ("Scale -1 1 1\n" if mirror else "") + 'LookAt 0 0 5  0 0 0  0 1 0\nCamera "perspective"\n'
    text += 'Film "rgb" "integer xresolution" 8 "integer yresolution" 8\nWorldBegin\n' + MARKER
    text += f"AttributeBegin\nTranslate 0.2 0.1 -0.3\nRotate 30 1 0 0\nRotate 50 0 0 1\n{light_line}\nAttributeEnd\n"
    (tmp_path / "scene.pbrt").write_text(text)
    return load_pbrt_scene(tmp_path / "scene.pbrt")


@pytest.mark.parametrize("mirror", [False, True])
def test_imported_goniometric_light_reads_the_texel_pbrt_reads(tmp_path, mirror):
    scene = _load(tmp_path, 'LightSource "goniometric" "string filename" "gonio.exr" "float scale" 2', mirror)
    (light,) = scene.lights
    assert isinstance(light, GoniometricLight)
    np.testing.assert_allclose(light.image, IMAGE.mean(axis=2), rtol=1e-6)
    world = np.diag([np.sign(scene.shapes[0].analytic.to_world[0, 3]), 1.0, 1.0])  # spectrace's from pbrt's
    light_from_world = np.linalg.inv(
        (_translate(0.2, 0.1, -0.3) @ _rotate(30, [1, 0, 0]) @ _rotate(50, [0, 0, 1]))[:3, :3]
    )
    directions = np.random.default_rng(8).normal(size=(3000, 3))
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    local = directions @ light_from_world.T
    expected = sphere_to_square(local[:, [0, 2, 1]])  # pbrt: y and z swapped
    x, y, z = light.frame()
    seen = directions @ world.T
    got = sphere_to_square(np.stack([seen @ x, seen @ y, seen @ z], axis=1))
    # The same texel: away from texel edges (where float rounding may pick the neighbour) the same index.
    inside = np.all(np.abs(expected * N - np.round(expected * N)) > 1e-6, axis=1)
    np.testing.assert_array_equal(np.floor(got[inside] * N), np.floor(expected[inside] * N))


def test_power_sets_the_flux_as_pbrt_normalises_it(tmp_path):
    """pbrt-v4 scales I (normalised to luminance 1) by power / (4π mean(image)): the import with `power` is the
    import with that `scale`."""
    mean = float(IMAGE.mean())
    by_power = _load(tmp_path, 'LightSource "goniometric" "string filename" "gonio.exr" "float power" 30', False)
    by_scale = _load(
        tmp_path,
        f'LightSource "goniometric" "string filename" "gonio.exr" "float scale" {30 / (4 * np.pi * mean)}',
        False,
    )
    np.testing.assert_allclose(by_power.lights[0].intensity.values, by_scale.lights[0].intensity.values, rtol=1e-5)
    assert by_power.lights[0].intensity.values.max() > 0


def test_a_python_scene_with_a_goniometric_light_is_saved_with_its_file(tmp_path):
    """save_scene writes the image's path and frame; pixels given as an array are refused in one line (a scene file
    names files)."""
    import spectrace

    write_exr(tmp_path / "gonio.exr", IMAGE, None, {})
    floor = spectrace.shape("rectangle", spectrace.diffuse(0.5))
    camera = spectrace.Camera(origin=(0, 0, 5), target=(0, 0, 0))
    for image in (tmp_path / "gonio.exr", IMAGE):
        light = spectrace.goniometric_light((0, 1, 0), intensity=2.0, image=image, up=(1, 0, 0), mirrored=True)
        scene = spectrace.Scene(camera=camera, width=4, height=4, shapes=[floor], lights=[light])
        if isinstance(image, np.ndarray):
            with pytest.raises(spectrace.SpectraceError, match="lights\\[0\\].*give its path") as error:
                spectrace.save_scene(scene, tmp_path / "array.toml")
            assert "\n" not in str(error.value)
            continue
        spectrace.save_scene(scene, tmp_path / "saved.toml")
        (loaded,) = spectrace.load_scene(tmp_path / "saved.toml").lights
        np.testing.assert_array_equal(loaded.image, light.image)
        assert loaded.mirrored and loaded.up == (1.0, 0.0, 0.0)


@pytest.mark.subprocess
@pytest.mark.slow
def test_a_non_square_image_is_refused_in_one_line_naming_the_key(tmp_path):
    """An equal-area map is square: another image is refused by `spectrace render` in one line naming the file and
    key, with a non-zero exit and no traceback."""
    import subprocess
    import sys

    write_exr(tmp_path / "wide.exr", np.ones((4, 8, 3), np.float32), None, {})
    scene = tmp_path / "scene.toml"
    scene.write_text(
        "[camera]\norigin = [0, 0, 5]\ntarget = [0, 0, 0]\nfov = 40\n[film]\nwidth = 4\nheight = 4\n"
        '[materials.m]\ntype = "diffuse"\nreflectance = { value = 0.5 }\n'
        '[[shapes]]\ntype = "rectangle"\nmaterial = "m"\n'
        '[[lights]]\ntype = "goniometric"\nposition = [0, 0, 1]\nintensity = { value = 1 }\nfile = "wide.exr"\n'
    )
    done = subprocess.run(
        [sys.executable, "-m", "spectrace", "render", str(scene), "-o", str(tmp_path / "out.exr")],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert done.returncode != 0 and "Traceback" not in done.stderr
    (line,) = done.stderr.strip().splitlines()
    assert "lights[0].file" in line and "must be square" in line and str(scene) in line
    assert not (tmp_path / "out.exr").exists()
