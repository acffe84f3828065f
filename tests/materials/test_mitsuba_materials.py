"""Materials imported from Mitsuba 3 render as Mitsuba 3 renders them: small scenes written here, rendered by
Mitsuba's scalar_spectral variant from the XML and by spectrace from its import of the same XML; independent replicas
of each, compared block by block and over the whole image within 5 standard errors of the difference
(replica_agreement). Reflectances are given as spectra, not RGB, so both renderers reflect the same spectrum (RGB
would go through two different uplift tables).

- A rough conductor with Beckmann's distribution (Mitsuba's default) under a small area light: the highlight's
  shape is the distribution's.
- Mitsuba's smooth `plastic`, `nonlinear` false and true: its internal scattering term is spectrace's (the coat's
  diffuse reflectance from inside, F_dr), and `nonlinear` puts the albedo into it.
- Mitsuba's `roughplastic`: the rough coat's own transmittance and internal reflectance (coat_transmission
  "rough"), within an allowance for Mitsuba's coarser tables.
- A `thindielectric` sheet, tilted in front of an area light: the light and the floor seen through it (T'), the
  sky reflected in it (R').

Upright surfaces are OBJ meshes or boxes, not Mitsuba's `rectangle`: Mitsuba 3.9's rectangle stood upright let sky
light through near its middle in one such scene (a floor beside it 15 % above the exact irradiance, which spectrace
and Mitsuba with a box both give).
"""

from pathlib import Path

import numpy as np
import pytest

from replica_agreement import assert_replicas_agree, spectrace_replicas
from spectrace.engine.renderer import Renderer
from spectrace.interop.mitsuba import load_mitsuba_scene
from spectrace.interop.mitsuba.export import mitsuba_film_xyz, scene_to_mitsuba_dict

pytestmark = pytest.mark.peer

SIZE, BLOCK = 24, 6


def _scene(body: str, size: int = SIZE, origin: str = "0, -3, 2.2", max_depth: int = 6) -> str:
    return f"""<scene version="3.0.0">
    <integrator type="path"><integer name="max_depth" value="{max_depth}"/></integrator>
    <sensor type="perspective">
        <float name="fov" value="40"/>
        <transform name="to_world"><lookat origin="{origin}" target="0, 0, 0" up="0, 0, 1"/></transform>
        <film type="hdrfilm"><integer name="width" value="{size}"/><integer name="height" value="{size}"/>
            <string name="pixel_format" value="xyz"/><rfilter type="box"/></film>
    </sensor>
    {body}
</scene>
"""


def _compare(
    tmp_path: Path, device, mi, text: str, replicas: int, replica_spp: int, edit=None, allowance: float = 0.0
) -> None:
    """Both renderers' replicas of `text` agree block by block (`edit`, if given, changes spectrace's imported
    scene: the tests' check that a wrong model fails); `allowance`: a known relative difference of the models that
    each block and the whole image may show on top of 5 standard errors."""
    xml = tmp_path / "scene.xml"
    xml.write_text(text)
    scene = load_mitsuba_scene(xml)
    if edit is not None:
        scene = edit(scene)
    mitsuba_scene = mi.load_file(str(xml))
    theirs = np.stack(
        [mitsuba_film_xyz(mi.render(mitsuba_scene, spp=replica_spp, seed=seed), mi) for seed in range(replicas)]
    )
    ours = spectrace_replicas(Renderer(scene, device), replicas, replica_spp)
    assert theirs[..., 1].mean() > 0.02  # a lit image
    if allowance == 0.0:
        assert_replicas_agree(ours, theirs, BLOCK)
        return
    n = SIZE // BLOCK
    for reduce in (
        lambda images: images.reshape(len(images), n, BLOCK, n, BLOCK, 3).mean(axis=(2, 4)),
        lambda images: images.mean(axis=(1, 2)),
    ):
        a, b = reduce(ours), reduce(theirs)
        difference = a.mean(axis=0) - b.mean(axis=0)
        standard_error = np.sqrt(a.var(axis=0, ddof=1) / len(a) + b.var(axis=0, ddof=1) / len(b))
        beyond = np.abs(difference) - allowance * np.abs(b.mean(axis=0))
        assert np.all(beyond <= 5.0 * standard_error), (np.max(beyond / standard_error), allowance)


FLOOR = """<shape type="rectangle">
        <transform name="to_world"><scale value="3"/></transform>
        {bsdf}
    </shape>"""
AREA_LIGHT = """<shape type="rectangle">
        <transform name="to_world"><scale value="0.3"/><rotate x="1" angle="180"/><translate value="0, 1.2, 1.6"/>
        </transform>
        <emitter type="area"><spectrum name="radiance" value="20"/></emitter>
    </shape>"""


def test_beckmann_rough_conductor_renders_like_mitsuba(tmp_path, device, mitsuba_scalar_spectral):
    """A floor of rough gold (Beckmann α = 0.15, Mitsuba's default distribution) seen at 35° from grazing, the
    reflection of a small area light on it and a dim constant sky. Measured: blocks within 2.2 σ (mean 0.8 σ), the
    whole image within 2.0 σ; the same floor rendered by spectrace with GGX instead fails at 48 σ."""
    bsdf = """<bsdf type="roughconductor"><string name="material" value="Au"/><float name="alpha" value="0.15"/>
        </bsdf>"""
    body = FLOOR.format(bsdf=bsdf) + AREA_LIGHT + '<emitter type="constant"><spectrum name="radiance" value="0.2"/>'
    body += "</emitter>"
    _compare(tmp_path, device, mitsuba_scalar_spectral, _scene(body), replicas=12, replica_spp=16)


REFLECTANCE = '<spectrum name="diffuse_reflectance" value="400:0.15, 480:0.7, 560:0.45, 640:0.25, 700:0.6"/>'


def _plastic_floor_and_wall(bsdf: str) -> str:
    wall = f"""<shape type="cube">
        <transform name="to_world"><scale x="3" y="0.02" z="1.5"/><translate value="0, 1.02, 1.5"/>
        </transform>{bsdf}</shape>"""
    return FLOOR.format(bsdf=bsdf) + wall + '<emitter type="constant"><spectrum name="radiance" value="1"/></emitter>'


@pytest.mark.parametrize("nonlinear", ["false", "true"])
def test_plastic_renders_like_mitsuba(tmp_path, device, mitsuba_scalar_spectral, nonlinear):
    """A floor and a wall of smooth coloured plastic (η = 1.5) meeting at a right angle, under a uniform sky, so
    light reaches the camera after one and after several bounces: each bounce's diffuse part is Mitsuba's, with and
    without `nonlinear`. Measured: blocks within 3.3 σ (false) and 2.6 σ (true), mean 0.7–0.8 σ; spectrace with
    the other setting of `nonlinear` fails at 187 σ and 149 σ."""
    bsdf = f"""<bsdf type="plastic">{REFLECTANCE}<float name="int_ior" value="1.5"/>
        <float name="ext_ior" value="1"/><boolean name="nonlinear" value="{nonlinear}"/></bsdf>"""
    # A thin box, not an upright rectangle (see above).
    _compare(
        tmp_path, device, mitsuba_scalar_spectral, _scene(_plastic_floor_and_wall(bsdf)), replicas=12, replica_spp=16
    )


def _write_quad(path: Path, corners: np.ndarray) -> None:
    """An OBJ of two triangles over four corners in order; their winding (counter-clockwise seen from the front)
    is the face both renderers emit from."""
    lines = [f"v {x:.6f} {y:.6f} {z:.6f}" for x, y, z in corners] + ["f 1 2 3", "f 1 3 4"]
    path.write_text("\n".join(lines) + "\n")


def _thin_sheet_scene(folder: Path) -> str:
    """The sheet's scene (see below), its meshes written into `folder`."""
    up = np.array([0.0, 0.5, np.sqrt(0.75)])  # in the sheet's plane, 30° from the vertical
    x = np.array([1.0, 0.0, 0.0])
    centre = np.array([0.0, 0.0, 0.7])
    _write_quad(folder / "sheet.obj", np.array([centre - x - up, centre + x - up, centre + x + up, centre - x + up]))
    # The light faces -y, toward the sheet and the camera.
    light = np.array([[-0.5, 1.5, 0.2], [0.5, 1.5, 0.2], [0.5, 1.5, 1.2], [-0.5, 1.5, 1.2]])
    _write_quad(folder / "light.obj", light)
    body = f"""
    <shape type="obj"><string name="filename" value="sheet.obj"/>
        <bsdf type="thindielectric"><float name="int_ior" value="1.5"/>
            <spectrum name="specular_transmittance" value="400:0.95, 550:0.8, 700:0.55"/></bsdf></shape>
    <shape type="obj"><string name="filename" value="light.obj"/>
        <bsdf type="diffuse"><spectrum name="reflectance" value="0"/></bsdf>
        <emitter type="area"><spectrum name="radiance" value="6"/></emitter></shape>
    {FLOOR.format(bsdf='<bsdf type="diffuse"><spectrum name="reflectance" value="0.6"/></bsdf>')}
    <emitter type="constant"><spectrum name="radiance" value="0.5"/></emitter>"""
    return _scene(body, origin="0, -3, 0.9").replace('target="0, 0, 0"', 'target="0, 1, 0.6"')


def test_thindielectric_sheet_renders_like_mitsuba(tmp_path, device, mitsuba_scalar_spectral):
    """A tinted thin sheet (η = 1.5) tilted 30° from upright across the view, an area light behind it and a diffuse
    floor under both, in a dim sky: the camera sees the light and the lit floor through the sheet, dimmed by T' and
    the tint, and the sky reflected in it by R' (0.08 at the view's incidence of about 25°). The light's surface is
    black (a shape without a bsdf reflects in spectrace's import, not in Mitsuba's render). Measured: blocks within
    2.0 σ (mean 0.8 σ); spectrace's sheet without the tint fails at 192 σ, and one of η = 1.34 (whose R' is one
    η = 1.5 face's R) at 7 σ in blocks and 10 σ over the whole image."""
    text = _thin_sheet_scene(tmp_path)
    _compare(tmp_path, device, mitsuba_scalar_spectral, text, replicas=12, replica_spp=16)


def _mitsuba_internal_reflectance_allowance(alpha: float, distribution: str, eta: float = 1.5) -> float:
    """How much darker Mitsuba's diffuse part is for its estimate of R_int: the plain mean of 2 μ r_in(μ) at 64
    equally spaced μ (from 0 to 1) instead of the integral, with r_in the rough interface's reflectance from inside
    (spectrace.materials.coat, itself checked against Monte Carlo of the device's BSDF in test_bsdf_dielectric.py):
    (1 − R_mean) / (1 − R_int) − 1, a known difference of the two renderers' tables, not of the model."""
    from spectrace.materials.coat import _albedos, rough_coat

    mu = np.maximum(np.linspace(0.0, 1.0, 64), 1e-6)
    reflected, _ = _albedos(mu, 1.0 / eta, alpha, distribution)
    mean_estimate = float(2.0 * np.mean(reflected * mu))
    return abs((1.0 - mean_estimate) / (1.0 - rough_coat(eta, alpha, distribution)[1]) - 1.0)


@pytest.mark.parametrize("alpha, distribution", [(0.1, "beckmann"), (0.3, "ggx")])
def test_rough_plastic_renders_like_mitsuba(tmp_path, device, mitsuba_scalar_spectral, alpha, distribution):
    """The floor and wall of the plastic test in Mitsuba's roughplastic (imported with coat_transmission "rough":
    the rough coat's own transmittance and internal reflectance). Each block may differ by the allowance for
    Mitsuba's coarser R_int (2.1 % for Beckmann α = 0.1, 1.0 % for GGX α = 0.3) plus 1 % for the other differences
    of the two renderers' tables (Mitsuba's separable masking G1 G1: the white base's albedo head-on at GGX α = 0.3
    is 0.662 with it, 0.668 with spectrace's height-correlated G2; its coarser quadratures). Measured: spectrace's
    image is 2.6 % (Beckmann) and 2.2 % (GGX) brighter, blocks within 1.7 σ and 3.2 σ beyond the allowance; with
    coat_transmission "smooth" the test fails at 6.9 σ (Beckmann) and 98 σ (GGX). With Mitsuba's R_int estimate
    substituted (a check outside the suite) the Beckmann case agrees within 3.0 σ without any allowance."""
    bsdf = f"""<bsdf type="roughplastic">{REFLECTANCE}<float name="int_ior" value="1.5"/>
        <float name="ext_ior" value="1"/><float name="alpha" value="{alpha}"/>
        <string name="distribution" value="{distribution}"/></bsdf>"""
    allowance = _mitsuba_internal_reflectance_allowance(alpha, distribution) + 0.01
    text = _scene(_plastic_floor_and_wall(bsdf))
    _compare(tmp_path, device, mitsuba_scalar_spectral, text, replicas=12, replica_spp=16, allowance=allowance)


def test_exported_thindielectric_is_mitsubas(tmp_path, device, mitsuba_scalar_spectral):
    """The sheet's scene imported and exported back (scene_to_mitsuba_dict: the sheet as Mitsuba's thindielectric
    with its index and tint) renders in Mitsuba as the original XML does, block by block within 5 σ."""
    mi = mitsuba_scalar_spectral
    xml = tmp_path / "scene.xml"
    xml.write_text(_thin_sheet_scene(tmp_path))
    scene = load_mitsuba_scene(xml)
    exported = scene_to_mitsuba_dict(scene, tmp_path / "export", spp=16)
    sheets = [entry for entry in exported.values() if isinstance(entry, dict) and entry.get("type") == "thindielectric"]
    assert len(sheets) == 1 and sheets[0]["int_ior"] == pytest.approx(1.5 / 1.000277, rel=1e-6)
    assert sheets[0]["ext_ior"] == 1.0 and "specular_transmittance" in sheets[0]
    original, back = mi.load_file(str(xml)), mi.load_dict(exported)
    replicas = 8
    theirs = np.stack([mitsuba_film_xyz(mi.render(original, spp=16, seed=seed), mi) for seed in range(replicas)])
    ours = np.stack([mitsuba_film_xyz(mi.render(back, spp=16, seed=100 + seed), mi) for seed in range(replicas)])
    assert_replicas_agree(ours, theirs, BLOCK)
