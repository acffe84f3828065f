"""Degenerate numbers that would reach a division or a NaN are refused where they enter, in one line naming the
file and key path (or option, or file:line), before any device work: transforms that are singular or overflow once
composed (scene files and pbrt files), light powers over no area or solid angle, pixel filters narrower than 32-bit
film positions resolve, film ranges where the observer is zero, white points outside the spectral locus or with
subnormal coordinates, environment maps beyond 32-bit range, spectral bands finer than the film's grid. Where the
rule is a number, it is checked against an independent reference (singular values, colour-science's locus, quadrature
of the filter)."""

import importlib
import math

import numpy as np
import pytest

from cli_runner import run_in_process, run_spectrace
from scene_text import emitting_screen, glowing_rectangle
from spectrace.errors import SpectraceError

SCENE = glowing_rectangle()
SHAPE_MATERIAL = 'material = "grey"\n'


def _with_film(text: str) -> str:
    return SCENE.replace("height = 6\n", f"height = 6\n{text}\n", 1)


def _with_shape_keys(text: str) -> str:
    return SCENE.replace(SHAPE_MATERIAL, SHAPE_MATERIAL + text + "\n", 1)


def _environment(folder, name: str, value: float) -> None:
    import OpenEXR

    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    with OpenEXR.File(header, {"RGB": np.full((4, 8, 3), value, np.float32)}) as exr:
        exr.write(str(folder / name))


OBJECT = """
[objects.box]
shapes = [{ type = "cube", material = "grey" }]

[[instances]]
object = "box"
transform = TRANSFORM
"""

# (id, scene text, extra options, the place after "<scene>: " (or the option), a fragment of the message)
SCENE_CASES = [
    (
        "scales-underflow-to-zero",
        _with_shape_keys("transform = [{ scale = 1e-200 }, { scale = 1e-200 }]"),
        (),
        "shapes[0].transform",
        "is singular (largest and smallest singular values 0 and 0)",
    ),
    (
        "sphere-flattened",
        _with_shape_keys("transform = [{ scale = [1, 1, 1e-200] }, { scale = [1, 1, 1e-200] }]").replace(
            'type = "rectangle"', 'type = "sphere"'
        ),
        (),
        "shapes[0].transform",
        "is singular",
    ),
    (
        "flattened-below-rounding",
        _with_shape_keys("transform = [{ scale = [1e-7, 1, 1] }, { scale = [1e-7, 1, 1] }]"),
        (),
        "shapes[0].transform",
        "smallest singular values 1 and 1e-14",
    ),
    (
        "instance-flattened",
        SCENE + OBJECT.replace("TRANSFORM", "[{ scale = 1e-200 }, { scale = 1e-200 }]"),
        (),
        "instances[0].transform",
        "is singular",
    ),
    (
        "huge-matrix-is-far-not-singular",
        _with_shape_keys(
            "transform = [{ matrix = [[1e200, 0, 0, 0], [0, 1e200, 0, 0], [0, 0, 1e200, 0], [0, 0, 0, 1]] }]"
        ),
        (),
        "shapes[0].transform",
        "coordinates reaching 1e+200",
    ),
    (
        "gaussian-window-too-narrow",
        _with_film('filter = { type = "gaussian", stddev = 4, radius = 0.2 }'),
        (),
        "film.filter.radius",
        "radius must be at least stddev/16 (0.25 px), got 0.2",
    ),
    (
        "gaussian-stddev-tiny",
        _with_film('filter = { type = "gaussian", stddev = 1e-30, radius = 1 }'),
        (),
        "film.filter.stddev",
        "must be ≥ 0.001",
    ),
    (
        "mitchell-radius-tiny",
        _with_film('filter = { type = "mitchell", radius = 1e-30 }'),
        (),
        "film.filter.radius",
        "must be ≥ 0.001",
    ),
    (
        "film-range-beyond-the-observer",
        _with_film("wavelengths = [900, 1000]"),
        (),
        "film.wavelengths",
        "observer 'CIE 1931 2°' is zero over the film's wavelengths 900-1000 nm (it responds over 360-830 nm)",
    ),
    (
        "film-range-below-the-2012-observer",
        _with_film('wavelengths = [370, 385]\nobservers = ["CIE 1931 2°", "CIE 2012 2°"]'),
        (),
        "film.wavelengths",
        "observer 'CIE 2012 2°' is zero over the film's wavelengths 370-385 nm",
    ),
    (
        "environment-texels-overflow",
        SCENE + '\n[[lights]]\ntype = "envmap"\nfile = "huge.exr"\n',
        (),
        "lights[0].file",
        "the map's texels reach 3e+38, beyond 1e+20",
    ),
    (
        "environment-scale-overflows",
        SCENE + '\n[[lights]]\ntype = "envmap"\nfile = "plain.exr"\nscale = 1e300\n',
        (),
        "lights[0].scale",
        "the map's texels times scale reach 1e+300",
    ),
    (
        "spectral-bins-finer-than-the-film-grid",
        _with_film("wavelengths = [400, 700]"),
        ("--spectral-bins", "302"),
        "--spectral-bins",
        "302 bands over the film's 400-700 nm would be narrower than the 1 nm grid",
    ),
    ("white-subnormal-y", SCENE, ("--white-balance", "0.3,1e-310"), "--white-balance", "is not a colour"),
    ("white-subnormal-x", SCENE, ("--white-balance", "1e-320,0.33"), "--white-balance", "is not a colour"),
    ("white-tiny-y", SCENE, ("--white-balance", "0.5,1e-300"), "--white-balance", "outside the spectral locus"),
    ("white-off-the-locus", SCENE, ("--white-balance", "0.01,0.01"), "--white-balance", "outside the spectral locus"),
    (
        "white-too-saturated-for-bradford",
        SCENE,
        ("--white-balance", "0.7,0.29"),
        "--white-balance",
        "too saturated for bradford adaptation",
    ),
]


def _no_device(*args, **kwargs):
    raise AssertionError("the device was opened before the input was refused")


@pytest.mark.parametrize(
    ("text", "options", "where", "says"), [c[1:] for c in SCENE_CASES], ids=[c[0] for c in SCENE_CASES]
)
def test_degenerate_numbers_are_one_line_naming_the_key(text, options, where, says, tmp_path, monkeypatch, capsys):
    _environment(tmp_path, "huge.exr", 3e38)
    _environment(tmp_path, "plain.exr", 1.0)
    scene = tmp_path / "scene.toml"
    scene.write_text(text)
    out = tmp_path / ("out.exr" if "--spectral-bins" in options else "out.png")
    out.write_bytes(b"an image to keep")
    monkeypatch.setattr(importlib.import_module("spectrace.engine.wavefront"), "make_renderer", _no_device)
    status, stderr = run_in_process(
        monkeypatch, capsys, ["render", str(scene), "-o", str(out), "--overwrite", "-q", *options]
    )
    assert status == 2, stderr
    lines = [line for line in stderr.splitlines() if line.strip()]
    assert len(lines) == 1 and "Traceback" not in stderr, stderr
    place = f"{where}: " if where.startswith("--") else f"{scene}: {where}: "
    assert lines[0].startswith("error: ") and place in lines[0] and says in lines[0], lines[0]
    assert out.read_bytes() == b"an image to keep"


PBRT_HEADER = """LookAt 0 0 5  0 0 0  0 1 0
Camera "perspective" "float fov" 30
Film "rgb" "integer xresolution" 8 "integer yresolution" 6
WorldBegin
"""
PLANE = 'Shape "trianglemesh" "point3 P" [-9 -9 0  9 -9 0  9 9 0  -9 9 0] "integer indices" [0 1 2 0 2 3]\n'
PBRT_CASES = [
    (
        "area-power-on-zero-area",
        PBRT_HEADER
        + 'AreaLightSource "diffuse" "float power" 60 "rgb L" [1 1 1]\n'
        + 'Shape "trianglemesh" "point3 P" [0 0 0  2 0 0  4 0 0] "integer indices" [0 1 2]\n',
        5,
        '"power" needs a shape with a positive finite area, got area 0',
    ),
    (
        "spot-power-on-a-closed-cone",
        PBRT_HEADER
        + 'LightSource "spot" "float power" 50 "float coneangle" 0 "float conedeltaangle" 0 "rgb I" [1 1 1]\n'
        + PLANE,
        5,
        '"power" needs a cone of positive solid angle (coneangle 0)',
    ),
    ("singular-camera", "Scale 0 1 1\n" + PBRT_HEADER + PLANE, 3, "camera-from-world) is singular"),
    (
        "camera-transform-overflows",
        "Scale 1e200 1 1\nScale 1e200 1 1\n" + PBRT_HEADER + PLANE,
        2,
        "Scale makes the current transform overflow",
    ),
    (
        "shape-transform-overflows",
        PBRT_HEADER + "ConcatTransform [1e300 0 0 0  0 1 0 0  0 0 1 0  0 0 0 1]\nScale 1e10 1 1\n" + PLANE,
        6,
        "Scale makes the current transform overflow",
    ),
    (
        "shape-transform-underflows",
        PBRT_HEADER + "Scale 1e-200 1 1\nScale 1e-200 1 1\n" + PLANE,
        7,
        "is singular",
    ),
    (
        "distant-light-under-a-singular-transform",
        PBRT_HEADER + 'AttributeBegin\nScale 0 0 0\nLightSource "distant" "rgb L" [1 1 1]\nAttributeEnd\n' + PLANE,
        7,
        "the light's transform is singular",
    ),
    (
        "gaussian-window-too-narrow",
        PBRT_HEADER.replace("WorldBegin", 'PixelFilter "gaussian" "float sigma" 4 "float xradius" 0.01\nWorldBegin')
        + PLANE,
        4,
        "a Gaussian's radius must be at least stddev/16",
    ),
]


@pytest.mark.parametrize(("text", "line", "says"), [c[1:] for c in PBRT_CASES], ids=[c[0] for c in PBRT_CASES])
def test_degenerate_pbrt_numbers_are_one_line_naming_the_line(text, line, says, tmp_path, monkeypatch, capsys):
    source = tmp_path / "scene.pbrt"
    source.write_text(text)
    out = tmp_path / "scene.toml"
    status, stderr = run_in_process(monkeypatch, capsys, ["import-pbrt", str(source), "-o", str(out)])
    assert status == 2, stderr
    lines = [line for line in stderr.splitlines() if line.strip()]
    assert len(lines) == 1 and "Traceback" not in stderr, stderr
    assert lines[0].startswith(f"error: {source}:{line}: ") and says in lines[0], lines[0]
    assert not out.exists()


@pytest.mark.subprocess
def test_a_real_process_refuses_a_power_over_no_area_in_one_line(tmp_path):
    source = tmp_path / "scene.pbrt"
    source.write_text(PBRT_CASES[0][1])
    result = run_spectrace("import-pbrt", str(source), "-o", str(tmp_path / "scene.toml"), timeout=300)
    assert result.returncode == 2 and "Traceback" not in result.stderr
    assert result.stderr.count("\n") == 1 and result.stderr.startswith(f"error: {source}:5: "), result.stderr


def test_an_importers_non_finite_number_is_found_by_its_key_path():
    from spectrace.interop.toml_writer import non_finite_key

    data = {"camera": {"origin": [0.0, 1.0, 5.0]}, "lights": [{"scale": 1.0}, {"direction": [0.0, math.nan, 0.0]}]}
    assert non_finite_key(data) == "lights[1].direction[1]"
    assert non_finite_key({"shapes": [{"transform": [{"scale": -math.inf}]}]}) == "shapes[0].transform[0].scale"
    assert non_finite_key({"film": {"width": 8, "exposure": 1e308}}) is None


# ---------------------------------------------------------------- the rules against independent references


def test_singular_means_singular_values_not_a_determinant_that_underflows():
    from spectrace.geometry.transforms import transform_matrix

    # A uniform scale of 1e-110 is a similarity (all singular values equal): its determinant, 1e-330, underflows to
    # 0, which the determinant's test took for singular.
    tiny = (np.diag([1e-110, 1e-110, 1e-110, 1.0])).tolist()
    assert np.linalg.det(np.array(tiny)[:3, :3]) == 0.0
    np.testing.assert_array_equal(transform_matrix([{"matrix": tiny}], "t"), np.array(tiny))
    # A rank-2 map built from a random rotation: its smallest singular value (numpy's SVD) is at rounding level.
    rng = np.random.default_rng(7)
    rotation, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    flat = np.eye(4)
    flat[:3, :3] = rotation @ np.diag([2.0, 0.5, 0.0]) @ rotation.T
    assert np.linalg.svd(flat[:3, :3], compute_uv=False)[-1] < 1e-15
    with pytest.raises(SpectraceError, match="is singular"):
        transform_matrix([{"matrix": flat.tolist()}], "t")
    # Composition: each step is regular, their product is not.
    with pytest.raises(SpectraceError, match="the transform is singular") as failure:
        transform_matrix([{"scale": [1e-160, 1, 1]}, {"scale": [1e-160, 1, 1]}], "t")
    assert failure.value.where == "t"


@pytest.mark.parametrize(
    "spec",
    [
        {"type": "gaussian", "stddev": 0.001},
        {"type": "gaussian", "stddev": 0.001, "radius": 16.0},
        {"type": "gaussian", "stddev": 4.0, "radius": 0.25},
        {"type": "mitchell", "radius": 0.001},
        {"type": "tent", "radius": 0.001},
    ],
    ids=["narrowest-gaussian", "narrowest-gaussian-widest-window", "narrowest-window", "mitchell", "tent"],
)
def test_the_narrowest_filters_allowed_have_finite_weights_and_their_closed_form_integral(spec):
    from scipy.integrate import quad

    from spectrace.pixel_filters import PixelFilter

    pixel_filter = PixelFilter(**spec)
    radius = pixel_filter.support
    # The integral the weights divide by, against adaptive quadrature of f itself, told where a narrow peak lies.
    width = pixel_filter.stddev if spec["type"] == "gaussian" else radius
    points = [p for p in (-10 * width, -width, 0.0, width, 10 * width) if -radius < p < radius]
    numeric, _ = quad(
        lambda x: float(pixel_filter.evaluate(np.array([x]))[0]), -radius, radius, points=points, limit=200
    )
    assert pixel_filter.integral() == pytest.approx(numeric, rel=1e-6)
    shape = np.asarray(pixel_filter.device_shape(), np.float32)
    cdf = pixel_filter.device_cdf()
    assert np.all(np.isfinite(shape)) and np.all(np.isfinite(cdf))
    if spec["type"] in ("gaussian", "mitchell"):
        assert np.all(np.diff(cdf) >= 0) and cdf[0] > 0 and cdf[-1] == 1.0
    if spec["type"] == "gaussian":
        # The window's peak above its cut-off survives 32-bit evaluation: f(0) in float32 is within 1e-3 of f64's.
        peak32 = np.float32(1.0) - np.exp(np.float32(shape[2]) * np.float32(radius) ** 2)
        assert peak32 == pytest.approx(pixel_filter.evaluate(np.zeros(1))[0], rel=1e-3)


def test_accepted_white_chromaticities_are_those_inside_colour_sciences_spectral_locus():
    """The locus test against colour-science's own CIE 1931 table and matplotlib's polygon test, on a grid of
    chromaticities (those within 0.002 of the boundary left out: the two tables' sampling differ there)."""
    colour = pytest.importorskip("colour")
    from matplotlib.path import Path

    from spectrace.film.colour_output import Adaptation, white_problem

    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"].values
    sums = cmfs.sum(axis=1)
    locus = Path((cmfs / sums[:, None])[sums > 1e-4 * sums.max(), :2])
    checked = 0
    for x in np.linspace(0.01, 0.74, 40):
        for y in np.linspace(0.01, 0.84, 40):
            if x + y >= 1.0 or locus.contains_point((x, y), radius=0.004) != locus.contains_point(
                (x, y), radius=-0.004
            ):
                continue
            inside = locus.contains_point((x, y))
            problem = white_problem(np.array([x / y, 1.0, (1.0 - x - y) / y]), Adaptation.VON_KRIES)
            assert (problem is None) == inside, (x, y, problem)
            checked += 1
    assert checked > 500


@pytest.mark.parametrize("method", ["bradford", "von-kries"])
def test_every_accepted_white_adapts_to_a_neutral(method):
    """Whatever white is accepted, the adaptation is finite and takes that white to R = G = B (the output white)."""
    from spectrace.film.colour_output import ColourSpace, parse_white_balance, white_problem, xyz_to_output

    rng = np.random.default_rng(11)
    accepted = 0
    for x, y in rng.uniform([0.0, 0.0], [0.75, 0.85], size=(400, 2)):
        white = np.array([x / y, 1.0, (1.0 - x - y) / y])
        if x + y >= 1.0 or white_problem(white, method) is not None:
            continue
        balance = parse_white_balance(f"{x!r},{y!r}", method)
        rgb = xyz_to_output(white[None, :], ColourSpace.SRGB, balance)[0].astype(np.float64)
        assert np.all(np.isfinite(rgb)) and rgb.min() > 0
        np.testing.assert_allclose(rgb, rgb.mean(), rtol=1e-4)
        accepted += 1
    assert accepted > 40


def test_the_observer_rule_follows_each_observers_table():
    """CIE 2012's tables start at 390 nm, CIE 1931's reach 360-830 nm (colour-science's data, CVRL's)."""
    colour = pytest.importorskip("colour")
    from spectrace.film.response import observer_range_problem

    start_2012 = float(colour.MSDS_CMFS["CIE 2015 2 Degree Standard Observer"].wavelengths[0])
    assert start_2012 == 390.0
    assert observer_range_problem("CIE 2012 2°", (380.0, start_2012 - 1)) is not None
    assert observer_range_problem("CIE 2012 2°", (380.0, start_2012)) is None
    assert observer_range_problem("CIE 1931 2°", (831.0, 900.0)) is not None
    assert observer_range_problem("CIE 1931 2°", (830.0, 900.0)) is None
    # A sensor film may leave its XYZ observer unseen: its channels are what it records.
    from spectrace.film.response import FilmResponse, Sensor

    sensor = Sensor("ir.csv", ("ir",), np.array([850.0, 1000.0]), np.array([[1.0], [1.0]]))
    FilmResponse(sensor=sensor, wavelengths=(900.0, 1000.0))
    with pytest.raises(SpectraceError, match="film.wavelengths"):
        FilmResponse(wavelengths=(900.0, 1000.0))


def test_an_environment_map_built_in_python_is_checked_too():
    from spectrace.lights.envmap import EnvironmentMap

    with pytest.raises(SpectraceError, match="beyond 1e\\+20"):
        EnvironmentMap(np.full((2, 4, 3), 1e30, np.float32))
    with pytest.raises(SpectraceError, match="times scale"):
        EnvironmentMap(np.ones((2, 4, 3), np.float32), scale=math.inf)
    EnvironmentMap(np.full((2, 4, 3), 1e10, np.float32), scale=1e10)  # exactly at the bound


def test_spectral_bands_span_the_films_wavelengths(device, tmp_path):
    """A screen of constant radiance 1 over a film of 300-1100 nm: the bands cover that range (not 360-830 nm) and
    each holds the band-averaged radiance 1, within 4 standard errors of its pixels' mean."""
    from spectrace.engine.renderer import Renderer
    from spectrace.scene import load_scene

    scene_file = tmp_path / "screen.toml"
    scene_file.write_text(emitting_screen().replace("[film]\n", "[film]\nwavelengths = [300, 1100]\n", 1))
    scene = load_scene(scene_file)
    image = Renderer(scene, device, spectral_bins=8).render()
    np.testing.assert_allclose(image.spectral.edges_nm, np.linspace(300.0, 1100.0, 9))
    bands = image.spectral.radiance.reshape(-1, 8).astype(np.float64)
    error = bands.std(axis=0, ddof=1) / math.sqrt(bands.shape[0])
    assert np.all(error > 0)
    np.testing.assert_array_less(np.abs(bands.mean(axis=0) - 1.0), 4.0 * error)


def test_the_fail_fraction_of_dropped_samples():
    from spectrace.film.state import DROPPED_FAIL_FRACTION, dropped_samples_problem

    assert dropped_samples_problem(0, 0) is None
    assert dropped_samples_problem(49, 100) is None and DROPPED_FAIL_FRACTION == 0.5
    assert "50 (50 %) of the render's 100 samples" in (dropped_samples_problem(50, 100) or "")
    assert "every one of the render's 100 samples" in (dropped_samples_problem(100, 100) or "")


# A scene built in Python (no file's checks) whose emitter, 3e38 W/(m² sr nm), overflows every sample; the command
# line renders it as if a file had given it.
_EVERY_SAMPLE_OVERFLOWS = """
import sys
import numpy as np
import spectrace.interop.scene_files
from spectrace import cli
from spectrace.geometry import primitives
from spectrace.geometry.transforms import apply_transform
from spectrace.materials.diffuse import DiffuseMaterial
from spectrace.scene.model import AreaEmitter, Camera, Scene, Shape
from spectrace.spectral.spectrum import Spectrum

wall = apply_transform(primitives.rectangle(), np.diag([10.0, 10.0, 1.0, 1.0]))
shape = Shape(wall, DiffuseMaterial(Spectrum.constant(0.5)), emitter=AreaEmitter(Spectrum.constant(3e38)), name="sun")
scene = Scene(Camera(origin=(0, 0, 5), target=(0, 0, 0), fov_degrees=30), width=4, height=3, shapes=[shape], spp=2)
spectrace.interop.scene_files.load_any_scene = lambda path, overrides=None, report=None: scene
sys.argv = ["spectrace", "render", "built-in-python.toml", "-o", sys.argv[1], "-q"]
cli.main()
"""


@pytest.mark.subprocess
@pytest.mark.slow
def test_a_real_process_fails_when_every_sample_is_dropped(tmp_path):
    import os
    import subprocess
    import sys

    out = tmp_path / "out.png"
    result = subprocess.run(
        [sys.executable, "-c", _EVERY_SAMPLE_OVERFLOWS, str(out)],
        capture_output=True,
        text=True,
        env=os.environ.copy(),
        timeout=300,
    )
    assert result.returncode == 2, result.stderr
    errors = [line for line in result.stderr.splitlines() if line.startswith("error: ")]
    assert "Traceback" not in result.stderr and len(errors) == 1, result.stderr
    assert "every one of the render's 24 samples" in errors[0] and "shape 'sun'" in errors[0], errors[0]
    assert not out.exists()


def test_an_emitter_scale_that_overflows_is_refused_at_the_scale(tmp_path):
    from spectrace.scene import load_scene

    scene = tmp_path / "scene.toml"
    scene.write_text(emitting_screen(radiance="value = 1e20").replace("emitter = {", "emitter = { scale = 1e20,"))
    with pytest.raises(SpectraceError, match="spectrum reaches 1e\\+40") as failure:
        load_scene(scene)
    assert failure.value.where == f"{scene}: shapes[0].emitter.scale"
