"""The measured BSDF (kernels/bsdf_measured.cl; Dupuy & Jakob 2018's RGL format) on the device through
kernels/testing/bsdf.cl, on files written here (tests/rgl_tensor.py) from a closed-form GGX reflector: the value
against the formula, the value, density and sampled directions against Mitsuba 3's `measured` reading the same
bytes, the refusals of files it cannot read. The registry's laws (sampling's chi-square, the pdf's integral, energy)
run on the same measurement in tests/materials/test_bsdfs.py, the furnaces in
tests/render/test_furnace_integrators.py, renders against Mitsuba in tests/materials/test_mitsuba_measured.py."""

import numpy as np
import pytest

import spectrace
from cli_runner import run_spectrace
from materials import test_bsdfs as laws
from materials.test_bsdfs import HARNESS, LAMBDA_NM, Bsdf, _uniform_hemisphere
from rgl_tensor import ggx_brdf_cos, ggx_file, ggx_measurement, ramp_reflectance, tensor_file_bytes
from scene_text import emitting_screen
from spectrace.errors import SpectraceError
from spectrace.scene import load_scene

ALPHAS = (0.2, 0.5)


@pytest.fixture(scope="module")
def device_bsdf(kernel_runner):
    runner = kernel_runner(HARNESS)
    return lambda material: Bsdf(runner, material)


def _pairs(n: int, seed: int, max_degrees: float = 80.0) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    a, b = _uniform_hemisphere(rng, n), _uniform_hemisphere(rng, n)
    keep = (a[:, 2] > np.cos(np.radians(max_degrees))) & (b[:, 2] > np.cos(np.radians(max_degrees)))
    return a[keep], b[keep]


def _relative_errors(value: np.ndarray, expected: np.ndarray) -> np.ndarray:
    """|value − expected| / expected where the expected value is above 2 % of its largest (elsewhere the error is
    an absolute one at the tables' resolution, not a relative one)."""
    significant = expected > 0.02 * expected.max()
    return np.abs(value[significant] - expected[significant]) / expected[significant]


@pytest.mark.parametrize("alpha", ALPHAS)
def test_value_is_the_ggx_it_was_written_from(device_bsdf, alpha):
    """f cos θi at four wavelengths equals F(λ) D G2 / (4 cos θo), F rising from 0.5 to 0.9 over the file's five
    wavelengths, within the tables' resolution (32² nodes, 12 viewer elevations): median relative error below 1 %,
    98 % of pairs within 5 % (directions up to 80° from the normal). Measured: medians 0.2 % (α 0.2) and 0.1 %."""
    wo, wi = _pairs(6000, seed=1)
    f_cos, _ = device_bsdf(spectrace.measured(ggx_file(alpha))).eval_pdf(wo, wi)
    expected = ggx_brdf_cos(wo, wi, alpha)[:, None] * ramp_reflectance(LAMBDA_NM)[None, :]
    relative = _relative_errors(f_cos, expected)
    assert np.median(relative) < 0.01, np.median(relative)
    assert np.quantile(relative, 0.98) < 0.05, np.quantile(relative, 0.98)


@pytest.mark.parametrize("alpha", ALPHAS)
def test_reciprocal_as_far_as_the_tables_resolve(device_bsdf, alpha):
    """f(ωo, ωi) = f(ωi, ωo) for a reciprocal measurement, to the tables' resolution (the tables are indexed by the
    viewer's side): median relative difference below 1 %, 98 % within 6 %."""
    wo, wi = _pairs(6000, seed=2)
    device = device_bsdf(spectrace.measured(ggx_file(alpha)))
    f_ab, _ = device.eval_pdf(wo, wi)
    f_ba, _ = device.eval_pdf(wi, wo)
    relative = _relative_errors(f_ab[:, 0] / wi[:, 2], f_ba[:, 0] / wo[:, 2])
    assert np.median(relative) < 0.01, np.median(relative)
    assert np.quantile(relative, 0.98) < 0.06, np.quantile(relative, 0.98)


def _mitsuba_interaction(mi, wo: np.ndarray):
    si = mi.SurfaceInteraction3f()
    si.wi = mi.Vector3f(*wo)
    si.wavelengths = mi.UnpolarizedSpectrum(*[float(v) for v in LAMBDA_NM])
    si.n = mi.Normal3f(0.0, 0.0, 1.0)
    si.sh_frame = mi.Frame3f(si.n)
    return si


@pytest.mark.parametrize("alpha", ALPHAS)
def test_value_and_density_are_mitsubas_on_the_same_file(device_bsdf, mitsuba_scalar_spectral, alpha):
    """Mitsuba 3's `measured` reads the same bytes (its si.wi is the viewer's side, spectrace's ωo): the same value
    at each wavelength and the same density, within float rounding of the two implementations (rtol 1e-3 beside an
    absolute 1e-5 of the peak)."""
    mi = mitsuba_scalar_spectral
    path = ggx_file(alpha)
    bsdf = mi.load_dict({"type": "measured", "filename": str(path)})
    context = mi.BSDFContext()
    wo, wi = _pairs(400, seed=3, max_degrees=85.0)
    f_cos, pdf = device_bsdf(spectrace.measured(path)).eval_pdf(wo, wi)
    theirs = np.array(
        [
            [
                *bsdf.eval(context, _mitsuba_interaction(mi, a), mi.Vector3f(*b)),
                bsdf.pdf(context, _mitsuba_interaction(mi, a), mi.Vector3f(*b)),
            ]
            for a, b in zip(wo, wi, strict=True)
        ]
    )
    np.testing.assert_allclose(f_cos, theirs[:, :4], rtol=1e-3, atol=1e-5 * theirs[:, :4].max())
    np.testing.assert_allclose(pdf, theirs[:, 4], rtol=1e-3, atol=1e-5 * theirs[:, 4].max())


def test_sampled_directions_are_mitsubas_for_the_same_numbers(device_bsdf, mitsuba_scalar_spectral):
    """The same two random numbers draw the same direction in both (the luminance warp, then the visible normals'),
    with the same weight: the sampling maps agree, not only their densities."""
    mi = mitsuba_scalar_spectral
    path = ggx_file(0.5)
    bsdf = mi.load_dict({"type": "measured", "filename": str(path)})
    context = mi.BSDFContext()
    n = 300
    wo = _pairs(2 * n, seed=5)[0][:n]
    ours = device_bsdf(spectrace.measured(path)).sample(wo, len(wo), seed=6)
    u = np.random.default_rng(6).random((len(wo), 4), dtype=np.float32)  # as Bsdf.sample draws them
    found = 0
    for k in range(len(wo)):
        sample, weight = bsdf.sample(
            context, _mitsuba_interaction(mi, wo[k]), float(u[k, 0]), mi.Point2f(u[k, 1], u[k, 2])
        )
        theirs_ok = bool(sample.pdf > 0 and np.max(np.abs(weight)) > 0)
        if not (theirs_ok and ours.ok[k]):
            assert theirs_ok == ours.ok[k] or sample.wo[2] < 1e-3, k
            continue
        found += 1
        np.testing.assert_allclose(ours.wi[k], np.array(sample.wo), atol=2e-4)
        np.testing.assert_allclose(ours.weight[k], np.array(weight), rtol=5e-3)
    assert found > 0.8 * len(wo)


# ---------------------------------------------------------------- refusals


def _fields(**changes):
    fields = ggx_measurement(0.5, size=4, theta_count=2)
    fields.update(changes)
    return {name: value for name, value in fields.items() if value is not None}


REFUSED = {
    "rgb": (
        _fields(wavelengths=None, spectra=None, rgb=np.zeros((1, 2, 3, 4, 4), np.float32)),
        "holds RGB data (an '_rgb' file): give the material's spectral '_spec.bsdf' file",
    ),
    "no ndf": (_fields(ndf=None), "has no field 'ndf'"),
    "float64 sigma": (_fields(sigma=np.ones((4, 4))), "field 'sigma' is float64 of 2 dimensions"),
    "nan spectra": (
        _fields(spectra=np.full((1, 2, 5, 4, 4), np.nan, np.float32)),
        "field 'spectra' has NaN or infinite values",
    ),
    "negative vndf": (_fields(vndf=-np.ones((1, 2, 4, 4), np.float32)), "has negative 'vndf' values"),
    "spectra of another shape": (
        _fields(spectra=np.ones((1, 2, 5, 4, 3), np.float32)),
        "has a 'spectra' field of shape (1, 2, 5, 4, 3)",
    ),
    "unordered theta": (_fields(theta_i=np.array([1.0, 0.5], np.float32)), "has 'theta_i' values that do not increase"),
}


@pytest.mark.parametrize("case", list(REFUSED))
def test_files_it_cannot_read_are_refused_in_one_line(tmp_path, case):
    fields, expected = REFUSED[case]
    path = tmp_path / "material_spec.bsdf"
    path.write_bytes(tensor_file_bytes(fields))
    with pytest.raises(SpectraceError) as refused:
        spectrace.measured(path)
    message = str(refused.value)
    assert expected in message and "material_spec.bsdf" in message and "\n" not in message, message


@pytest.mark.parametrize(
    "data, expected",
    [
        (b"P6\n1 1\n255\n", "does not begin with 'tensor_file'"),
        (tensor_file_bytes(_fields())[:40], "its header ends early"),
        (tensor_file_bytes(_fields())[:-64], "reaches past the end"),
    ],
    ids=["not a tensor file", "truncated header", "truncated data"],
)
def test_broken_tensor_files_are_refused_in_one_line(tmp_path, data, expected):
    path = tmp_path / "broken_spec.bsdf"
    path.write_bytes(data)
    with pytest.raises(SpectraceError) as refused:
        spectrace.measured(path)
    assert expected in str(refused.value) and "\n" not in str(refused.value), str(refused.value)


@pytest.mark.subprocess
def test_render_of_a_scene_naming_an_rgb_file_fails_in_one_line_naming_the_key(tmp_path):
    """The command line: the scene file and the material's key path in one line, a non-zero status, no traceback,
    and no image written."""
    fields, _ = REFUSED["rgb"]
    (tmp_path / "paint_rgb.bsdf").write_bytes(tensor_file_bytes(fields))
    scene = (
        emitting_screen(shape='type = "rectangle"', extra="")
        + '\n[materials.paint]\ntype = "measured"\nfilename = "paint_rgb.bsdf"\n'
    )
    scene = scene.replace('material = "black"', 'material = "paint"')
    (tmp_path / "scene.toml").write_text(scene)
    result = run_spectrace("render", str(tmp_path / "scene.toml"), "-o", str(tmp_path / "out.png"))
    lines = result.stderr.strip().splitlines()
    assert result.returncode != 0 and len(lines) == 1, result.stderr
    assert "scene.toml" in lines[0] and "materials.paint.filename" in lines[0], lines[0]
    assert "'_spec.bsdf'" in lines[0] and "Traceback" not in result.stderr
    assert not (tmp_path / "out.png").exists()


def test_a_scene_built_in_python_saves_the_file_as_its_scene_file_finds_it(tmp_path, monkeypatch):
    """The API's `filename` is relative to the working folder, the scene file's to the scene file's folder: a saved
    scene names the file from where it is written, and loads the same tables."""
    monkeypatch.chdir(ggx_file(0.5).parent)
    material = spectrace.measured(ggx_file(0.5).name)
    scene = spectrace.Scene(
        camera=spectrace.Camera(origin=(0.0, 1.0, -4.0), target=(0.0, 0.0, 0.0), fov_degrees=40.0),
        width=8,
        height=8,
        shapes=[spectrace.shape("sphere", material)],
        lights=[spectrace.constant_environment(1.0)],
    )
    path = spectrace.save_scene(scene, tmp_path / "saved" / "scene.toml")
    loaded = load_scene(path).shapes[0].material
    assert loaded.tables == material.tables


# Files written as anisotropic ones (absolute microfacet azimuths, the viewer's azimuth a parameter), whole and
# folded by GGX's symmetries: φo spanning 2π (reduction 1), π (2) and π/2 (4).
FOLDS = {1: np.linspace(-np.pi, np.pi, 9), 2: np.linspace(-np.pi, 0.0, 5), 4: np.linspace(-np.pi, -np.pi / 2, 3)}


@pytest.fixture(scope="module")
def anisotropic_files(tmp_path_factory):
    folder = tmp_path_factory.mktemp("anisotropic")
    paths = {}
    for reduction, phi_i in FOLDS.items():
        paths[reduction] = folder / f"ggx_r{reduction}_spec.bsdf"
        fields = ggx_measurement(0.4, size=24, theta_count=8, phi_i=phi_i)
        paths[reduction].write_bytes(tensor_file_bytes(fields))
    return paths


@pytest.mark.parametrize("reduction", list(FOLDS))
def test_anisotropic_files_are_the_ggx_and_mitsubas(device_bsdf, mitsuba_scalar_spectral, anisotropic_files, reduction):
    """An anisotropic file's tables, folded or whole, read as Mitsuba 3 reads them (value and density, rtol 1e-3)
    and give the GGX they were written from (median relative error below 2 %: coarser tables than the isotropic
    ones, the viewer's azimuth interpolated too)."""
    mi = mitsuba_scalar_spectral
    path = anisotropic_files[reduction]
    device = device_bsdf(spectrace.measured(path))
    assert spectrace.measured(path).tables.reduction == reduction
    wo, wi = _pairs(3000, seed=7)
    f_cos, _ = device.eval_pdf(wo, wi)
    expected = ggx_brdf_cos(wo, wi, 0.4)[:, None] * ramp_reflectance(LAMBDA_NM)[None, :]
    assert np.median(_relative_errors(f_cos, expected)) < 0.02
    bsdf = mi.load_dict({"type": "measured", "filename": str(path)})
    context = mi.BSDFContext()
    f_cos, pdf = device.eval_pdf(wo[:200], wi[:200])
    theirs = np.array(
        [
            [
                *bsdf.eval(context, _mitsuba_interaction(mi, a), mi.Vector3f(*b)),
                bsdf.pdf(context, _mitsuba_interaction(mi, a), mi.Vector3f(*b)),
            ]
            for a, b in zip(wo[:200], wi[:200], strict=True)
        ]
    )
    np.testing.assert_allclose(f_cos, theirs[:, :4], rtol=1e-3, atol=1e-5 * theirs[:, :4].max())
    np.testing.assert_allclose(pdf, theirs[:, 4], rtol=1e-3, atol=1e-5 * theirs[:, 4].max())


@pytest.mark.parametrize("reduction", list(FOLDS))
@pytest.mark.slow
def test_anisotropic_sampling_follows_its_density(device_bsdf, anisotropic_files, reduction):
    """The registry's sampling laws (tests/materials/test_bsdfs.py) on the anisotropic files: the chi-square of
    sampled directions against the pdf, and the pdf's integral against the sampler's success rate, from a viewer
    whose azimuth the folded files mirror. The pdf is integrated on a quarter of the laws' grid (500 × 512 cells):
    on each file its bins' probabilities differ from the full grid's by under 0.5 standard errors of the
    histogram's counts (a chi-square of 0.2 at most, where the statistic's own spread is about 18) and its
    integral by under 2e-4 (a tenth of the slack)."""
    material = spectrace.measured(anisotropic_files[reduction])
    grid = (500, 512)
    laws.test_sampler_matches_its_pdf_chi_square(device_bsdf, f"measured-r{reduction}", material, grid)
    laws.test_pdf_integrates_to_the_samplers_success_rate(device_bsdf, f"measured-r{reduction}", material, grid)


def test_a_live_sessions_edits_store_the_tables_once(tmp_path):
    """Each edit of a material writes every material's row again: the measured tables stay one block of the
    spectrum table (a database file's are tens of MB), and the image after the edits is a fresh render's."""
    from spectrace.session import Session

    scene = tmp_path / "scene.toml"
    scene.write_text(
        f"""[film]
width = 8
height = 8

[camera]
origin = [0, 0, 4]
target = [0, 0, 0]
fov = 30

[materials.paint]
type = "measured"
filename = "{ggx_file(0.5).as_posix()}"

[materials.grey]
type = "diffuse"
reflectance = {{ value = 0.5 }}

[[shapes]]
type = "sphere"
material = "paint"
transform = [{{ translate = [-0.5, 0, 0] }}]

[[shapes]]
type = "sphere"
material = "grey"
transform = [{{ translate = [0.6, 0, 0] }}]

[[lights]]
type = "constant"
radiance = {{ value = 1.0 }}
"""
    )
    with Session(scene, pass_spp=1) as session:
        size = len(session.renderer.buffers.spectra)
        for value in (0.2, 0.4, 0.6):
            session.update({"materials.grey.reflectance": {"value": value}})
        assert len(session.renderer.buffers.spectra) <= size + 3 * 471  # three new reflectances at most
        session.step()
        image = session.image().xyz
    fresh = spectrace.render(spectrace.load_scene(scene, {"materials.grey.reflectance": {"value": 0.6}}), spp=1)
    assert image[..., 1].mean() > 0
    np.testing.assert_array_equal(image, fresh.xyz)
