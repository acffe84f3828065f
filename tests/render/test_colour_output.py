"""Output colour spaces and white balance against published matrices, the standards' primaries and curves, and
colour-science's independent colorimetry."""

import colour
import numpy as np
import pytest

from cli_runner import render_cornell_box, run_here, run_spectrace
from spectrace.errors import SpectraceError
from spectrace.film.colour_output import (
    Adaptation,
    ColourSpace,
    adaptation_matrix,
    encode_for_display,
    parse_white_balance,
    xyz_to_output,
    xyz_to_rgb_matrix,
)
from spectrace.film.image import Image
from spectrace.io.exr import read_exr
from spectrace.spectral.colorimetry import XYZ_TO_LINEAR_SRGB

pytestmark = pytest.mark.filterwarnings("ignore:Aligning")

# Bruce Lindbloom, "Chromatic Adaptation" (brucelindbloom.com, Eqn_ChromAdapt), D65 -> D50 with his reference
# whites D65 = (0.95047, 1, 1.08883) and D50 = (0.96422, 1, 0.82521), to 7 decimals.
LINDBLOOM_D65 = np.array([0.95047, 1.0, 1.08883])
LINDBLOOM_D50 = np.array([0.96422, 1.0, 0.82521])
LINDBLOOM_BRADFORD_D65_TO_D50 = np.array(
    [[1.0478112, 0.0228866, -0.0501270], [0.0295424, 0.9904844, -0.0170491], [-0.0092345, 0.0150436, 0.7521316]]
)
LINDBLOOM_VON_KRIES_D65_TO_D50 = np.array(
    [[1.0160803, 0.0552297, -0.0521326], [0.0060666, 0.9955661, -0.0012235], [0.0, 0.0, 0.7578869]]
)

# Primaries and white (CIE 1931 xy) as the standards publish them: SMPTE EG 432-1 (Display P3: the DCI-P3
# primaries with D65) and ITU-R BT.2020 Table 3.
PUBLISHED_PRIMARIES = {
    ColourSpace.DISPLAY_P3: [(0.680, 0.320), (0.265, 0.690), (0.150, 0.060)],
    ColourSpace.REC2020: [(0.708, 0.292), (0.170, 0.797), (0.131, 0.046)],
    ColourSpace.SRGB: [(0.640, 0.330), (0.300, 0.600), (0.150, 0.060)],
}
D65_XY = (0.3127, 0.3290)


def xy_to_xyz(xy) -> np.ndarray:
    x, y = xy
    return np.array([x / y, 1.0, (1.0 - x - y) / y])


@pytest.mark.parametrize(
    "method, published",
    [(Adaptation.BRADFORD, LINDBLOOM_BRADFORD_D65_TO_D50), (Adaptation.VON_KRIES, LINDBLOOM_VON_KRIES_D65_TO_D50)],
)
def test_adaptation_matrices_match_published_ones(method, published):
    np.testing.assert_allclose(adaptation_matrix(LINDBLOOM_D65, LINDBLOOM_D50, method), published, atol=6e-8)


@pytest.mark.parametrize("space", list(PUBLISHED_PRIMARIES))
def test_output_matrices_map_the_published_primaries_and_white(space):
    matrix = xyz_to_rgb_matrix(space)
    for channel, xy in enumerate(PUBLISHED_PRIMARIES[space]):
        rgb = matrix @ xy_to_xyz(xy)
        others = np.delete(rgb, channel)
        assert rgb[channel] > 0 and np.all(np.abs(others) < 2e-4 * rgb[channel]), rgb
    white = matrix @ xy_to_xyz(D65_XY)
    np.testing.assert_allclose(white / white.mean(), 1.0, atol=3e-4)


def test_default_output_is_the_lecture_srgb_unchanged():
    xyz = np.random.default_rng(1).random((3, 4, 3)).astype(np.float32)
    image = Image(xyz=xyz, spp=1, seed=0, device="test", render_seconds=0.0, exposure=1.5)
    expected = (xyz.astype(np.float64) @ XYZ_TO_LINEAR_SRGB.T * 2**1.5).astype(np.float32)
    assert np.array_equal(image.to_linear_srgb(), expected)
    assert np.array_equal(image.to_rgb(), expected)


def _white_diffuser_xyz(illuminant: colour.SpectralDistribution) -> np.ndarray:
    """colour-science's XYZ (Y = 1) of a perfect white diffuser under `illuminant`: its own integration."""
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
    xyz = colour.sd_to_XYZ(illuminant, cmfs, method="Integration")
    return xyz / xyz[1]


@pytest.mark.parametrize(
    "white, illuminant",
    [
        ("A", colour.SDS_ILLUMINANTS["A"]),
        ("FL2", colour.SDS_ILLUMINANTS["FL2"]),
        ("3200K", colour.sd_blackbody(3200, colour.SpectralShape(360, 830, 1))),
    ],
)
@pytest.mark.parametrize("space", [ColourSpace.SRGB, ColourSpace.DISPLAY_P3, ColourSpace.REC2020])
@pytest.mark.parametrize("method", list(Adaptation))
def test_white_balance_makes_the_illuminant_neutral(white, illuminant, space, method):
    rgb = xyz_to_output(_white_diffuser_xyz(illuminant), space, parse_white_balance(white, method))
    # Tolerance: colour-science integrates its own tabulations (5 nm, its own interpolation), we the 1 nm grid.
    np.testing.assert_allclose(rgb / rgb.mean(), 1.0, atol=2e-3)
    unbalanced = xyz_to_output(_white_diffuser_xyz(illuminant), space)
    assert np.ptp(unbalanced / unbalanced.mean()) > 0.05  # without it these whites are visibly tinted


def test_white_balance_accepts_a_chromaticity():
    balance = parse_white_balance("0.44757, 0.40745")  # CIE illuminant A's published xy (CIE 15:2004)
    rgb = xyz_to_output(xy_to_xyz((0.44757, 0.40745)), ColourSpace.SRGB, balance)
    np.testing.assert_allclose(rgb / rgb.mean(), 1.0, atol=1e-6)


@pytest.mark.parametrize("text", ["Q7", "0.7,0.6", "20K"])
def test_bad_white_is_one_error_naming_the_option(text):
    with pytest.raises(SpectraceError) as error:
        parse_white_balance(text)
    assert error.value.where == "--white-balance"


def test_rec2020_curve_is_the_published_oetf():
    # ITU-R BT.2020 Table 4: E' = 4.5 E below beta, else alpha E^0.45 - (alpha - 1), with alpha = 1.099 and
    # beta = 0.018 for 10-bit (and fewer bits) systems, the same curve as BT.709.
    linear = np.array([0.0, 0.01, 0.018, 0.1, 0.5, 1.0])
    alpha, beta = 1.099, 0.018
    expected = np.where(linear < beta, 4.5 * linear, alpha * linear**0.45 - (alpha - 1.0))
    np.testing.assert_allclose(
        encode_for_display(linear[:, None].repeat(3, 1), ColourSpace.REC2020)[:, 0], expected, atol=1e-9
    )


def test_p3_files_say_what_they_hold(tmp_path):
    from PIL import Image as PILImage

    xyz = np.full((2, 3, 3), 0.2, np.float32)
    image = Image(xyz=xyz, spp=1, seed=0, device="test", render_seconds=0.0, colour_space=ColourSpace.DISPLAY_P3)
    image.write(tmp_path / "p3.png")
    image.write(tmp_path / "p3.exr")
    data = (tmp_path / "p3.png").read_bytes()
    # cICP chunk (PNG 3rd edition): primaries 12 = P3 D65, transfer 13 = sRGB curve (ITU-T H.273), before IDAT.
    assert b"cICP\x0c\x0d\x00\x01" in data and data.index(b"cICP") < data.index(b"IDAT")
    with PILImage.open(tmp_path / "p3.png") as png:
        assert png.text["spectrace:colour_space"] == "display-p3"
    channels, header = read_exr(tmp_path / "p3.exr")
    published = [v for xy in PUBLISHED_PRIMARIES[ColourSpace.DISPLAY_P3] for v in xy] + list(D65_XY)
    np.testing.assert_allclose(header["chromaticities"], published, atol=1e-7)
    np.testing.assert_allclose(channels["RGB"], xyz_to_output(xyz, ColourSpace.DISPLAY_P3), rtol=1e-6)
    np.testing.assert_array_equal(channels["Y"], xyz[..., 1])  # the film's XYZ stays physical


def test_xyz_output_keeps_the_film(tmp_path):
    xyz = np.random.default_rng(2).random((2, 2, 3)).astype(np.float32)
    image = Image(xyz=xyz, spp=1, seed=0, device="test", render_seconds=0.0, colour_space=ColourSpace.XYZ)
    image.write(tmp_path / "xyz.exr")
    channels, _ = read_exr(tmp_path / "xyz.exr")
    np.testing.assert_array_equal(channels["RGB"], xyz)
    with pytest.raises(SpectraceError):
        image.write(tmp_path / "xyz.png")


@pytest.mark.subprocess
@pytest.mark.slow
def test_render_command_colour_options(tmp_path):
    """The options' image through the command's entry point here; their refusal, an exit status, in a process."""
    out = tmp_path / "balanced.exr"
    args = [
        *render_cornell_box(out, 1, 8, 6),
        "-q",
        "--colour-space",
        "rec2020",
        "--white-balance",
        "cornell_box/light",
        "--adaptation",
        "von-kries",
    ]
    result = run_here(*args)
    assert result.returncode == 0, result.stderr
    channels, header = read_exr(out)
    assert header["spectrace:colour_space"] == "rec2020"
    assert header["spectrace:white_balance"] == "cornell_box/light (von-kries)"
    film = np.stack([channels["X"], channels["Y"], channels["Z"]], axis=-1)
    balance = parse_white_balance("cornell_box/light", "von-kries")
    np.testing.assert_allclose(channels["RGB"], xyz_to_output(film, ColourSpace.REC2020, balance), rtol=1e-5, atol=1e-7)
    bad = run_spectrace(*args[:-4], "--colour-space", "xyz", "-o", str(tmp_path / "x.png"))
    assert bad.returncode == 2 and "--colour-space" in bad.stderr and "Traceback" not in bad.stderr
