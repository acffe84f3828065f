"""Polarised transport as a whole: on a scene of depolarising materials only, the polarised kernels render the same
S0 as the unpolarised ones (the first column of every depolariser is the scalar BSDF) and exactly zero S1..S3; the
same Stokes images however the render is split; and the scenes polarised transport cannot render are refused in
one line naming the key, by a real process that keeps the output already on disk."""

import numpy as np
import pytest
from tests.cli_runner import run_spectrace
from tests.polarization.stokes_scenes import header, sheets

import spectrace
from spectrace.scene.loader import load_scene

# Two diffuse walls and a floor under an area light, a polariser-free box: every event depolarises.
BOX = (
    header("origin = [0, 1, 3.5]\ntarget = [0, 0.8, 0]\nfov = 40", spp=32, max_depth=5)
    + """
[materials.white]
type = "diffuse"
reflectance = { value = 0.8 }

[materials.red]
type = "diffuse"
reflectance = { rgb = [0.7, 0.1, 0.1] }

[[shapes]]
type = "rectangle"
material = "white"
transform = [{ rotate = { axis = [1, 0, 0], angle = -90 } }]

[[shapes]]
type = "rectangle"
material = "red"
transform = [{ rotate = { axis = [0, 1, 0], angle = 90 } }, { translate = [-1, 1, 0] }]

[[shapes]]
type = "rectangle"
material = "white"
transform = [{ translate = [0, 1, -1] }]

[[shapes]]
type = "rectangle"
material = "black"
emitter = { radiance = { value = 4 } }
transform = [{ scale = [0.3, 0.3, 1] }, { rotate = { axis = [1, 0, 0], angle = 90 } }, { translate = [0, 1.9, 0] }]
"""
)


def _render(tmp_path, text: str, name: str):
    path = tmp_path / f"{name}.toml"
    path.write_text(text)
    return spectrace.render(load_scene(path), progress=False, colour_space="xyz")


def test_depolarizing_scene_renders_its_unpolarized_image(tmp_path):
    polarized = _render(tmp_path, BOX, "polarized")
    plain = _render(tmp_path, BOX.replace('aovs = ["stokes", "dolp"]', ""), "plain")
    stokes = polarized.aovs["stokes"].reshape(*polarized.aovs["stokes"].shape[:2], 4, 3)
    # The image and S0 agree with the unpolarised render within 4 standard errors of the difference (blocks of
    # 2 x 2 pixels, their spread); S1..S3 are exactly zero: no event polarises.
    difference = (np.asarray(polarized.xyz) - np.asarray(plain.xyz))[..., 1]
    blocks = difference.reshape(4, 2, 4, 2).mean(axis=(1, 3))
    stderr = difference.std(ddof=1) / np.sqrt(4)
    assert np.all(np.abs(blocks) <= 4 * stderr + 1e-6)
    assert np.allclose(stokes[..., 0, :], np.asarray(polarized.xyz), rtol=1e-6, atol=1e-7)
    assert np.asarray(plain.xyz)[..., 1].mean() > 0.05
    assert np.all(stokes[..., 1:, :] == 0.0)


def test_stokes_images_do_not_depend_on_the_pass_split(tmp_path):
    """Deterministic: 16 samples in one pass, in passes of 4 and in tiles of 3 rows give the same bits in every
    Stokes image."""
    path = tmp_path / "sheets.toml"
    path.write_text(sheets('type = "polarizer"\nangle = 20', 'type = "retarder"\nangle = 65\nretardance = 70'))
    scene = load_scene(path)
    whole = spectrace.render(scene, progress=False, colour_space="xyz")
    split = spectrace.render(scene, progress=False, colour_space="xyz", pass_spp=4)
    tiles = spectrace.render(scene, progress=False, colour_space="xyz", tile_rows=3)
    for other in (split, tiles):
        assert np.array_equal(whole.aovs["stokes"], other.aovs["stokes"])
        assert np.array_equal(np.asarray(whole.xyz), np.asarray(other.xyz))


@pytest.mark.subprocess
@pytest.mark.parametrize(
    ("edit", "key"),
    [
        (lambda text: text.replace("[integrator]", '[integrator]\ntype = "direct"'), "integrator.type"),
        (
            lambda text: (
                text + '\n[materials.card]\ntype = "diffuse"\nreflectance = { value = 0.5 }\n'
                '\n[materials.dye]\ntype = "fluorescent"\nbase = "card"\n'
                "excitation = { values = [[360, 0.8], [450, 0.8], [500, 0.0], [830, 0.0]] }\n"
                "emission = { values = [[360, 0.0], [500, 0.0], [540, 1.0], [600, 0.0], [830, 0.0]] }\n"
                "quantum_yield = 0.9\n"
                '\n[[shapes]]\ntype = "sphere"\nmaterial = "dye"\ntransform = [{ translate = [0, 0, -3] }]\n'
            ),
            "fluorescent",
        ),
    ],
    ids=["other integrator", "fluorescent"],
)
@pytest.mark.slow
def test_unrenderable_polarized_scenes_are_refused_in_one_line(tmp_path, edit, key):
    scene = tmp_path / "scene.toml"
    scene.write_text(edit(sheets('type = "polarizer"')))
    out = tmp_path / "out.exr"
    out.write_bytes(b"kept")
    result = run_spectrace("render", str(scene), "-o", str(out), timeout=300)
    assert result.returncode != 0
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and key in lines[0] and str(scene) in lines[0], result.stderr
    assert "Traceback" not in result.stderr
    assert out.read_bytes() == b"kept"


def test_meters_refuse_a_polarized_scene(tmp_path):
    """A meter has no camera basis for Stokes vectors: it refuses rather than treat a polariser as a grey filter."""
    from spectrace.api import measure_radiance
    from spectrace.errors import SpectraceError

    path = tmp_path / "sheets.toml"
    path.write_text(sheets('type = "polarizer"'))
    with pytest.raises(SpectraceError, match="meters measure unpolarised transport"):
        measure_radiance(load_scene(path), (0, 0, 3), (0, 0, -1))


def test_measured_polarized_is_refused_naming_its_missing_data(tmp_path):
    """Mitsuba 3's measured_polarized reads Baek et al.'s pBRDF files, which no public repository holds: the import
    refuses it in one error naming the plugin and the data it lacks."""
    from spectrace.errors import SpectraceError
    from spectrace.interop.mitsuba import load_mitsuba_scene

    xml = tmp_path / "scene.xml"
    xml.write_text(
        '<scene version="3.0.0"><sensor type="perspective"><float name="fov" value="30"/></sensor>'
        '<shape type="sphere"><bsdf type="measured_polarized"><string name="filename" value="6_gold_inpainted.pbsdf"/>'
        "</bsdf></shape></scene>"
    )
    with pytest.raises(SpectraceError, match=r"bsdf 'measured_polarized' \(its measured pBRDF files, Baek et al"):
        load_mitsuba_scene(xml)
