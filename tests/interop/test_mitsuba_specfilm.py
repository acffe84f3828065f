"""Mitsuba 3's spectral film (`specfilm`) imported as the film's sensor: its named response curves become a sensor
CSV beside the TOML, one channel per curve in the file's order (Mitsuba's film holds them so). Both films record
∫ L(λ) s(λ) dλ per channel: checked against that integral (numpy, a fine grid) for a camera that sees only an
emitter of a known spectrum, and against Mitsuba 3's own render of the same XML."""

import numpy as np
import pytest

from spectrace.engine.renderer import Renderer
from spectrace.errors import SpectraceError
from spectrace.interop.mitsuba import import_mitsuba, load_mitsuba_scene
from spectrace.scene import load_scene
from stats_toolkit import assert_within_standard_errors, mean_and_standard_error

SIZE = 8
RADIANCE = ((350.0, 1.0), (850.0, 2.0))  # W/(m² sr nm), linear in λ
# Two responses, named so that the alphabetical order differs from the file's (which the channels keep).
CURVES = {"zeta": ((420.0, 0.0), (480.0, 1.0), (540.0, 0.0)), "alpha": ((550.0, 0.0), (600.0, 0.5), (690.0, 0.0))}


def _value(pairs) -> str:
    return ", ".join(f"{w:g}:{v:g}" for w, v in pairs)


def _xml(curves=CURVES) -> str:
    responses = "".join(f'<spectrum name="{name}" value="{_value(pairs)}"/>' for name, pairs in curves.items())
    return f"""<scene version="3.0.0">
  <integrator type="path"/>
  <sensor type="perspective"><float name="fov" value="30"/>
    <transform name="to_world"><lookat origin="0, 0, 3" target="0, 0, 0" up="0, 1, 0"/></transform>
    <film type="specfilm"><integer name="width" value="{SIZE}"/><integer name="height" value="{SIZE}"/>
      {responses}<rfilter type="box"/></film></sensor>
  <shape type="rectangle"><transform name="to_world"><scale value="5"/></transform>
    <bsdf type="diffuse"><float name="reflectance" value="0"/></bsdf>
    <emitter type="area"><spectrum name="radiance" value="{_value(RADIANCE)}"/></emitter></shape>
</scene>"""


def _expected(pairs) -> float:
    """∫ L(λ) s(λ) dλ on a 0.01 nm grid (both piecewise linear)."""
    fine = np.arange(300.0, 900.0, 0.01)
    radiance = np.interp(fine, *zip(*RADIANCE))
    response = np.interp(fine, *zip(*pairs), left=0.0, right=0.0)
    return float(np.trapezoid(radiance * response, fine))


def _channels(image) -> dict[str, np.ndarray]:
    return {name: image.channels[f"sensor.{name}"].astype(np.float64).ravel() for name in CURVES}


def test_specfilm_becomes_the_films_sensor_beside_the_toml(tmp_path, device):
    xml = tmp_path / "scene.xml"
    xml.write_text(_xml())
    toml = tmp_path / "out" / "imported.toml"
    notes = import_mitsuba(xml, toml)
    csv = toml.parent / "imported.sensor.csv"
    assert csv.exists() and any("sensor" in note for note in notes)
    header = next(line for line in csv.read_text().splitlines() if not line.startswith("#"))
    assert header == "wavelength_nm,zeta,alpha"  # the file's order, as Mitsuba's film holds them
    scene = load_scene(toml)
    assert scene.film_response.wavelengths == (360, 830)  # the responses lie within the visible
    image = Renderer(scene, device).render(spp=16)
    for name, values in _channels(image).items():
        mean, error = mean_and_standard_error(values)
        # The emitter fills the view: every pixel estimates the same integral (1e-4: float32 sums).
        assert_within_standard_errors(mean, _expected(CURVES[name]), error, slack=1e-4 * _expected(CURVES[name]))


def test_responses_beyond_the_visible_widen_the_films_range(tmp_path):
    xml = tmp_path / "scene.xml"
    xml.write_text(_xml({"nir": ((800.0, 0.0), (900.0, 1.0), (1000.0, 0.0))}))
    toml = tmp_path / "imported.toml"
    import_mitsuba(xml, toml)
    scene = load_scene(toml)
    assert scene.film_response.wavelengths == (360, 1000) and scene.film_response.extend_rgb
    assert scene.film_response.sensor.channel_names == ("nir",)


def test_a_specfilm_without_responses_is_one_line(tmp_path):
    xml = tmp_path / "scene.xml"
    xml.write_text(_xml({}))
    toml = tmp_path / "imported.toml"
    with pytest.raises(SpectraceError, match="at least one response") as caught:
        import_mitsuba(xml, toml)
    assert "\n" not in str(caught.value)
    assert not toml.exists() and not (tmp_path / "imported.sensor.csv").exists()


@pytest.mark.peer
def test_specfilm_channels_match_mitsuba(tmp_path, device, mitsuba_scalar_spectral):
    """Mitsuba's channels (in the file's order, as its render returns them) estimate the same integrals."""
    mi = mitsuba_scalar_spectral
    xml = tmp_path / "scene.xml"
    xml.write_text(_xml())
    theirs = np.array(mi.render(mi.load_file(str(xml)), spp=64, seed=1), np.float64).reshape(-1, len(CURVES))
    ours = _channels(Renderer(load_mitsuba_scene(xml), device).render(spp=64))
    for index, name in enumerate(CURVES):
        mean, error = mean_and_standard_error(theirs[:, index])
        assert_within_standard_errors(mean, _expected(CURVES[name]), error, slack=1e-3 * _expected(CURVES[name]))
        ours_mean, ours_error = mean_and_standard_error(ours[name])
        assert_within_standard_errors(ours_mean, mean, np.hypot(error, ours_error), slack=1e-3 * mean)
