"""Output colour: the film's CIE 1931 XYZ in a chosen colour space, white-balanced by chromatic adaptation.

The film is XYZ (see `spectrace.spectral.colorimetry`); every RGB output is derived from it here, in this order:

1. white balance (optional): a chromatic adaptation transform (von Kries with the Hunt–Pointer–Estévez cone
   matrix, or Bradford) maps the chosen *scene white* (an illuminant, a black body, a chromaticity or a library
   spectrum) onto the output space's white, so a surface lit by that illuminant with a flat reflectance comes
   out neutral (R = G = B);
2. XYZ -> linear RGB of the output space: sRGB with the lecture's matrix (as `spectrace.spectral`), Display P3
   and ITU-R BT.2020 with the matrices colour-science derives from their published primaries and D65 white; `xyz`
   keeps XYZ;
3. exposure: x 2**stops;
4. for display files only (PNG, TIFF, JPEG), the space's transfer curve: IEC 61966-2-1 sRGB for sRGB and
   Display P3 (which uses the sRGB curve, SMPTE EG 432-1), the ITU-R BT.2020 (= BT.709) OETF for Rec.2020.

docs/colour.md documents the options for users.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import StrEnum
from functools import cache

import numpy as np

from spectrace.errors import SpectraceError
from spectrace.number_text import number_problem
from spectrace.spectral.colorimetry import XYZ_TO_LINEAR_SRGB, spectrum_to_xyz, srgb_encode


class ColourSpace(StrEnum):
    """Output colour spaces; the value is the command-line spelling."""

    SRGB = "srgb"
    DISPLAY_P3 = "display-p3"
    REC2020 = "rec2020"
    XYZ = "xyz"


class Adaptation(StrEnum):
    """Chromatic adaptation transforms for white balance; the value is the command-line spelling."""

    BRADFORD = "bradford"
    VON_KRIES = "von-kries"


# colour-science's names for the data behind each choice (its datasets carry their references).
_COLOURSPACE_DATASETS = {ColourSpace.DISPLAY_P3: "Display P3", ColourSpace.REC2020: "ITU-R BT.2020"}
_ADAPTATION_DATASETS = {Adaptation.BRADFORD: "Bradford", Adaptation.VON_KRIES: "Von Kries"}

# PNG cICP chunk (PNG 3rd edition, codes from ITU-T H.273): colour primaries, transfer characteristics,
# matrix coefficients (0 = RGB), full range. Viewers that read it show P3 and Rec.2020 files correctly; others
# assume sRGB.
_PNG_CICP = {
    ColourSpace.SRGB: (1, 13, 0, 1),
    ColourSpace.DISPLAY_P3: (12, 13, 0, 1),
    ColourSpace.REC2020: (9, 1, 0, 1),
}


@cache
def xyz_to_rgb_matrix(space: ColourSpace) -> np.ndarray:
    """3x3 matrix taking (film) XYZ to the linear RGB of `space` (the identity for XYZ)."""
    space = ColourSpace(space)
    if space is ColourSpace.XYZ:
        matrix = np.eye(3)
    elif space is ColourSpace.SRGB:
        matrix = np.array(XYZ_TO_LINEAR_SRGB)
    else:
        import colour  # here, not at module import: it takes about a second, and sRGB needs none of it

        matrix = np.array(colour.RGB_COLOURSPACES[_COLOURSPACE_DATASETS[space]].matrix_XYZ_to_RGB, dtype=np.float64)
    matrix.setflags(write=False)
    return matrix


def output_white_xyz(space: ColourSpace) -> np.ndarray:
    """XYZ (Y = 1) of the white that white balance adapts to: the space's RGB (1, 1, 1), i.e. its D65 as the
    space's own matrix defines it, so an adapted white is exactly neutral. XYZ output uses the sRGB white."""
    space = ColourSpace(space)
    matrix = xyz_to_rgb_matrix(ColourSpace.SRGB if space is ColourSpace.XYZ else space)
    white = np.linalg.solve(matrix, np.ones(3))
    return white / white[1]


@dataclass(frozen=True)
class WhiteBalance:
    """Adapt `scene_white_xyz` (the white the viewer should see as neutral) to the output white."""

    label: str  # what the user asked for, e.g. "A", "3200K", "0.4476,0.4074"
    scene_white_xyz: np.ndarray  # Y = 1
    method: Adaptation = Adaptation.BRADFORD

    def __post_init__(self) -> None:
        if problem := white_problem(self.scene_white_xyz, Adaptation(self.method)):
            raise SpectraceError(f"white '{self.label}' {problem}", where="white_balance")

    def matrix(self, space: ColourSpace) -> np.ndarray:
        """3x3 matrix acting on XYZ."""
        return adaptation_matrix(self.scene_white_xyz, output_white_xyz(space), self.method)

    def describe(self) -> str:
        return f"{self.label} ({self.method.value})"


def adaptation_matrix(
    source_white_xyz: np.ndarray, target_white_xyz: np.ndarray, method: Adaptation = Adaptation.BRADFORD
) -> np.ndarray:
    """Von Kries-type chromatic adaptation: M⁻¹ diag(LMS_target / LMS_source) M on XYZ, with the cone matrix M of
    `method` (Bradford: Lam 1985; von Kries: Hunt–Pointer–Estévez, normalised to D65), from colour-science."""
    import colour

    return colour.adaptation.matrix_chromatic_adaptation_VonKries(
        np.asarray(source_white_xyz, float),
        np.asarray(target_white_xyz, float),
        transform=_ADAPTATION_DATASETS[Adaptation(method)],
    )


@cache
def _spectral_locus_xy() -> np.ndarray:
    """(n, 2) CIE 1931 chromaticities of the monochromatic lights on the grid, in wavelength order: with the
    purple line from the last back to the first, the boundary of every colour a spectrum can have."""
    from spectrace.spectral.colorimetry import CIE_1931_CMFS

    sums = CIE_1931_CMFS.sum(axis=1)
    keep = sums > 1e-4 * sums.max()  # the tables' far ends, where the chromaticities are rounding
    return CIE_1931_CMFS[keep, :2] / sums[keep, None]


def _inside_polygon(point: np.ndarray, polygon: np.ndarray) -> bool:
    """Whether `point` lies inside the closed `polygon` (even-odd rule: crossings of a ray toward +x)."""
    x, y = point
    start, end = polygon, np.roll(polygon, -1, axis=0)
    straddles = (start[:, 1] > y) != (end[:, 1] > y)
    with np.errstate(divide="ignore", invalid="ignore"):
        crossing_x = start[:, 0] + (y - start[:, 1]) * (end[:, 0] - start[:, 0]) / (end[:, 1] - start[:, 1])
    return bool(np.count_nonzero(straddles & (crossing_x > x)) % 2)


def white_problem(xyz: np.ndarray, method: Adaptation = Adaptation.BRADFORD) -> str | None:
    """Why XYZ cannot be a white to adapt from, or None. Adaptation divides by the white's Y and by its cone responses
    (diag(LMS_target / LMS_source)): a Y that is zero or subnormal, a chromaticity outside the spectral locus (no
    light has it), or a cone response of `method` that is not positive (Bradford's sharpened cones go negative near
    the locus) would turn every pixel into huge, negative or NaN values."""
    import colour

    method = Adaptation(method)
    white = np.asarray(xyz, np.float64)
    if white.shape != (3,) or not np.all(np.isfinite(white)):
        return f"must be three finite numbers X, Y, Z, got {white}"
    if not white[1] >= np.finfo(np.float64).tiny:
        return f"has no luminance (Y = {white[1]:g}): it cannot be scaled to Y = 1"
    with np.errstate(over="ignore"):
        normalised = white / white[1]
    total = float(normalised.sum())
    if not np.all(np.isfinite(normalised)) or not total > 0:
        return f"has X, Y, Z ({white[0]:g}, {white[1]:g}, {white[2]:g}) of no chromaticity"
    chromaticity = normalised[:2] / total
    if not _inside_polygon(chromaticity, _spectral_locus_xy()):
        return (
            f"has chromaticity x, y = {chromaticity[0]:.4g}, {chromaticity[1]:.4g}, outside the spectral locus: "
            "no light has that colour"
        )
    cones = colour.CHROMATIC_ADAPTATION_TRANSFORMS[_ADAPTATION_DATASETS[method]] @ normalised
    if not np.all(cones > 1e-6 * np.abs(cones).max()):
        return (
            f"is too saturated for {method.value} adaptation (its cone responses {', '.join(f'{c:.3g}' for c in cones)}"
            " must be positive): pick a less saturated white or another --adaptation"
        )
    return None


def _chromaticity_white(text: str, where: str | None) -> np.ndarray | None:
    parts = text.replace(" ", "").split(",")
    if len(parts) != 2:
        return None
    if any(number_problem(part) for part in parts):
        return None
    x, y = (float(part) for part in parts)
    # Normal floats only: x / y of a subnormal y overflows, a subnormal x is a typo for 0.
    tiny = np.finfo(np.float64).tiny
    if not (tiny <= x < 1.0 and tiny <= y < 1.0 and x + y < 1.0):
        raise SpectraceError(
            f"chromaticity x, y = {x:g}, {y:g} is not a colour (need x, y > 0, x + y < 1)", where=where
        )
    return np.array([x / y, 1.0, (1.0 - x - y) / y])


def _blackbody_white(text: str, where: str | None) -> np.ndarray | None:
    if not text.lower().endswith("k"):
        return None
    if number_problem(text[:-1]):
        return None
    temperature_k = float(text[:-1])
    if not 500.0 <= temperature_k <= 100000.0:
        raise SpectraceError(f"black-body temperature must lie in 500..100000 K, got {temperature_k:g} K", where=where)
    from spectrace.spectral.blackbody import blackbody

    return spectrum_to_xyz(blackbody(temperature_k))


def _spectrum_white(text: str, where: str | None) -> np.ndarray:
    from spectrace.spectral.illuminants import cie_illuminant_names
    from spectrace.spectral.spectrum_io import library_spectrum

    name = text if (":" in text or "/" in text) else f"cie:{text}"
    try:
        spectrum = library_spectrum(name)
    except SpectraceError:
        raise SpectraceError(
            f"unknown white '{text}': give a CIE illuminant ({', '.join(cie_illuminant_names()[:6])}, ...), a "
            "temperature such as 3200K, a chromaticity 'x,y', or a library spectrum (`spectrace spectra list`)",
            where=where,
        ) from None
    return spectrum_to_xyz(spectrum)


def parse_white_balance(
    text: str,
    method: Adaptation | str = Adaptation.BRADFORD,
    *,
    where: str | None = "--white-balance",
    method_where: str | None = "--adaptation",
) -> WhiteBalance:
    """The white named by `text`: a CIE illuminant ("A", "D50", "FL2", "cie:A"), a black body ("3200K"), a
    CIE 1931 chromaticity ("0.4476,0.4074") or a library spectrum ("cornell_box/light"). Spectra are integrated
    with the renderer's CMFs, so an illuminant's own white maps to exactly neutral. An error names `where` (the
    white) or `method_where` (the method), the command line's options unless told."""
    text = text.strip()
    try:
        method = Adaptation(method)
    except ValueError:
        raise SpectraceError(
            f"unknown adaptation '{method}' (use {', '.join(a.value for a in Adaptation)})", where=method_where
        ) from None
    white = _chromaticity_white(text, where)
    if white is None:
        white = _blackbody_white(text, where)
    if white is None:
        white = _spectrum_white(text, where)
    if problem := white_problem(white, method):
        raise SpectraceError(f"white '{text}' {problem}", where=where)
    return WhiteBalance(label=text, scene_white_xyz=white / white[1], method=method)


def parse_colour_space(text: str, where: str | None = "--colour-space") -> ColourSpace:
    try:
        return ColourSpace(text.strip().lower())
    except ValueError:
        raise SpectraceError(
            f"unknown colour space '{text}' (use {', '.join(s.value for s in ColourSpace)})", where=where
        ) from None


def xyz_to_output(
    xyz: np.ndarray,
    space: ColourSpace = ColourSpace.SRGB,
    white_balance: WhiteBalance | None = None,
    exposure_stops: float = 0.0,
) -> np.ndarray:
    """Linear values of `space` (XYZ on the last axis in, float32 out): white balance, matrix, 2**exposure."""
    space = ColourSpace(space)
    matrix = xyz_to_rgb_matrix(space)
    if white_balance is not None:
        matrix = matrix @ white_balance.matrix(space)
    return (np.asarray(xyz, np.float64) @ matrix.T * 2.0**exposure_stops).astype(np.float32)


def encode_for_display(linear_rgb: np.ndarray, space: ColourSpace) -> np.ndarray:
    """Clip to [0, 1] and apply the space's transfer curve, for 8-bit files and screens."""
    space = ColourSpace(space)
    if space is ColourSpace.XYZ:
        raise SpectraceError("xyz has no display encoding: write it as .exr")
    clipped = np.clip(np.asarray(linear_rgb, np.float64), 0.0, 1.0)
    if space is ColourSpace.REC2020:
        import colour

        return np.asarray(colour.models.oetf_BT2020(clipped), np.float64)
    return srgb_encode(clipped)


def png_cicp(space: ColourSpace) -> bytes:
    """The 4-byte payload of a PNG cICP chunk naming `space`'s primaries and transfer curve."""
    space = ColourSpace(space)
    if space not in _PNG_CICP:
        raise SpectraceError(f"{space.value} has no display encoding: write it as .exr")
    return bytes(_PNG_CICP[space])


def exr_chromaticities(space: ColourSpace) -> tuple[float, ...]:
    """OpenEXR `chromaticities` (red, green, blue, white xy) of the RGB channels' space; for XYZ output the
    CIE XYZ primaries (1, 0), (0, 1), (0, 0) with the equal-energy white, as OpenEXR's documentation suggests."""
    space = ColourSpace(space)
    if space is ColourSpace.XYZ:
        return (1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0 / 3.0, 1.0 / 3.0)
    import colour

    dataset = colour.RGB_COLOURSPACES["sRGB" if space is ColourSpace.SRGB else _COLOURSPACE_DATASETS[space]]
    return tuple(float(v) for v in (*np.ravel(dataset.primaries), *dataset.whitepoint))
