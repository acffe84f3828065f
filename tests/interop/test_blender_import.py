"""Blender files in (`spectrace import-blend`, `spectrace render SCENE.blend`), with scenes built in the test by
Blender's own Python module (tests/interop/blender_builder.py, in a child process): the TOML against the values the
scene was built with, the lights' units against closed forms of the irradiance they give, and the add-on inside
Blender (the comparisons with Cycles are in test_blender_cycles.py). Everything but the missing-bpy test skips where
bpy is not installed (installed apart, ~370 MB to download)."""

from __future__ import annotations

import importlib.util
import math
import os
import shutil
import subprocess
import sys
import tomllib
from pathlib import Path

import numpy as np
import pytest
from tests.cli_runner import run_here, run_spectrace

HAS_BPY = importlib.util.find_spec("bpy") is not None
needs_bpy = pytest.mark.skipif(
    not HAS_BPY, reason="bpy (Blender as a Python module, installed apart: pip install bpy) is absent"
)
ROOT = Path(__file__).resolve().parents[2]


def _child(*args: str) -> None:
    """Run `python ARGS` in its own process (bpy stays out of the test process)."""
    env = os.environ.copy()
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(ROOT), env.get("PYTHONPATH")]))
    done = subprocess.run([sys.executable, *args], capture_output=True, text=True, env=env, timeout=300, cwd=ROOT)
    assert done.returncode == 0, done.stderr[-2000:]


def _build(kind: str, blend: Path, cycles: Path | None = None, spp: int = 0) -> None:
    args = ["-m", "tests.interop.blender_builder", kind, str(blend)]
    if cycles is not None:
        args += [str(cycles), str(spp)]
    _child(*args)


LIGHT_KINDS = ("POINT", "SPOT", "SUN", "AREA")
BUILT = ("grey_box", "materials_box", "unsupported", *(f"light_{kind}" for kind in LIGHT_KINDS))


@pytest.fixture(scope="module")
def built(tmp_path_factory) -> Path:
    """Every scene of BUILT saved as KIND.blend in one folder by one Blender process (each start of bpy costs
    seconds); a test copies the file it needs, so that nothing it writes beside it meets another test's files."""
    folder = tmp_path_factory.mktemp("blender_scenes")
    _child("-m", "tests.interop.blender_builder", "--many", str(folder), *BUILT)
    return folder


def _copy(built: Path, kind: str, tmp_path: Path) -> Path:
    return Path(shutil.copy(built / f"{kind}.blend", tmp_path / f"{kind}.blend"))


def _import(tmp_path: Path, kind: str, built: Path | None = None) -> tuple[Path, dict]:
    """`spectrace import-blend` of a scene of the builder (copied from `built` where it is one of BUILT): its TOML,
    and what it holds."""
    blend, toml = tmp_path / f"{kind}.blend", tmp_path / f"{kind}.toml"
    if built is None:
        _build(kind, blend)
    else:
        _copy(built, kind, tmp_path)
    done = run_spectrace("import-blend", str(blend), "-o", str(toml))
    assert done.returncode == 0, done.stderr
    return toml, tomllib.loads(toml.read_text(encoding="utf-8"))


BUILD_AND_IMPORT = """
import sys
from tests.interop import blender_builder
from spectrace.interop.blender import import_blend

kind, blend, toml = sys.argv[1:4]
sys.argv = [sys.argv[0], kind, blend]
blender_builder.main()
import_blend(blend, toml)
"""


def _build_and_import(tmp_path: Path, kind: str) -> tuple[Path, dict]:
    """A scene of the builder saved and imported by one Blender process (each start of bpy costs seconds)."""
    name = kind.split(":")[0]
    blend, toml = tmp_path / f"{name}.blend", tmp_path / f"{name}.toml"
    _child("-c", BUILD_AND_IMPORT, kind, str(blend), str(toml))
    return toml, tomllib.loads(toml.read_text(encoding="utf-8"))


@pytest.mark.subprocess
@pytest.mark.slow
def test_without_bpy_each_command_names_the_extra_in_one_line(tmp_path):
    # a bpy that cannot be imported, first on the path: as where bpy is not installed
    (tmp_path / "stub").mkdir()
    (tmp_path / "stub" / "bpy.py").write_text("raise ImportError('no bpy here')\n")
    blend = tmp_path / "scene.blend"
    blend.write_bytes(b"BLENDER-v500")
    env = os.environ.copy()
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(tmp_path / "stub"), env.get("PYTHONPATH")]))
    out = tmp_path / "out.toml"
    out.write_text("kept\n")
    for args in (["import-blend", str(blend), "-o", str(out)], ["render", str(blend), "-o", str(tmp_path / "a.png")]):
        done = subprocess.run(
            [sys.executable, "-m", "spectrace", *args], capture_output=True, text=True, env=env, timeout=300
        )
        assert done.returncode != 0
        lines = done.stderr.strip().splitlines()
        assert len(lines) == 1 and "bpy" in lines[0] and "pip install bpy" in lines[0], done.stderr
        assert "Traceback" not in done.stderr
    assert out.read_text() == "kept\n"


@needs_bpy
@pytest.mark.subprocess
@pytest.mark.slow
def test_a_file_blender_cannot_open_is_one_line_and_nothing_is_written(tmp_path):
    not_blend = tmp_path / "notes.blend"
    not_blend.write_text("not a Blender file\n")
    out = tmp_path / "out.toml"
    for source, message in ((not_blend, "Blender cannot open it"), (tmp_path / "missing.blend", "no such file")):
        done = run_spectrace("import-blend", str(source), "-o", str(out))
        assert done.returncode != 0
        lines = done.stderr.strip().splitlines()
        assert len(lines) == 1 and message in lines[0] and source.name in lines[0], done.stderr
    assert not out.exists() and not (tmp_path / "out_assets").exists()


@needs_bpy
@pytest.mark.subprocess
@pytest.mark.slow
def test_materials_lights_camera_and_instances_as_blender_holds_them(tmp_path, built):
    toml, data = _import(tmp_path, "materials_box", built)
    materials = data["materials"]
    assert materials["plastic"] == {
        "type": "principled",
        "base_color": {"rgb": [0.8, 0.1, 0.1]},
        "metallic": 0.0,
        "roughness": 0.3,
        "eta": 1.5,
    }
    metal = materials["metal"]
    assert (metal["metallic"], metal["roughness"], metal["clearcoat"]) == (1.0, 0.2, 0.5)
    assert metal["clearcoat_gloss"] == pytest.approx(1.0 - 0.03)  # Blender's default Coat Roughness
    assert (materials["glassy"]["spec_trans"], materials["glassy"]["eta"]) == (1.0, 1.45)
    # Anisotropic Rotation in turns, Cycles' counter-clockwise turn of the tangent: 0.125 is 45°
    brushed = materials["brushed"]
    assert (brushed["anisotropic"], brushed["anisotropic_rotation"]) == (pytest.approx(0.6), 45.0)
    # Glass and Glossy: Cycles squares Roughness into α
    assert materials["glass"]["type"] == "dielectric" and materials["glass"]["ior"] == 1.5
    assert materials["glass"]["roughness"] == pytest.approx(0.2**2)
    assert materials["glossy"]["type"] == "conductor" and materials["glossy"]["roughness"] == pytest.approx(0.4**2)
    texture = materials["textured"]["base_color"]
    assert texture["texture"] == "bitmap"
    from PIL import Image

    with Image.open(toml.parent / texture["file"]) as image:
        assert image.size == (8, 4)  # the builder's 8×4 colour grid
    shapes = {shape.get("name"): shape for shape in data["shapes"]}
    assert shapes["bulb"]["emitter"] == {"radiance": {"rgb": [1.0, 0.9, 0.8]}, "scale": 3.0, "two_sided": True}
    # the subdivided ball: a UV sphere of 32×16 segments has 960 triangles, one subdivision level ×4 of its quads
    ball = shapes["ball"]
    assert ball["transform"][0]["matrix"][0][3] == pytest.approx(-0.8)
    # two collection instances of one pebble, stored once
    assert list(data["objects"]) == ["pebble"]
    assert [row["transform"][0]["matrix"][0][3] for row in data["instances"]] == [-1.5, 1.5]
    # the 1×0.5 rectangle light of 50 W: radiance P / (π A)
    panel = shapes["panel"]
    assert panel["emitter"]["radiance"]["scale"] == pytest.approx(50.0 / (math.pi * 0.5))
    lights = {light["type"]: light for light in data["lights"]}
    assert lights["distant"]["direction"] == pytest.approx(
        [0.0, math.sin(math.radians(30)), -math.cos(math.radians(30))]
    )
    assert lights["distant"]["irradiance"] == {"rgb": [1.0, 0.95, 0.9], "scale": 2.5}
    assert lights["point"]["intensity"]["scale"] == pytest.approx(80.0 / (4.0 * math.pi))
    assert lights["spot"]["cutoff_angle"] == pytest.approx(25.0)
    assert lights["constant"]["radiance"] == {"rgb": [0.2, 0.3, 0.4], "scale": 0.5}
    camera = data["camera"]
    assert camera["type"] == "thinlens"
    assert camera["fov"] == pytest.approx(math.degrees(2.0 * math.atan(36.0 / (2.0 * 35.0))))
    assert camera["aperture_radius"] == pytest.approx(0.035 / (2.0 * 4.0))
    assert camera["focus_distance"] == 5.0
    # Blender's default pixel filter, Blackman-Harris 1.5 px wide: the Gaussian of its spread over its support
    assert data["film"] == {
        "width": 32,
        "height": 24,
        "filter": {"type": "gaussian", "stddev": pytest.approx(0.28 * 1.5), "radius": 1.5},
    }
    # Blender's default per-kind limits, lower than Max Bounces 12: named, as spectrace has one depth for all
    assert data["integrator"]["max_depth"] == 14
    assert "Cycles' diffuse 4, glossy 4 bounce limits are not imported" in toml.read_text(encoding="utf-8")
    rendered = run_spectrace(
        "render", str(tmp_path / "materials_box.blend"), "-o", str(tmp_path / "m.exr"), "--spp", "4"
    )
    assert rendered.returncode == 0, rendered.stderr


@pytest.mark.slow
@needs_bpy
@pytest.mark.subprocess
def test_unsupported_nodes_are_named_once_each_and_strict_refuses(tmp_path, built):
    blend, toml = _copy(built, "unsupported", tmp_path), tmp_path / "out.toml"
    toml.write_text("kept\n")
    refused = run_spectrace("import-blend", str(blend), "-o", str(toml), "--strict")
    assert refused.returncode != 0
    assert len(refused.stderr.strip().splitlines()) == 1 and "--strict" in refused.stderr, refused.stderr
    assert toml.read_text() == "kept\n"
    done = run_spectrace("import-blend", str(blend), "-o", str(toml))
    assert done.returncode == 0, done.stderr
    warnings = [line for line in done.stderr.splitlines() if line.startswith("warning: ")]
    # the Noise Texture of two materials: one warning; the Toon BSDF: one
    assert sum("ShaderNodeTexNoise" in line for line in warnings) == 1, warnings
    assert sum("ShaderNodeBsdfToon" in line for line in warnings) == 1, warnings
    data = tomllib.loads(toml.read_text(encoding="utf-8"))
    assert data["materials"]["noisy0"]["roughness"] == 0.5  # the socket's own value


@needs_bpy
@pytest.mark.subprocess
@pytest.mark.slow
def test_an_environment_image_is_turned_as_blender_maps_it(tmp_path, device):
    """Blender's equirectangular lookup (Cycles' direction_to_equirectangular): u = 0.5 − atan2(y, x) / 2π,
    v = 0.5 + atan2(z, √(x² + y²)) / π, v up the image. An image lit (radiance 1, × the world Strength 2) in its left
    half of the upper rows is the quarter of directions y > 0, z > 0: irradiance L π / 2 on a surface facing +y or
    +z, none facing −y or −z, and the same (L π / 4) facing ±x."""
    from spectrace.engine.meters import IrradianceMeter, measure
    from spectrace.interop.gltf.context import photometric_scale
    from spectrace.io.exr import write_exr
    from spectrace.scene import load_scene

    image = np.zeros((32, 64, 3), dtype=np.float32)
    image[:16, :32] = 1.0  # rows top-down
    write_exr(tmp_path / "sky.exr", image, None, {})
    toml, data = _build_and_import(tmp_path, f"environment:{tmp_path / 'sky.exr'}")
    assert data["lights"][0]["type"] == "envmap" and data["lights"][0]["scale"] == 2.0
    scene = load_scene(toml).with_overrides(max_depth=2)
    expected = {(0, 1, 0): math.pi, (0, 0, 1): math.pi, (0, -1, 0): 0.0, (0, 0, -1): 0.0}
    expected |= {(1, 0, 0): math.pi / 2.0, (-1, 0, 0): math.pi / 2.0}
    for normal, irradiance in expected.items():
        meter = IrradianceMeter((0.0, 0.0, 0.0), tuple(float(v) for v in normal))
        reading = measure(scene, meter, streams=4, samples_per_item=64, device=device)
        y, error = reading.photometric / photometric_scale(), float(reading.xyz_standard_error[1]) / photometric_scale()
        # 2 %: the 64 × 32 texels' staircase along the lit region's edges, and the uplift's Y
        assert abs(y - irradiance) <= 4.0 * error + 0.02 * math.pi, (normal, y)


def _square_irradiance(radiance: float, side: float, height: float) -> float:
    """E on the axis of a Lambertian square of radiance L at distance h: four rectangles a × a (a = side/2) with a
    corner over the point, each π L F with the differential-area configuration factor of a parallel rectangle,
    F = [X/√(1+X²) atan(Y/√(1+X²)) + Y/√(1+Y²) atan(X/√(1+Y²))] / 2π, X = Y = a/h."""
    x = side / 2.0 / height
    return 4.0 * radiance / 2.0 * 2.0 * x / math.sqrt(1 + x * x) * math.atan(x / math.sqrt(1 + x * x))


@pytest.fixture(scope="module")
def light_scenes(tmp_path_factory, built) -> Path:
    """The light-unit scenes, each light_KIND.blend and its import light_KIND.toml in one folder: one process
    imports them all (each start of bpy costs seconds)."""
    folder = tmp_path_factory.mktemp("blender_lights")
    kinds = [f"light_{kind}" for kind in LIGHT_KINDS]
    for kind in kinds:
        _copy(built, kind, folder)
    _child(
        "-c",
        "import sys\nfrom spectrace.interop.blender import import_blend\n"
        "for name in sys.argv[2:]:\n    import_blend(f'{sys.argv[1]}/{name}.blend', f'{sys.argv[1]}/{name}.toml')",
        str(folder),
        *kinds,
    )
    return folder


@needs_bpy
@pytest.mark.subprocess
@pytest.mark.parametrize("kind", LIGHT_KINDS)
@pytest.mark.slow
def test_light_units_give_the_irradiance_of_their_closed_form(light_scenes, device, kind):
    """Blender's units as Cycles renders them (a point or spot light's P W: I = P / 4π; a sun's S W/m²: E = S facing
    it; an area light's P W out of its face: L = P / (π A)), read by spectrace's irradiance meter at the origin,
    LIGHT_HEIGHT below the light, as film Y: the light colour's luminance Y(c) times the closed form."""
    from tests.interop.blender_builder import LIGHT_COLOUR, LIGHT_HEIGHT, LIGHTS

    from spectrace.engine.meters import IrradianceMeter, measure
    from spectrace.interop.gltf.context import photometric_scale
    from spectrace.scene import load_scene

    toml = light_scenes / f"light_{kind}.toml"
    settings, _ = LIGHTS[kind]
    power, h = settings["energy"], LIGHT_HEIGHT
    if kind in ("POINT", "SPOT"):
        expected = power / (4.0 * math.pi * h * h)
    elif kind == "SUN":
        expected = power * math.cos(math.radians(30.0))
    else:
        side = settings["size"]
        expected = _square_irradiance(power / (math.pi * side * side), side, h)
    luminance = float(np.dot([0.2126, 0.7152, 0.0722], LIGHT_COLOUR))
    scene = load_scene(toml).with_overrides(max_depth=2)
    reading = measure(
        scene, IrradianceMeter((0.0, 0.0, 0.0), (0.0, 0.0, 1.0)), streams=8, samples_per_item=64, device=device
    )
    y, error = reading.photometric / photometric_scale(), float(reading.xyz_standard_error[1]) / photometric_scale()
    # 0.5 %: the D65-shaped uplift reproduces its colour's Y to that, and the meter integrates ȳ every 5 nm
    assert abs(y - luminance * expected) <= 4.0 * error + 5e-3 * luminance * expected


ADDON_RENDER = """
import importlib.util
import json
import sys
from pathlib import Path

import bpy

# the add-on as Blender installs it: the folder `spectrace blender-addon` printed, imported by its path
folder = Path(sys.argv[1])
spec = importlib.util.spec_from_file_location(
    "spectrace_addon", folder / "__init__.py", submodule_search_locations=[str(folder)]
)
addon = importlib.util.module_from_spec(spec)
sys.modules["spectrace_addon"] = addon
spec.loader.exec_module(addon)
seen = []
reported = addon.SpectraceRenderEngine._progress


def record(engine, done, total):
    seen.append([done, total])
    reported(engine, done, total)


shown = []
show = addon.SpectraceRenderEngine._show


def record_show(engine, result, image):
    shown.append(Path(image).name)
    return show(engine, result, image)


addon.SpectraceRenderEngine._progress = record
addon.SpectraceRenderEngine._show = record_show
if sys.argv[5] == "esc":
    # Esc pressed once the first pass has been reported (what the engine's test_break would then say)
    addon.SpectraceRenderEngine._stop_asked = lambda engine: bool(seen)
addon.register()
bpy.ops.wm.open_mainfile(filepath=sys.argv[2])
scene = bpy.context.scene
scene.render.engine = "SPECTRACE"
scene.cycles.samples = int(sys.argv[4])
scene.render.image_settings.file_format = "OPEN_EXR"
scene.render.image_settings.color_depth = "32"
bpy.ops.render.render()
bpy.data.images["Render Result"].save_render(sys.argv[3])
print("progress", json.dumps(seen))
print("shown", json.dumps(shown))
"""


def _addon_render(tmp_path: Path, blend: Path, saved: Path, spp: int, esc: bool = False) -> tuple[list, list]:
    """F12 in Blender with the add-on registered (ADDON_RENDER): the (done, total) reported after each pass and the
    image files shown in the Render Result, in order; `esc`: Esc pressed once the first pass is reported."""
    import json

    folder = run_here("blender-addon").stdout.strip()
    env = os.environ.copy()
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(ROOT / "host"), env.get("PYTHONPATH")]))
    done = subprocess.run(
        [sys.executable, "-c", ADDON_RENDER, folder, str(blend), str(saved), str(spp), "esc" if esc else "-"],
        capture_output=True,
        text=True,
        env=env,
        timeout=300,
        cwd=tmp_path,
    )
    assert done.returncode == 0, done.stderr[-2000:]
    progress = json.loads(done.stdout.split("progress ", 1)[1].splitlines()[0])
    shown = json.loads(done.stdout.split("shown ", 1)[1].splitlines()[0])
    return progress, shown


@pytest.mark.subprocess
def test_blender_addon_prints_the_add_on_folder():
    done = run_spectrace("blender-addon")
    assert done.returncode == 0, done.stderr
    folder = Path(done.stdout.strip())
    assert "bl_info" in (folder / "__init__.py").read_text(encoding="utf-8")


@needs_bpy
@pytest.mark.subprocess
@pytest.mark.slow
def test_the_add_on_renders_into_blenders_render_result_telling_its_progress(tmp_path, built):
    """The render engine inside Blender, registered from the folder `spectrace blender-addon` prints: F12
    (bpy.ops.render.render) on the grey room gives in Blender's Render Result the image `spectrace render` gives for
    the same file (same export, seed and device: equal to float32 rounding, rows in Blender's bottom-up order), and
    Blender is told the samples done after each pass, up to the scene's Cycles sample count, and shown the image
    so far while the render goes on (RenderEngine.update_result)."""
    from spectrace.io.exr import read_exr

    spp = 16
    blend, saved, direct = _copy(built, "grey_box", tmp_path), tmp_path / "addon.exr", tmp_path / "direct.exr"
    progress, shown = _addon_render(tmp_path, blend, saved, spp)
    assert len(progress) >= 2 and progress[-1] == [spp, spp], progress
    assert all(b[0] > a[0] for a, b in zip(progress, progress[1:], strict=False)), progress
    # the image after the first pass shown while the render went on, then the final one
    assert shown[0] == "image.partial.npy" and shown[-1] == "image.npy", shown
    rendered = run_spectrace("render", str(blend), "-o", str(direct), "--spp", str(spp))
    assert rendered.returncode == 0, rendered.stderr
    image = read_exr(saved)[0]["RGBA"][..., :3]
    reference = read_exr(direct)[0]["RGB"][..., :3]
    assert image.shape == reference.shape == (24, 32, 3)
    assert reference.mean() > 0.05  # a lit room, not two black images
    np.testing.assert_allclose(image, reference, rtol=1e-3, atol=1e-6)


@needs_bpy
@pytest.mark.subprocess
@pytest.mark.slow
def test_esc_in_blender_stops_the_render_with_the_image_of_the_samples_done(tmp_path, built):
    """Esc once the first pass is reported (the add-on's _stop_asked, which asks RenderEngine.test_break(), made to
    say so: bpy offers no way to press Esc headless): the add-on passes it on to the worker (SIGINT), which ends
    after the pass in flight, and the Render Result holds the image of the samples done, far short of the million
    asked for."""
    from spectrace.io.exr import read_exr

    blend, saved = _copy(built, "grey_box", tmp_path), tmp_path / "stopped.exr"
    progress, shown = _addon_render(tmp_path, blend, saved, 1_000_000, esc=True)
    assert progress and progress[-1][0] < 1_000_000, progress
    assert shown[-1] == "image.npy", shown
    image = read_exr(saved)[0]["RGBA"][..., :3]
    assert np.all(np.isfinite(image)) and image.mean() > 0.05
