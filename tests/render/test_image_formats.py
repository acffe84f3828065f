"""The image formats people open (PNG 8/16-bit, JPEG, TIFF 8/16-bit, PFM), read back by readers other than the
writers: Pillow, Little CMS (through Pillow's ImageCms) for the embedded ICC profiles, and the PFM layout parsed
here from its specification; colours are compared with colour-science's conversions."""

import io

import numpy as np
import pytest
from PIL import Image as PILImage
from PIL import ImageCms

from cli_runner import render_cornell_box, run_here, run_spectrace
from spectrace.errors import SpectraceError
from spectrace.film.colour_output import ColourSpace
from spectrace.film.image import Image
from spectrace.io.png16 import read_png16

colour = pytest.importorskip("colour")

# Film XYZ of a few colours inside sRGB, Display P3 and Rec.2020 (a skin tone, a green, a grey, a blue).
_XYZ = np.array(
    [[[0.35, 0.30, 0.15], [0.20, 0.35, 0.15], [0.18, 0.19, 0.20], [0.15, 0.12, 0.45]]],
    np.float32,
)


def _image(space=ColourSpace.SRGB, xyz=_XYZ) -> Image:
    return Image(xyz=xyz.copy(), spp=1, seed=0, device="test", render_seconds=0.0, colour_space=space)


def _reference_srgb_8bit(xyz: np.ndarray) -> np.ndarray:
    linear = colour.XYZ_to_RGB(xyz, "sRGB", apply_cctf_encoding=False)
    return colour.cctf_encoding(np.clip(linear, 0.0, 1.0), "sRGB") * 255.0


@pytest.mark.parametrize("space", [ColourSpace.DISPLAY_P3, ColourSpace.REC2020])
@pytest.mark.parametrize("suffix", [".png", ".tif", ".jpg"])
def test_wide_gamut_files_embed_a_profile_that_little_cms_converts_like_colour_science(tmp_path, space, suffix):
    """A viewer reading the file's ICC profile shows the colours the film holds: the pixels converted to sRGB by
    Little CMS from the embedded profile match colour-science's XYZ → sRGB of the film within quantisation: half a
    level of the file's 8 bits is up to about a level of sRGB for P3 and two for Rec.2020 (its RGB → sRGB matrix's
    rows sum to 2.3 in absolute value), plus the half level of the result; JPEG's compression a few levels more."""
    path = tmp_path / f"image{suffix}"
    _image(space).write(path)
    with PILImage.open(path) as picture:
        profile_bytes = picture.info.get("icc_profile")
        assert profile_bytes, f"{suffix} in {space} carries no ICC profile"
        profile = ImageCms.ImageCmsProfile(io.BytesIO(profile_bytes))
        transform = ImageCms.buildTransform(
            profile, ImageCms.createProfile("sRGB"), "RGB", "RGB", ImageCms.Intent.RELATIVE_COLORIMETRIC
        )
        shown = np.asarray(ImageCms.applyTransform(picture.convert("RGB"), transform), float)
    tolerance = (1.5 if space is ColourSpace.DISPLAY_P3 else 2.6) + (4.0 if suffix == ".jpg" else 0.0)
    np.testing.assert_allclose(shown, _reference_srgb_8bit(_XYZ.astype(float)), atol=tolerance)


def test_the_profile_carries_the_spaces_primaries_for_little_cms():
    """The profile's red, green and blue, as Little CMS reads them (XYZ in the D50 connection space), are
    colour-science's primaries and white carried from D65 to D50 by Bradford's transform (ICC.1 Annex G)."""
    from spectrace.film.icc_profile import icc_profile

    d50 = colour.xy_to_XYZ(colour.CCS_ILLUMINANTS["CIE 1931 2 Degree Standard Observer"]["D50"])
    for space, name in ((ColourSpace.DISPLAY_P3, "Display P3"), (ColourSpace.REC2020, "ITU-R BT.2020")):
        profile = ImageCms.ImageCmsProfile(io.BytesIO(icc_profile(space))).profile
        assert profile.version >= 4.0 and profile.xcolor_space == "RGB " and profile.connection_space == "XYZ "
        read = np.array([p[0] for p in (profile.red_primary, profile.green_primary, profile.blue_primary)]).T
        model = colour.RGB_COLOURSPACES[name]
        white = colour.xy_to_XYZ(model.whitepoint)
        adapt = colour.adaptation.matrix_chromatic_adaptation_VonKries(white, d50, transform="Bradford")
        np.testing.assert_allclose(read, adapt @ model.matrix_RGB_to_XYZ, atol=2e-3)


@pytest.mark.parametrize("suffix", [".png", ".tif"])
def test_sixteen_bit_files_keep_sixteen_bits(tmp_path, suffix):
    """16-bit PNG read by the project's 16-bit decoder (Pillow's C unfilter on each byte plane) and Pillow's 8-bit
    view of both formats: samples round(v · 65535) of the sRGB-encoded film, which 8 bits cannot hold."""
    xyz = np.linspace(0.0, 0.9, 3 * 6 * 5).reshape(6, 5, 3).astype(np.float32)
    image = _image(xyz=xyz)
    path = tmp_path / f"deep{suffix}"
    image.write(path, bit_depth=16)
    linear = colour.XYZ_to_RGB(xyz.astype(float), "sRGB", apply_cctf_encoding=False)
    expected = np.rint(colour.cctf_encoding(np.clip(linear, 0, 1), "sRGB") * 65535)
    if suffix == ".png":
        samples = read_png16(path).astype(float)
        assert np.any(samples % 257 != 0)  # not 8-bit values widened
        # The film's XYZ → sRGB matrix (4 decimals) and colour-science's differ by up to 1e-4: 7 levels of 65535.
        np.testing.assert_allclose(samples, expected, atol=10.0)
    with PILImage.open(path) as picture:
        assert picture.size == (5, 6)
        np.testing.assert_allclose(np.asarray(picture.convert("RGB"), float), expected / 257.0, atol=1.0)


def test_pfm_holds_the_linear_film_unclipped(tmp_path):
    """PFM: "PF", width height, a negative scale (little-endian), float32 rows from the bottom up."""
    xyz = (_XYZ * 40.0).astype(np.float32)  # over-bright: a display format would clip it
    image = _image(xyz=xyz)
    image.write(tmp_path / "film.pfm")
    data = (tmp_path / "film.pfm").read_bytes()
    magic, size, scale, rest = data.split(b"\n", 3)
    assert magic == b"PF" and size.split() == [b"4", b"1"] and float(scale) < 0
    pixels = np.frombuffer(rest, "<f4").reshape(1, 4, 3)[::-1]
    reference = colour.XYZ_to_RGB(xyz.astype(float), "sRGB", apply_cctf_encoding=False)
    np.testing.assert_allclose(pixels, reference, rtol=2e-3, atol=1e-4)
    assert pixels.max() > 1.0


def test_jpeg_and_eight_bit_tiff_match_the_png(tmp_path):
    image = _image()
    for suffix in (".png", ".tif", ".jpg"):
        image.write(tmp_path / f"same{suffix}")
    with PILImage.open(tmp_path / "same.png") as png, PILImage.open(tmp_path / "same.tif") as tif:
        assert np.array_equal(np.asarray(png), np.asarray(tif))
        np.testing.assert_allclose(np.asarray(png), _reference_srgb_8bit(_XYZ.astype(float)), atol=1.0)
    with PILImage.open(tmp_path / "same.jpg") as jpg:
        assert jpg.format == "JPEG" and b"spectrace:spp" in jpg.info.get("comment", b"")


def test_refusals_name_the_file(tmp_path):
    image = _image()
    for path, depth in ((tmp_path / "a.bmp", 8), (tmp_path / "a.jpg", 16), (tmp_path / "a.png", 12)):
        with pytest.raises(SpectraceError) as error:
            image.write(path, bit_depth=depth)
        assert error.value.where == str(path)
        assert not path.exists()
    with pytest.raises(SpectraceError):
        _image(ColourSpace.XYZ).write(tmp_path / "xyz.tif")


@pytest.mark.subprocess
@pytest.mark.slow
def test_render_command_writes_each_format(tmp_path):
    """`spectrace render -o` with each suffix (through the entry point in this process), and --bit-depth refused for
    JPEG in one line before any work (a real process)."""
    outputs = {"film.tif": ("--bit-depth", "16"), "film.jpg": (), "film.pfm": ()}
    for name, extra in outputs.items():
        result = run_here(*render_cornell_box(tmp_path / name, 1, 8, 6), "-q", *extra)
        assert result.returncode == 0, result.stderr
        assert (tmp_path / name).stat().st_size > 0
    bad = run_spectrace(*render_cornell_box(tmp_path / "deep.jpg", 1, 8, 6), "--bit-depth", "16")
    assert bad.returncode == 2 and "--bit-depth" in bad.stderr and "Traceback" not in bad.stderr
    assert len(bad.stderr.strip().splitlines()) == 1 and not (tmp_path / "deep.jpg").exists()
