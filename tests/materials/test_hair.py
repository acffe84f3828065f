"""The hair BSDF (kernels/bsdf_hair.cl; Chiang, Bitterli, Tappan & Burley 2016) on the device through
kernels/testing/bsdf_hair.cl, at offsets h across the fibre: the paper's white furnace (σa = 0: ∫ S dω = 1 for
every roughness, estimated with directions drawn uniformly on the sphere, independent of the BSDF's sampler), the
sampler's chi-square against its pdf and the pdf integrating to 1, sample weights equal to S / pdf (and, for
importance transport, the adjoint S(ωi, ωo) |cos θi| / |cos θo| / pdf), and melanin's absorption against the paper's
linear sRGB values (colour-science as the reference)."""

import warnings

import numpy as np
import pytest

from spectrace.materials import material_row
from spectrace.materials.hair import EUMELANIN_RGB, PHEOMELANIN_RGB, HairMaterial, melanin_sigma_a
from spectrace.spectral.grid import GRID_NM
from spectrace.spectral.spectrum import Spectrum
from spectrace.spectral.table import SpectrumTable
from stats_toolkit import assert_chi_square_fits, assert_within_standard_errors, mean_and_standard_error

HARNESS = "testing/bsdf_hair.cl"
LAMBDA_NM = np.array([420.0, 510.0, 600.0, 690.0], np.float32)
SIGMAS = 4.0


def _float4(vectors: np.ndarray) -> np.ndarray:
    out = np.zeros((len(vectors), 4), np.float32)
    out[:, :3] = vectors
    return out


def _uniform_sphere(rng: np.random.Generator, n: int) -> np.ndarray:
    z = 2.0 * rng.random(n) - 1.0
    phi = 2.0 * np.pi * rng.random(n)
    r = np.sqrt(np.maximum(0.0, 1.0 - z * z))
    return np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=1)


class Hair:
    def __init__(self, runner, material: HairMaterial):
        table = SpectrumTable()
        table.add(Spectrum.zeros())
        self.row = material_row(material, table)
        self.runner = runner
        self.material = runner.buffer(np.array([self.row]))
        self.spectra = runner.buffer(table.data)
        self.lam = runner.buffer(LAMBDA_NM)

    def eval_pdf(self, wo, wi, h) -> tuple[np.ndarray, np.ndarray]:
        n = len(wi)
        wo = np.broadcast_to(wo, wi.shape)
        h = np.broadcast_to(np.asarray(h, np.float32), (n,)).copy()
        f_cos, pdf = np.zeros((n, 4), np.float32), np.zeros(n, np.float32)
        args = [
            self.material,
            self.spectra,
            self.lam,
            self.runner.buffer(_float4(wo)),
            self.runner.buffer(_float4(wi)),
            self.runner.buffer(h),
            self.runner.buffer(f_cos, True),
            self.runner.buffer(pdf, True),
        ]
        self.runner.run("hair_harness_eval_pdf", n, args, {6: f_cos, 7: pdf})
        return f_cos.astype(np.float64), pdf.astype(np.float64)

    def sample(self, wo, h, n: int, seed: int, adjoint: bool = False):
        u = np.random.default_rng(seed).random((n, 4), dtype=np.float32)
        wos = np.broadcast_to(wo, (n, 3)) if np.ndim(wo) == 1 else wo
        hs = np.broadcast_to(np.asarray(h, np.float32), (n,)).copy()
        wi, weight = np.zeros((n, 4), np.float32), np.zeros((n, 4), np.float32)
        pdf = np.zeros(n, np.float32)
        args = [
            self.material,
            self.spectra,
            self.lam,
            self.runner.buffer(_float4(wos)),
            self.runner.buffer(u),
            self.runner.buffer(hs),
            np.int32(adjoint),
            self.runner.buffer(wi, True),
            self.runner.buffer(weight, True),
            self.runner.buffer(pdf, True),
        ]
        self.runner.run("hair_harness_sample", n, args, {7: wi, 8: weight, 9: pdf})
        return wi[:, :3].astype(np.float64), wi[:, 3] > 0, weight.astype(np.float64), pdf.astype(np.float64)


@pytest.fixture(scope="module")
def hair(kernel_runner):
    runner = kernel_runner(HARNESS)
    return lambda material: Hair(runner, material)


def _white(beta_m: float, beta_n: float, alpha: float = 2.0) -> HairMaterial:
    return HairMaterial(Spectrum.constant(0.0), beta_m=beta_m, beta_n=beta_n, alpha=alpha)


BROWN = HairMaterial(melanin_sigma_a(1.3, 0.0))
RED = HairMaterial(melanin_sigma_a(0.3, 1.2), beta_m=0.2, beta_n=0.5, alpha=-3.0)


@pytest.mark.parametrize("beta_m", (0.1, 0.3, 0.6, 1.0))
@pytest.mark.parametrize("beta_n", (0.1, 0.3, 0.6, 1.0))
def test_white_furnace(hair, beta_m, beta_n):
    """σa = 0: ∫ S(ωo, ωi) dωi = 1 (the paper's white furnace), for many ωo and h, each estimated from directions
    drawn uniformly on the sphere (4π S): within 4 standard errors."""
    device = hair(_white(beta_m, beta_n))
    rng = np.random.default_rng(int(100 * beta_m + 10 * beta_n))
    n = 40000
    for wo, h in zip(_uniform_sphere(rng, 6), (-0.95, -0.5, 0.0, 0.3, 0.7, 0.99), strict=True):
        # Stay off exact grazing along the fibre, where cos θo → 0 and every lobe collapses onto the axis.
        wi = _uniform_sphere(rng, n)
        f_cos, _ = device.eval_pdf(wo, wi, h)
        assert np.all(np.isfinite(f_cos)) and np.all(f_cos >= 0)
        mean, se = mean_and_standard_error(4.0 * np.pi * f_cos)
        assert_within_standard_errors(mean, 1.0, se, SIGMAS, slack=2e-3, what=(beta_m, beta_n, wo, h))


@pytest.mark.parametrize("material", (BROWN, RED, _white(0.3, 0.3)), ids=("brown", "red", "white"))
def test_pdf_integrates_to_one_and_weights_are_value_over_pdf(hair, material):
    """∫ pdf dω = 1 (uniform sphere estimate, 4σ); each sample's weight is S / pdf and its pdf the pdf's value; in
    importance transport the weight is the adjoint's, S(ωi, ωo) |cos θi| / |cos θo| / pdf; an absorbing fibre
    reflects less than it receives."""
    device = hair(material)
    rng = np.random.default_rng(5)
    for wo, h in zip(_uniform_sphere(rng, 4), (-0.6, 0.1, 0.5, 0.9), strict=True):
        wi = _uniform_sphere(rng, 40000)
        f_cos, pdf = device.eval_pdf(wo, wi, h)
        mean, se = mean_and_standard_error(4.0 * np.pi * pdf)
        assert_within_standard_errors(mean, 1.0, se, SIGMAS, slack=2e-3, what=(wo, h))
        assert np.all(4.0 * np.pi * f_cos.mean(axis=0) <= 1.0 + SIGMAS * 4.0 * np.pi * f_cos.std(axis=0) / 200.0)
        for adjoint in (False, True):
            s_wi, ok, weight, s_pdf = device.sample(wo, h, 4000, seed=6 + adjoint, adjoint=adjoint)
            assert ok.mean() > 0.99
            f, p = device.eval_pdf(wo, s_wi[ok], h)
            np.testing.assert_allclose(s_pdf[ok], p, rtol=2e-3)
            if adjoint:
                f_swapped, _ = device.eval_pdf(s_wi[ok], np.broadcast_to(wo, s_wi[ok].shape), h)
                f = f_swapped * (np.abs(s_wi[ok][:, 2:3]) / abs(wo[2]))
            np.testing.assert_allclose(weight[ok], f / p[:, None], rtol=3e-3, atol=1e-6)


# Bins uniform in sin θ = ωi.x and φ about the fibre: equal areas on the sphere.
CHI2_X_BINS, CHI2_PHI_BINS = 10, 16
GRID_X, GRID_PHI = 500, 1024
CHI2_SAMPLES = 200_000
CHI2_CASES = [("brown", BROWN), ("red", RED), ("white-rough", _white(0.7, 0.8))]
CHI2_DIRECTIONS = ((0.3, 0.2, 0.93, -0.4), (-0.6, 0.7, 0.38, 0.8), (0.85, -0.2, -0.49, 0.05))
CHI2_SIGNIFICANCE = 0.01 / (len(CHI2_CASES) * len(CHI2_DIRECTIONS))


@pytest.mark.parametrize("name, material", CHI2_CASES, ids=[c[0] for c in CHI2_CASES])
@pytest.mark.slow
def test_sampler_matches_its_pdf_chi_square(hair, name, material):
    """Histogram of sampled directions against N × the pdf integrated over each bin (midpoint rule on a fine grid),
    plus one bin for samples that produced no direction."""
    device = hair(material)
    x = -1.0 + 2.0 * (np.arange(GRID_X) + 0.5) / GRID_X
    phi = 2.0 * np.pi * (np.arange(GRID_PHI) + 0.5) / GRID_PHI
    r = np.sqrt(1.0 - x**2)[:, None]
    grid = np.stack(np.broadcast_arrays(x[:, None], r * np.cos(phi), r * np.sin(phi)), axis=-1).reshape(-1, 3)
    cell = (2.0 / GRID_X) * (2.0 * np.pi / GRID_PHI)
    for index, (*direction, h) in enumerate(CHI2_DIRECTIONS):
        wo = np.array(direction) / np.linalg.norm(direction)
        _, pdf = device.eval_pdf(wo, grid, h)
        probabilities = (
            (pdf.reshape(GRID_X, GRID_PHI) * cell)
            .reshape(CHI2_X_BINS, GRID_X // CHI2_X_BINS, CHI2_PHI_BINS, GRID_PHI // CHI2_PHI_BINS)
            .sum(axis=(1, 3))
        )
        # The lobes are normalised: the pdf's quadrature is 1 (Mp with I0 and log I0 truncated as pbrt-v4 does was
        # 0.4 % short here).
        assert abs(probabilities.sum() - 1.0) < 5e-4, probabilities.sum()
        wi, ok, _, _ = device.sample(wo, h, CHI2_SAMPLES, seed=300 + index)
        wi = wi[ok]
        x_bin = np.clip(((wi[:, 0] + 1.0) * 0.5 * CHI2_X_BINS).astype(int), 0, CHI2_X_BINS - 1)
        angle = np.mod(np.arctan2(wi[:, 2], wi[:, 1]), 2.0 * np.pi)
        phi_bin = np.clip((angle / (2.0 * np.pi) * CHI2_PHI_BINS).astype(int), 0, CHI2_PHI_BINS - 1)
        observed = np.zeros((CHI2_X_BINS, CHI2_PHI_BINS))
        np.add.at(observed, (x_bin, phi_bin), 1.0)
        expected = CHI2_SAMPLES * probabilities
        observed_all = np.append(observed.ravel(), CHI2_SAMPLES - ok.sum())
        expected_all = np.append(expected.ravel(), CHI2_SAMPLES * max(1.0 - probabilities.sum(), 0.0))
        assert_chi_square_fits(observed_all, expected_all, CHI2_SIGNIFICANCE, what=(name, index))


def _srgb_under_d65(values: np.ndarray) -> np.ndarray:
    """Linear sRGB of a spectrum on the grid read as a reflectance under D65, by colour-science."""
    colour = pytest.importorskip("colour")
    sd = colour.SpectralDistribution(dict(zip(GRID_NM.tolist(), values.tolist(), strict=True)))
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # colour-science aligns the shapes, saying so
        xyz = colour.sd_to_XYZ(sd, cmfs, colour.SDS_ILLUMINANTS["D65"]) / 100.0
    return colour.XYZ_to_RGB(xyz, colour.RGB_COLOURSPACES["sRGB"], apply_cctf_encoding=False)


@pytest.mark.parametrize("eumelanin, pheomelanin", ((1.0, 0.0), (0.0, 1.0), (1.3, 0.0), (0.4, 2.0), (8.0, 0.5)))
def test_melanin_absorption_is_the_papers(eumelanin, pheomelanin):
    """σa's colour (its linear sRGB as a reflectance under D65, as the uplift defines colour) is the paper's
    eumelanin · (0.419, 0.697, 1.37) + pheomelanin · (0.187, 0.4, 1.05), to the uplift's fit."""
    expected = eumelanin * np.array(EUMELANIN_RGB) + pheomelanin * np.array(PHEOMELANIN_RGB)
    rgb = _srgb_under_d65(melanin_sigma_a(eumelanin, pheomelanin).values)
    np.testing.assert_allclose(rgb, expected, rtol=0.01, atol=2e-3 * expected.max())


@pytest.mark.parametrize(
    "sigma_a, beta_m, beta_n, alpha",
    ((0.0, 0.3, 0.3, 2.0), (0.4, 0.3, 0.3, 2.0), (1.5, 0.15, 0.6, -4.0), (0.1, 0.8, 0.2, 0.0)),
)
def test_scattering_is_mitsubas_hair(hair, sigma_a, beta_m, beta_n, alpha):
    """S(ωo, ωi) equals Mitsuba 3's `hair` BSDF (an implementation of the same paper, written apart from pbrt's) at
    the same directions. Mitsuba frames the fibre along local y and takes h from ωo and the normal, h = −X / |(X, Z)|
    (a cylinder's entry point); here the fibre is x, so Mitsuba's (X, Y, Z) is (y, x, z) and h is given that value.
    ωo above the surface only: behind it Mitsuba's γo is the geometric angle beyond ±π/2, which no point of a
    cylinder seen from ωo has. Directions: half uniform, half drawn from the BSDF (where S is large)."""
    mi = pytest.importorskip("mitsuba", reason="the comparison with Mitsuba 3's hair needs mitsuba")
    if "scalar_spectral" not in mi.variants():
        pytest.skip("this mitsuba build has no scalar_spectral variant")
    mi.set_variant("scalar_spectral")
    theirs_bsdf = mi.load_dict(
        {
            "type": "hair",
            "sigma_a": {"type": "spectrum", "value": sigma_a},
            "int_ior": 1.55,
            "ext_ior": 1.0,
            "longitudinal_roughness": beta_m,
            "azimuthal_roughness": beta_n,
            "scale_tilt": alpha,
        }
    )
    device = hair(HairMaterial(Spectrum.constant(sigma_a), beta_m=beta_m, beta_n=beta_n, alpha=alpha))
    rng = np.random.default_rng(11)
    wo = _uniform_sphere(rng, 200)
    wo[:, 2] = np.abs(wo[:, 2])
    h = -wo[:, 1] / np.hypot(wo[:, 1], wo[:, 2])
    sampled, ok, _, _ = device.sample(wo[:100], h[:100], 100, seed=12)
    assert ok.all()
    wi = np.concatenate([sampled, _uniform_sphere(rng, 100)])
    ours, _ = device.eval_pdf(wo, wi, h)
    theirs = np.zeros(len(wo))
    context = mi.BSDFContext()
    for i, (a, b) in enumerate(zip(wo, wi, strict=True)):
        interaction = mi.SurfaceInteraction3f()
        interaction.wi = mi.Vector3f(a[1], a[0], a[2])
        theirs[i] = np.array(theirs_bsdf.eval(context, interaction, mi.Vector3f(b[1], b[0], b[2])))[0]
    # σa is constant, so every wavelength is the same. Mitsuba's Mp keeps pbrt's truncations (I0's series cut at ten
    # terms, log I0's 1/(8x) halved): up to 0.5 % low where the lobe is narrow, the share by which this side's lobes
    # integrate closer to 1 (test_sampler_matches_its_pdf_chi_square's quadrature).
    assert ours[:, 0].max() > 0.1
    np.testing.assert_allclose(ours[:, 0], theirs, rtol=6e-3, atol=2e-4 * theirs.max())


SCENE = """
[camera]
origin = [0, 0, 5]
target = [0, 0, 0]
fov = 30

[materials.fibre]
type = "hair"
{keys}

[[shapes]]
type = "rectangle"
material = "fibre"
"""


@pytest.mark.parametrize(
    "keys, named",
    (
        ("sigma_a = { value = 0.5 }\nreflectance = { rgb = [0.3, 0.2, 0.1] }", "sigma_a and reflectance"),
        ("eumelanin = 1.0\nreflectance = { value = 0.4 }", "reflectance and eumelanin/pheomelanin"),
        ("pheomelanin = 1.0\nsigma_a = { value = 0.4 }", "sigma_a and eumelanin/pheomelanin"),
        ("beta_m = 0.0", "beta_m"),
        ("eta = 1.0", "eta"),
    ),
)
def test_scene_file_refuses_conflicting_or_bad_keys_in_one_line(tmp_path, keys, named):
    from spectrace import load_scene
    from spectrace.errors import SpectraceError

    path = tmp_path / "scene.toml"
    path.write_text(SCENE.format(keys=keys))
    with pytest.raises(SpectraceError) as caught:
        load_scene(path)
    message = str(caught.value)
    assert "scene.toml" in message and "materials.fibre" in message and named in message and "\n" not in message


def test_the_three_ways_of_giving_the_absorption():
    """Melanin (default eumelanin 1.3), σa and the paper's inversion of a colour: c = 1 absorbs nothing; darker
    colours absorb more; a wider azimuthal lobe needs less absorption for the same colour (the inversion's
    denominator grows with βn over (0, 1))."""
    import spectrace

    np.testing.assert_allclose(spectrace.hair().sigma_a.values, melanin_sigma_a(1.3, 0.0).values)
    assert np.all(spectrace.hair(reflectance=1.0).sigma_a.values == 0.0)
    light, dark = spectrace.hair(reflectance=0.6).sigma_a.values, spectrace.hair(reflectance=0.2).sigma_a.values
    assert np.all(dark > light)
    # (ln 0.2 / (5.969 − 0.215·0.3 + 2.532·0.09 − 10.73·0.027 + 5.574·0.0081 + 0.245·0.00243))² = (1.6094 / 5.8884)²
    np.testing.assert_allclose(dark, 0.07471, rtol=1e-3)
    np.testing.assert_allclose(spectrace.hair(sigma_a=(0.2, 0.2, 0.2)).sigma_a.values, 0.2, rtol=1e-3)
