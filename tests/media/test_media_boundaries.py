"""Which medium a ray is in after it meets a surface, against closed forms (docs/media.md).

A shape with an interior medium is a boundary: crossing it enters or leaves that medium. Any other shape (an opaque
object or a thin sheet inside a medium, a lamp inside it) is no boundary: a ray leaving it, and a shadow ray cast
from it, are still in the medium the path was in (Mitsuba 3's rule for shapes without media). A pass straight
through a thin sheet counts toward max_depth unless `count_thin_passes = false` (Mitsuba 3's volpath)."""

import math

import numpy as np
import pytest

from scene_text import camera_film
from spectrace.engine.meters import RadianceMeter, measure
from spectrace.errors import SpectraceError
from spectrace.scene import load_scene

WAVELENGTHS = np.array([450.0, 600.0])
SIGMA_A = 0.8  # 1/scene unit, grey

HEAD = (
    camera_film(origin="[0, 0, 5]", target="[0, 0, 0]", fov="20", width="4", height="4")
    + """
[integrator]
max_depth = {depth}
{integrator}
"""
)

# An absorbing box, index-matched (no material): 4 wide, spanning z in [-1, 1].
BOX = f"""
[[shapes]]
type = "cube"
interior = {{ sigma_a = {{ value = {SIGMA_A} }} }}
transform = [{{ scale = [2, 2, 1] }}]
"""


def _sheet(z: float) -> str:
    """A thin sheet (no interior: no boundary) across the box at height z, facing +z; it reflects nothing."""
    return f"""
[[shapes]]
type = "rectangle"
material = "sheet"
transform = [{{ scale = 1.5 }}, {{ translate = [0, 0, {z}] }}]
"""


SHEET_MATERIAL = """
[materials.sheet]
type = "thindielectric"
ior = 1.5
specular_reflectance = { value = 0 }
"""

ENVIRONMENT = """
[[lights]]
type = "constant"
radiance = { value = 1.0 }
"""


def _load(tmp_path, text: str):
    path = tmp_path / "scene.toml"
    path.write_text(text)
    return load_scene(path)


def _sheet_transmittance(ior: float) -> float:
    """T' = 1 − 2R/(1 + R) at normal incidence, R = ((n − 1)/(n + 1))² (bsdf_thindielectric.cl's sheet)."""
    r = ((ior - 1.0) / (ior + 1.0)) ** 2
    return 1.0 - 2.0 * r / (1.0 + r)


def _look_down(scene, device):
    """Radiance seen straight down the z axis from above the box."""
    reading = measure(
        scene,
        RadianceMeter((0.0, 0.0, 3.0), (0.0, 0.0, -1.0)),
        wavelengths_nm=WAVELENGTHS,
        streams=16,
        samples_per_item=32,
        device=device,
    )
    return reading.spectral, reading.spectral_standard_error


def _assert_within_noise(value, standard_error, expected):
    """Within 5 standard errors of the streams (the sheets' lobe choice is the only randomness), plus float32's
    rounding (3e-4 relative: shadow rays stop 1e-4 short of the light) where the estimate has no spread."""
    tolerance = 5.0 * standard_error + 3e-4 * abs(expected) + 1e-7
    assert np.all(np.abs(value - expected) <= tolerance), (value, standard_error, expected)


def test_a_thin_sheet_inside_a_medium_leaves_the_ray_in_it(tmp_path, device):
    """Down through the box (2 units) with a sheet at its middle, toward a uniform environment k = 1 below:
    L = T' exp(−σa·2). Had the sheet ended the medium, the second half would be clear: T' exp(−σa)."""
    scene = _load(tmp_path, HEAD.format(depth=-1, integrator="") + SHEET_MATERIAL + BOX + _sheet(0.0) + ENVIRONMENT)
    expected = _sheet_transmittance(1.5) * math.exp(-SIGMA_A * 2.0)
    _assert_within_noise(*_look_down(scene, device), expected)


@pytest.mark.parametrize("count_thin_passes, expected", [(True, 0.0), (False, None)])
def test_passes_through_thin_sheets_count_toward_max_depth_unless_told(tmp_path, device, count_thin_passes, expected):
    """Two sheets in empty space between the meter and the environment, max_depth 2: counted, the second pass would
    be a third segment and nothing arrives; uncounted (Mitsuba 3's volpath), L = T'²."""
    integrator = f"count_thin_passes = {'true' if count_thin_passes else 'false'}"
    scene = _load(
        tmp_path,
        HEAD.format(depth=2, integrator=integrator) + SHEET_MATERIAL + _sheet(0.5) + _sheet(-0.5) + ENVIRONMENT,
    )
    if expected is None:
        expected = _sheet_transmittance(1.5) ** 2
    _assert_within_noise(*_look_down(scene, device), expected)


def test_a_point_light_inside_a_medium_lights_through_it(tmp_path, device):
    """A white diffuse floor (ρ = 1, z = -0.5) and a point light of intensity I (z = 0.5, 0.6 to the side), both
    inside the absorbing box: the floor under the meter has radiance ρ/π · I cos θ / r² · exp(−σa r), seen through
    1.5 units of the box, exp(−1.5 σa). Nothing else lights it (the box's faces are index-matched, no environment).
    A shadow ray that started outside the medium would miss the factor exp(−σa r)."""
    intensity, height, offset = 2.0, 1.0, 0.6
    text = (
        HEAD.format(depth=-1, integrator="")
        + """
[materials.white]
type = "diffuse"
reflectance = { value = 1.0 }

[[shapes]]
type = "rectangle"
material = "white"
transform = [{ scale = 1.5 }, { translate = [0, 0, -0.5] }]
"""
        + BOX
        + f"""
[[lights]]
type = "point"
position = [{offset}, 0, 0.5]
intensity = {{ value = {intensity} }}
"""
    )
    r = math.hypot(height, offset)
    expected = intensity * (height / r) / r**2 * math.exp(-SIGMA_A * r) / math.pi * math.exp(-SIGMA_A * 1.5)
    _assert_within_noise(*_look_down(_load(tmp_path, text), device), expected)


def test_count_thin_passes_is_for_the_path_tracer_only(tmp_path):
    with pytest.raises(SpectraceError, match="count_thin_passes = false is only for integrator 'path'"):
        _load(tmp_path, HEAD.format(depth=4, integrator='type = "light"\ncount_thin_passes = false') + ENVIRONMENT)


def test_count_thin_passes_refusal_names_the_key(tmp_path):
    with pytest.raises(SpectraceError) as error:
        _load(tmp_path, HEAD.format(depth=4, integrator='type = "bdpt"\ncount_thin_passes = false') + ENVIRONMENT)
    assert "integrator" in str(error.value) and "\n" not in str(error.value)


def test_a_scene_built_in_python_is_refused_too(tmp_path, device):
    from spectrace.engine.renderer import Renderer

    scene = _load(tmp_path, HEAD.format(depth=4, integrator="") + SHEET_MATERIAL + _sheet(0.0) + ENVIRONMENT)
    with pytest.raises(SpectraceError, match="count_thin_passes = false is only for integrator 'path'"):
        Renderer(scene.with_overrides(integrator="light", count_thin_passes=False), device)


def _mitsuba_xml(tmp_path, kind: str):
    path = tmp_path / f"{kind}.xml"
    path.write_text(
        f'<scene version="3.0.0"><integrator type="{kind}"/><sensor type="perspective">'
        '<film type="hdrfilm"><integer name="width" value="4"/><integer name="height" value="4"/></film>'
        '</sensor><emitter type="constant"/></scene>'
    )
    return path


def test_mitsuba_volpath_imports_uncounted_thin_passes(tmp_path):
    """Mitsuba's volpath counts no pass through a thin sheet (a null lobe there), its path tracer does."""
    from spectrace.interop.mitsuba import mitsuba_scene_data

    for kind, counted in (("volpath", False), ("path", True)):
        data, _ = mitsuba_scene_data(_mitsuba_xml(tmp_path, kind))
        assert data["integrator"].get("count_thin_passes", True) is counted


@pytest.mark.peer
def test_uncounted_thin_passes_export_as_volpath(tmp_path, mitsuba_scalar_spectral):
    from spectrace.interop.mitsuba import load_mitsuba_scene
    from spectrace.interop.mitsuba.export import scene_to_mitsuba_dict

    for kind in ("volpath", "path"):
        exported = scene_to_mitsuba_dict(load_mitsuba_scene(_mitsuba_xml(tmp_path, kind)), tmp_path / "meshes")
        assert exported["integrator"]["type"] == kind
