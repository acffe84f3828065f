"""A scene with nothing in it, or with nothing that emits, renders black, as in Mitsuba 3 and pbrt-v4: every
integrator and kernel shape with an empty BVH and no lights (light pick, light power CDF and the light tracer's
emission sampling with nothing to choose from), and the meters. A scene of an environment light alone sees its
closed-form radiance. Each loads with one warning line rather than being refused."""

import warnings

import numpy as np
import pytest

import spectrace
from cli_runner import run_spectrace
from scene_text import camera_film, diffuse
from spectrace.engine.meters import FluxMeter, IrradianceMeter, RadianceMeter, measure
from spectrace.engine.wavefront import make_renderer
from spectrace.errors import SpectraceWarning
from spectrace.integrators import INTEGRATORS

EMPTY = camera_film(width="16", height="16")
DARK = (
    camera_film(width="16", height="16")
    + diffuse()
    + """
[[shapes]]
type = "rectangle"
material = "grey"

[[shapes]]
type = "sphere"
material = "grey"
transform = [{ scale = 0.5 }, { translate = [0, 0, 0.5] }]

[[shapes]]
type = "cube"
material = "grey"
transform = [{ scale = 0.2 }, { translate = [0.6, 0.4, 0.3] }]
"""
)
SKY_RADIANCE = 0.7
SKY = (
    camera_film(width="16", height="16")
    + f"""
[[lights]]
type = "constant"
radiance = {{ value = {SKY_RADIANCE} }}
"""
)

# Every integrator in the megakernel shape, and the path tracer in the wavefront shape.
RENDERS = [(name, "megakernel") for name in INTEGRATORS] + [("path", "wavefront")]
METERS = [IrradianceMeter((0, 0, 1), (0, 0, 1)), RadianceMeter((0, 0, 2), (0, 0, -1)), FluxMeter((0, 0, 0.5), 0.3)]


def _load(tmp_path, text: str, name: str) -> tuple[spectrace.Scene, list[str]]:
    path = tmp_path / f"{name}.toml"
    path.write_text(text, encoding="utf-8")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        scene = spectrace.load_scene(path)
    return scene, [str(w.message) for w in caught if issubclass(w.category, SpectraceWarning)]


def test_a_scene_without_shapes_or_lights_loads_with_one_warning(tmp_path):
    _, told = _load(tmp_path, EMPTY, "empty")
    assert len(told) == 1 and "neither shapes nor lights" in told[0] and "empty.toml" in told[0]
    _, told = _load(tmp_path, DARK, "dark")
    assert len(told) == 1 and "nothing in the scene emits light" in told[0]
    _, told = _load(tmp_path, SKY, "sky")
    assert told == []


@pytest.mark.parametrize(("integrator", "kernel"), RENDERS)
@pytest.mark.parametrize("text", [EMPTY, DARK], ids=["empty", "unlit"])
def test_every_integrator_renders_a_scene_without_light_black(tmp_path, device, integrator, kernel, text):
    """Exactly zero in every pixel: nothing emits, so no estimator has anything to add (a NaN or a stray value
    from an empty light table or BVH would show)."""
    scene, _ = _load(tmp_path, text, "scene")
    scene = scene.with_overrides(integrator=integrator, spp=4)
    image = make_renderer(scene, device, kernel).render(pass_spp=4)
    assert image.spp == 4 and image.dropped_samples == 0
    assert np.array_equal(image.xyz, np.zeros_like(image.xyz))


@pytest.mark.parametrize("meter", METERS, ids=lambda m: type(m).__name__)
@pytest.mark.parametrize("text", [EMPTY, DARK], ids=["empty", "unlit"])
def test_meters_read_zero_in_a_scene_without_light(tmp_path, device, meter, text):
    scene, _ = _load(tmp_path, text, "scene")
    reading = measure(scene, meter, wavelengths_nm=[450.0, 550.0, 650.0], streams=4, samples_per_item=4, device=device)
    assert np.array_equal(reading.spectral, np.zeros(3)) and reading.total == 0.0


def _cie_1931_ratios() -> np.ndarray:
    """(∫x̄, ∫ȳ, ∫z̄) / ∫ȳ over 360–830 nm from colour-science's tables: the XYZ of a constant radiance 1."""
    colour = pytest.importorskip("colour")
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"].copy().align(colour.SpectralShape(360, 830, 1))
    sums = cmfs.values.sum(axis=0)
    return sums / sums[1]


@pytest.mark.parametrize(("integrator", "kernel"), RENDERS)
def test_an_environment_alone_is_seen_at_its_radiance(tmp_path, device, integrator, kernel):
    """Camera rays all leave an empty scene: a constant environment of radiance L is seen as L (x̄, ȳ, z̄) / ∫ȳ in
    every pixel, in expectation over the sampled wavelengths. The image means of independent replicas (seeds; SPPM
    shares a pass's wavelengths among its pixels, so pixels are not independent) are within 4 standard errors of
    it, per channel; the light tracer and BDPT reach the camera from the environment too."""
    expected = SKY_RADIANCE * _cie_1931_ratios()
    scene, _ = _load(tmp_path, SKY, "sky")
    means = np.array(
        [
            make_renderer(scene.with_overrides(integrator=integrator, seed=seed), device, kernel)
            .render(pass_spp=4)
            .xyz.reshape(-1, 3)
            .astype(np.float64)
            .mean(axis=0)
            for seed in range(8)
        ]
    )
    mean, error = means.mean(axis=0), means.std(axis=0, ddof=1) / np.sqrt(len(means))
    assert np.all(error > 0) and np.all(error < 0.03 * expected)  # noisy enough to test, tight enough to mean it
    assert np.all(np.abs(mean - expected) < 4 * error), (mean, expected, error)


def test_a_radiance_meter_reads_an_environment_alone_exactly(tmp_path, device):
    """Each wavelength is measured rather than sampled: the environment's radiance at every one, no noise."""
    scene, _ = _load(tmp_path, SKY, "sky")
    reading = measure(scene, METERS[1], wavelengths_nm=[400.0, 550.0, 700.0], streams=4, samples_per_item=4)
    np.testing.assert_allclose(reading.spectral, SKY_RADIANCE, rtol=1e-6)


SENSOR_ONLY = """<scene version="3.0.0">
    <integrator type="path"/>
    <sensor type="perspective">
        <float name="fov" value="40"/>
        <transform name="to_world">
            <lookat origin="0, 0, 5" target="0, 0, 0" up="0, 1, 0"/>
        </transform>
        <sampler type="independent"><integer name="sample_count" value="4"/></sampler>
        <film type="hdrfilm">
            <integer name="width" value="8"/>
            <integer name="height" value="6"/>
        </film>
    </sensor>
</scene>
"""


@pytest.mark.peer
def test_a_mitsuba_sensor_alone_imports_and_renders_black_in_both(tmp_path, device, mitsuba_scalar_spectral):
    from spectrace.interop.mitsuba import load_mitsuba_scene

    xml = tmp_path / "sensor.xml"
    xml.write_text(SENSOR_ONLY, encoding="utf-8")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        scene = load_mitsuba_scene(xml)
    told = [str(w.message) for w in caught if issubclass(w.category, SpectraceWarning)]
    assert told == [f"{xml}: the scene has neither shapes nor lights: it renders black"]
    image = make_renderer(scene, device).render(pass_spp=4)
    assert image.xyz.shape[:2] == (6, 8) and np.array_equal(image.xyz, np.zeros_like(image.xyz))
    mi = mitsuba_scalar_spectral
    theirs = np.array(mi.render(mi.load_file(str(xml)), spp=4))
    assert theirs.shape[:2] == (6, 8) and np.array_equal(theirs, np.zeros_like(theirs))


@pytest.mark.subprocess
@pytest.mark.slow
def test_the_command_line_warns_in_one_line_and_writes_the_black_image(tmp_path):
    """`import-mitsuba` and `render` of a scene with nothing in it: exit 0, one warning line each, the image."""
    xml = tmp_path / "sensor.xml"
    xml.write_text(SENSOR_ONLY, encoding="utf-8")
    imported = run_spectrace("import-mitsuba", str(xml), "-o", str(tmp_path / "sensor.toml"))
    assert imported.returncode == 0, imported.stderr
    lines = (imported.stdout + imported.stderr).splitlines()
    assert [line for line in lines if line.startswith("warning:")] == [
        "warning: the scene has neither shapes nor lights: it renders black"
    ]
    rendered = run_spectrace("render", str(tmp_path / "sensor.toml"), "-o", str(tmp_path / "out.exr"), "-q")
    assert rendered.returncode == 0, rendered.stderr
    assert (rendered.stdout + rendered.stderr).strip() == (
        "warning: the scene has neither shapes nor lights: it renders black"
    )
    assert (tmp_path / "out.exr").stat().st_size > 0
