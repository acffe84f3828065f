"""Polarised scenes render as Mitsuba 3's scalar_spectral_polarized renders them with its `stokes` integrator: the
same XML rendered by Mitsuba and by spectrace's import of it (which turns `stokes` into polarised transport with the
`stokes` AOV), the Y of each Stokes image compared in 2 x 2 blocks of the 8 x 8 image within 5 standard errors of
the difference (each renderer's pixel spread within the block; its pixels see one value up to a fraction of a
degree of angle). Mitsuba writes each Stokes image as linear sRGB, whose Y is the film's.

Conventions (measured with Mitsuba 3's scalar_spectral_polarized): the two renderers' Stokes images are in the same
camera basis and the same sense of S3 (Collett's), so they are compared as they are: S1 and S2 of reflections seen
by a camera turned about its view axis, and S3 of light reflected by two conductors in turned planes of incidence,
agree with no sheet in the scene (test_handedness checks that sense against Maxwell's equations); Mitsuba's
polarizer measures its theta the other way round from spectrace's angle (spectrace.materials.polarizer.mitsuba_angle),
its retarder's theta and delta are spectrace's. The last tests render Mitsuba's own polarisation docs scenes when
their files are at hand (SPECTRACE_MITSUBA_DATA)."""

from pathlib import Path

import numpy as np
import pytest
from tests.polarization.stokes_scenes import sheets

import spectrace
from spectrace.interop.mitsuba import load_mitsuba_scene
from spectrace.interop.mitsuba.export import scene_to_mitsuba_dict
from spectrace.scene.loader import load_scene

pytestmark = pytest.mark.peer

SIZE, BLOCK = 8, 4
# Of S0, on top of 5 standard errors: the delta paths here have almost no noise, and the two renderers treat light
# crossing a sheet obliquely differently (spectrace projects the sheet's axis onto the plane normal to the ray):
# in a view 10° wide the wave-plate scene's S1 differs by 1.7 % (0.7 % of S0), in the 2° views here by 0.02 %.
ALLOWANCE = 0.005
SRGB_Y = np.array([0.2126, 0.7152, 0.0722])  # linear sRGB → Y (IEC 61966-2-1)


@pytest.fixture(scope="module")
def mitsuba_polarized():
    mitsuba = pytest.importorskip("mitsuba", reason="the Mitsuba comparison needs `pip install spectrace[test]`")
    if "scalar_spectral_polarized" not in mitsuba.variants():
        pytest.skip("this mitsuba build has no scalar_spectral_polarized variant")
    mitsuba.set_variant("scalar_spectral_polarized")
    return mitsuba


def _scene(body: str, origin: str, up: str, fov: float, spp: int = 64) -> str:
    return f"""<scene version="3.0.0">
    <integrator type="stokes"><integrator type="path"><integer name="max_depth" value="6"/></integrator></integrator>
    <sensor type="perspective">
        <float name="fov" value="{fov}"/>
        <transform name="to_world"><lookat origin="{origin}" target="0, 0, 0" up="{up}"/></transform>
        <sampler type="independent"><integer name="sample_count" value="{spp}"/></sampler>
        <film type="hdrfilm"><integer name="width" value="{SIZE}"/><integer name="height" value="{SIZE}"/>
            <string name="pixel_format" value="xyz"/><rfilter type="box"/></film>
    </sensor>
    {body}
</scene>
"""


def _blocks(stokes_y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Block means and their standard errors of (SIZE, SIZE, 4) Stokes Y images."""
    n = SIZE // BLOCK
    cells = stokes_y.reshape(n, BLOCK, n, BLOCK, 4).transpose(0, 2, 1, 3, 4).reshape(n, n, BLOCK * BLOCK, 4)
    return cells.mean(axis=2), cells.std(axis=2, ddof=1) / np.sqrt(BLOCK * BLOCK)


def _compare(tmp_path: Path, mi, text: str, components: tuple[int, ...] = (0, 1, 2, 3)) -> np.ndarray:
    xml = tmp_path / "scene.xml"
    xml.write_text(text)
    theirs_rgb = np.asarray(mi.render(mi.load_file(str(xml)), seed=3), np.float64)[..., 3:15]
    theirs = theirs_rgb.reshape(SIZE, SIZE, 4, 3) @ SRGB_Y
    image = spectrace.render(load_mitsuba_scene(xml), progress=False, colour_space="xyz")
    ours = image.aovs["stokes"].reshape(SIZE, SIZE, 4, 3)[..., 1].astype(np.float64)
    (a, sa), (b, sb) = _blocks(ours), _blocks(theirs)
    tolerance = 5.0 * np.sqrt(sa**2 + sb**2) + ALLOWANCE * np.abs(b[..., :1])
    beyond = (np.abs(a - b) / tolerance)[..., list(components)]
    assert np.all(beyond <= 1.0), (a.mean(axis=(0, 1)), b.mean(axis=(0, 1)), beyond)
    return b.mean(axis=(0, 1))


EMITTER_BELOW = """<shape type="rectangle"><transform name="to_world"><scale x="2" y="2"/></transform>
        <bsdf type="diffuse"><spectrum name="reflectance" value="0"/></bsdf>
        <emitter type="area"><spectrum name="radiance" value="1"/></emitter></shape>"""


def _sheet(z: float, bsdf: str) -> str:
    return f"""<shape type="rectangle"><transform name="to_world"><translate z="{z}"/></transform>{bsdf}</shape>"""


def test_polarizer_pair_and_wave_plate_render_like_mitsuba(tmp_path, mitsuba_polarized):
    body = (
        EMITTER_BELOW
        + _sheet(1.0, '<bsdf type="polarizer"><float name="theta" value="10"/></bsdf>')
        + _sheet(1.25, '<bsdf type="polarizer"><float name="theta" value="40"/></bsdf>')
        + _sheet(1.5, '<bsdf type="retarder"><float name="theta" value="-25"/><float name="delta" value="70"/></bsdf>')
    )
    means = _compare(tmp_path, mitsuba_polarized, _scene(body, "0, 0, 3", "0, 1, 0", 2))
    assert abs(means[3]) > 0.1 * means[0]  # circular light: the retarder's sense is tested


GLASS_AND_METAL = """<emitter type="constant"><spectrum name="radiance" value="1"/></emitter>
    <shape type="rectangle">{plate}</shape>
    <shape type="rectangle"><transform name="to_world"><scale x="20" y="20"/><translate z="-0.5"/></transform>
        <bsdf type="diffuse"><spectrum name="reflectance" value="0"/></bsdf></shape>"""


def _reflection(incidence: float) -> tuple[str, str]:
    theta = np.radians(incidence)
    return f"{3 * np.sin(theta):.9f}, 0, {3 * np.cos(theta):.9f}", "0, 0, 1"


def test_glass_plate_near_brewster_renders_like_mitsuba(tmp_path, mitsuba_polarized):
    """Glass of index 1.5 seen 1.3° off its Brewster angle (56.3°): nearly all s-polarised (S1 ≈ S0)."""
    plate = '<bsdf type="dielectric"><float name="int_ior" value="1.5"/></bsdf>'
    origin, up = _reflection(55.0)
    # S2 is a few 1e-4 of S0 in every block, from each pixel's plane of incidence against the camera's basis, which
    # the two renderers turn differently off the view axis: compared as nearly 0 in both.
    means = _compare(tmp_path, mitsuba_polarized, _scene(GLASS_AND_METAL.format(plate=plate), origin, up, 1), (0, 1, 3))
    assert means[1] > 0.9 * means[0]
    assert abs(means[2]) < 0.002 * means[0]


def test_conductor_behind_a_polarizer_renders_like_mitsuba(tmp_path, mitsuba_polarized):
    """A smooth conductor (0.2 + 3.5i) at 45° reflecting sky light polarised at 45° to the plane of incidence: the
    metal's retardance makes it elliptical (S3 ≈ -0.38 S0)."""
    plate = '<bsdf type="conductor"><spectrum name="eta" value="0.2"/><spectrum name="k" value="3.5"/></bsdf>'
    theta = np.radians(45.0)
    centre = 1.5 * np.array([-np.sin(theta), 0.0, np.cos(theta)])
    sheet = f"""<shape type="rectangle"><transform name="to_world"><rotate y="1" angle="-45"/>
        <translate x="{centre[0]:.9f}" z="{centre[2]:.9f}"/></transform>
        <bsdf type="polarizer"><float name="theta" value="45"/></bsdf></shape>"""
    origin, up = _reflection(45.0)
    means = _compare(tmp_path, mitsuba_polarized, _scene(GLASS_AND_METAL.format(plate=plate) + sheet, origin, up, 2))
    assert means[3] < -0.3 * means[0]


def _rough_conductor(alpha: float, eta: float, k: float) -> str:
    return f"""<bsdf type="roughconductor"><string name="distribution" value="ggx"/>
        <float name="alpha" value="{alpha}"/><spectrum name="eta" value="{eta}"/>
        <spectrum name="k" value="{k}"/></bsdf>"""


def test_rough_conductor_behind_a_polarizer_renders_like_mitsuba(tmp_path, mitsuba_polarized):
    """The conductor above made rough (GGX, α = 0.05): Mitsuba 3's polarised roughconductor applies the Fresnel
    Mueller matrix on each microfacet, in its plane of incidence, as spectrace does; BSDF sampling and the sky's
    light samples both reach the polariser's light. Rougher, the camera sees the sheet obliquely enough for the two
    renderers' oblique polarisers to differ (α = 0.2: S1 0.04 S0 here, -0.02 S0 in Mitsuba, though by the scene's
    mirror symmetry a conductor turns none of the sheet's S2 into S1); the unpolarised sky below tests α = 0.2."""
    theta = np.radians(45.0)
    centre = 1.5 * np.array([-np.sin(theta), 0.0, np.cos(theta)])
    sheet = f"""<shape type="rectangle"><transform name="to_world"><scale x="3" y="3"/><rotate y="1" angle="-45"/>
        <translate x="{centre[0]:.9f}" z="{centre[2]:.9f}"/></transform>
        <bsdf type="polarizer"><float name="theta" value="45"/></bsdf></shape>"""
    origin, up = _reflection(45.0)
    plate = _rough_conductor(0.05, 0.2, 3.5)
    text = _scene(GLASS_AND_METAL.format(plate=plate) + sheet, origin, up, 2, 256)
    means = _compare(tmp_path, mitsuba_polarized, text)
    assert means[3] < -0.3 * means[0]


def test_rough_conductor_under_the_sky_renders_like_mitsuba(tmp_path, mitsuba_polarized):
    """A rough conductor (GGX, α = 0.2, index 1.2 + 2i) reflecting the unpolarised sky at 70°: partially
    s-polarised (S1 ≈ 0.35 S0)."""
    origin, up = _reflection(70.0)
    plate = _rough_conductor(0.2, 1.2, 2.0)
    text = _scene(GLASS_AND_METAL.format(plate=plate), origin, up, 2, 256)
    means = _compare(tmp_path, mitsuba_polarized, text)
    assert means[1] > 0.25 * means[0]


def test_rough_glass_renders_like_mitsuba_in_s0(tmp_path, mitsuba_polarized):
    """A rough glass plate (GGX, α = 0.2) reflecting the sky: S0 as Mitsuba's. Mitsuba 3's roughdielectric
    depolarises in its polarised variants (its BSDF returns a depolariser), where spectrace applies the Fresnel
    matrix on each microfacet (test_rough_microfacets), so S1..S3 differ by design and are not compared here."""
    plate = """<bsdf type="roughdielectric"><string name="distribution" value="ggx"/><float name="alpha" value="0.2"/>
        <float name="int_ior" value="1.5"/></bsdf>"""
    origin, up = _reflection(55.0)
    text = _scene(GLASS_AND_METAL.format(plate=plate), origin, up, 2, spp=256)
    _compare(tmp_path, mitsuba_polarized, text, (0,))


@pytest.mark.parametrize(
    ("incidence", "alpha", "rho", "distribution"),
    [(60.0, 0.2, 0.3, "ggx"), (75.0, 0.2, 0.8, "ggx"), (60.0, 0.1, 0.5, "beckmann")],
    ids=["specular s-polarised", "diffuse p-polarised", "beckmann"],
)
def test_pplastic_under_the_sky_renders_like_mitsuba(tmp_path, mitsuba_polarized, incidence, alpha, rho, distribution):
    """Mitsuba 3's pplastic (Baek et al. 2018) reflecting the unpolarised sky: its specular light polarised along
    the plane of incidence's normal (S1 > 0), its diffuse light, which the refraction out polarises across it,
    S1 < 0 where the base dominates (ρ = 0.8 at 75°)."""
    plate = f"""<bsdf type="pplastic"><string name="distribution" value="{distribution}"/>
        <float name="alpha" value="{alpha}"/><spectrum name="diffuse_reflectance" value="{rho}"/>
        <float name="int_ior" value="1.5"/></bsdf>"""
    origin, up = _reflection(incidence)
    text = _scene(GLASS_AND_METAL.format(plate=plate), origin, up, 2, 256)
    means = _compare(tmp_path, mitsuba_polarized, text)
    assert abs(means[1]) > 0.03 * means[0]


def test_rough_plastic_depolarises_as_in_mitsuba(tmp_path, mitsuba_polarized):
    """Mitsuba 3's roughplastic has no polarised model (its BSDF returns a depolariser), nor has spectrace's rough
    plastic: the same S0 under the sky at 70°, and S1..S3 zero in both."""
    plate = """<bsdf type="roughplastic"><string name="distribution" value="ggx"/><float name="alpha" value="0.2"/>
        <spectrum name="diffuse_reflectance" value="0.3"/><float name="int_ior" value="1.5"/></bsdf>"""
    origin, up = _reflection(70.0)
    means = _compare(tmp_path, mitsuba_polarized, _scene(GLASS_AND_METAL.format(plate=plate), origin, up, 2, 256))
    assert means[0] > 0.1 and np.all(means[1:] == 0.0)


def test_exported_polarizer_and_retarder_render_like_spectrace(tmp_path, mitsuba_polarized):
    """The other way: spectrace's polariser at 30° and retarder (20°, 60°) exported to Mitsuba (its `polarizer`'s
    theta negated, its `retarder`'s as it is), the export's integrator wrapped in `stokes`: S0..S3 as spectrace's."""
    path = tmp_path / "scene.toml"
    # A view 2° wide, as above: the renderers' sheets crossed obliquely part at the edges of a wider one.
    camera = "origin = [0, 0, 3]\ntarget = [0, 0, 0]\nfov = 2"
    path.write_text(
        sheets('type = "polarizer"\nangle = 30', 'type = "retarder"\nangle = 20\nretardance = 60', camera=camera)
    )
    scene = load_scene(path)
    exported = scene_to_mitsuba_dict(scene, tmp_path, spp=64)
    exported["integrator"] = {"type": "stokes", "nested": exported["integrator"]}
    theirs_rgb = np.asarray(mitsuba_polarized.render(mitsuba_polarized.load_dict(exported), seed=3), np.float64)
    theirs = theirs_rgb[..., 3:15].reshape(SIZE, SIZE, 4, 3) @ SRGB_Y
    ours = spectrace.render(scene, progress=False, colour_space="xyz").aovs["stokes"]
    (a, sa), (b, sb) = _blocks(ours.reshape(SIZE, SIZE, 4, 3)[..., 1].astype(np.float64)), _blocks(theirs)
    tolerance = 5.0 * np.sqrt(sa**2 + sb**2) + ALLOWANCE * np.abs(b[..., :1])
    assert np.all(np.abs(a - b) <= tolerance), (a.mean(axis=(0, 1)), b.mean(axis=(0, 1)))
    assert abs(b[..., 2].mean()) > 0.3 * b[..., 0].mean() and abs(b[..., 3].mean()) > 0.1 * b[..., 0].mean()
