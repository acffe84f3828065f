"""CIE 1931 colorimetry on the spectral grid: the renderer's XYZ convention and XYZ <-> sRGB.

The renderer's XYZ: a radiance spectrum L(lambda) gives film
    XYZ = integral L(lambda) (xbar, ybar, zbar)(lambda) dlambda / CIE_Y_INTEGRAL,
integrals being the trapezoid rule on the 1 nm grid. A constant spectrum 1 therefore has Y = 1,
so film Y is "radiance relative to an equal-energy spectrum of unit value", with no 683 lm/W.

XYZ <-> linear sRGB uses the matrices of the radiometry lecture this project comes from (INF2604);
they are the sRGB/D65 matrices of IEC 61966-2-1 at 6 decimals, as also printed in pbrt-v3's
`XYZToRGB`/`RGBToXYZ` (github.com/mmp/pbrt-v3, src/core/spectrum.h). A test checks them against
colour-science's sRGB colourspace.
"""

from functools import cache

import numpy as np

from spectrace.resources import spectra_dir
from spectrace.spectral.grid import GRID_MAX_NM, GRID_MIN_NM, GRID_STEP_NM, TRAPEZOID_WEIGHTS_NM, integrate_on_grid
from spectrace.spectral.spectrum import Spectrum


def _read_only(rows: list[list[float]]) -> np.ndarray:
    array = np.array(rows, dtype=np.float64)
    array.setflags(write=False)
    return array


XYZ_TO_LINEAR_SRGB = _read_only(
    [[3.240479, -1.537150, -0.498535], [-0.969256, 1.875991, 0.041556], [0.055648, -0.204043, 1.057311]]
)
LINEAR_SRGB_TO_XYZ = _read_only(
    [[0.412453, 0.357580, 0.180423], [0.212671, 0.715160, 0.072169], [0.019334, 0.119193, 0.950227]]
)

CIE_1931_OBSERVER = "CIE 1931 2 Degree Standard Observer"


CMF_TABLE = "observers/cie1931_2deg.csv"  # under spectra/


def _cie_1931_cmfs_on_grid() -> np.ndarray:
    """CIE 1931 2 degree colour matching functions on the grid, from the table shipped in spectra/.

    The table is colour-science's (`colour.MSDS_CMFS`, from CVRL's "Older CIE Standards" tables, cvrl.org), at
    1 nm over 360..830 nm, exactly our grid, written out once so that a render does not import colour-science
    (about a second); tests/cli/test_startup.py checks it equals colour-science's.
    """
    lines = [
        line
        for line in (spectra_dir() / CMF_TABLE).read_text(encoding="utf-8").splitlines()
        if line.strip() and not line.startswith("#")
    ]
    table = np.array([[float(field) for field in line.split(",")] for line in lines[1:]], dtype=np.float64)
    if table.shape != (GRID_MAX_NM - GRID_MIN_NM + 1, 4) or not np.array_equal(
        table[:, 0], np.arange(GRID_MIN_NM, GRID_MAX_NM + GRID_STEP_NM, GRID_STEP_NM)
    ):
        raise RuntimeError(f"{CMF_TABLE} is not on the {GRID_MIN_NM}..{GRID_MAX_NM} nm, 1 nm grid")
    values = np.ascontiguousarray(table[:, 1:])
    values.setflags(write=False)
    return values


CIE_1931_CMFS = _cie_1931_cmfs_on_grid()  # (471, 3): xbar, ybar, zbar
CIE_Y_INTEGRAL = float(integrate_on_grid(CIE_1931_CMFS[:, 1]))  # nm; about 106.857

# spectrum_to_xyz is then one matrix product: values @ _XYZ_WEIGHTS.
_XYZ_WEIGHTS = CIE_1931_CMFS * TRAPEZOID_WEIGHTS_NM[:, None] / CIE_Y_INTEGRAL


def _grid_values(spectrum: Spectrum | np.ndarray) -> np.ndarray:
    return spectrum.values if isinstance(spectrum, Spectrum) else np.asarray(spectrum, dtype=np.float64)


def spectrum_to_xyz(values_on_grid: Spectrum | np.ndarray) -> np.ndarray:
    """Film XYZ of a radiance spectrum (471 grid samples, or an array of them on the last axis).

    XYZ = trapezoid integral of L * (xbar, ybar, zbar) / CIE_Y_INTEGRAL; a constant 1 gives Y = 1.
    """
    return _grid_values(values_on_grid) @ _XYZ_WEIGHTS


def reflectance_to_xyz(reflectance: Spectrum | np.ndarray, illuminant: Spectrum | np.ndarray) -> np.ndarray:
    """XYZ of a reflectance seen under an illuminant, normalised so a perfect white reflector has Y = 1.

    XYZ = integral R E cmf / integral E ybar: the film XYZ of R*E divided by the film Y of E.
    """
    illuminant_values = _grid_values(illuminant)
    return spectrum_to_xyz(_grid_values(reflectance) * illuminant_values) / spectrum_to_xyz(illuminant_values)[1]


def cmf_table_normalised() -> np.ndarray:
    """(471, 3) float32: the CMFs divided by CIE_Y_INTEGRAL, the table the kernels weight samples with."""
    return (CIE_1931_CMFS / CIE_Y_INTEGRAL).astype(np.float32)


def normalised_to_unit_y(spectrum: Spectrum, name: str | None = None) -> Spectrum:
    """The spectrum scaled so that its film Y is 1 (its shape, i.e. chromaticity, is kept)."""
    luminance = spectrum_to_xyz(spectrum)[1]
    if not luminance > 0:
        raise ValueError(f"spectrum '{spectrum.name}' has film Y = {luminance:g}; cannot normalise it to Y = 1")
    return spectrum.scaled(1.0 / luminance, name=spectrum.name if name is None else name)


def xyz_to_xy(xyz: np.ndarray) -> np.ndarray:
    """CIE 1931 chromaticity (x, y) = (X, Y) / (X + Y + Z)."""
    xyz = np.asarray(xyz, dtype=np.float64)
    return xyz[..., :2] / xyz.sum(axis=-1, keepdims=True)


def xyz_to_linear_srgb(xyz: np.ndarray) -> np.ndarray:
    """Linear sRGB (D65 white, no clipping) of XYZ values on the last axis, with the lecture's matrix."""
    return np.asarray(xyz, dtype=np.float64) @ XYZ_TO_LINEAR_SRGB.T


def linear_srgb_to_xyz(linear_rgb: np.ndarray) -> np.ndarray:
    """XYZ of linear sRGB values on the last axis, with the lecture's matrix."""
    return np.asarray(linear_rgb, dtype=np.float64) @ LINEAR_SRGB_TO_XYZ.T


# IEC 61966-2-1:1999 sRGB transfer function constants.
_SRGB_LINEAR_LIMIT = 0.0031308  # linear value where the curve switches from the slope to the power law
_SRGB_ENCODED_LIMIT = 0.04045  # the same point after encoding
_SRGB_SLOPE = 12.92
_SRGB_GAMMA = 2.4
_SRGB_OFFSET = 0.055


def srgb_encode(linear: np.ndarray) -> np.ndarray:
    """sRGB transfer curve (IEC 61966-2-1), linear -> encoded; not clipped (negatives use the linear
    segment, values above 1 continue the power law) so that clipping stays the display's choice."""
    linear = np.asarray(linear, dtype=np.float64)
    power = (1 + _SRGB_OFFSET) * np.power(np.maximum(linear, _SRGB_LINEAR_LIMIT), 1 / _SRGB_GAMMA) - _SRGB_OFFSET
    return np.where(linear <= _SRGB_LINEAR_LIMIT, _SRGB_SLOPE * linear, power)


def srgb_decode(encoded: np.ndarray, bits: int | None = None) -> np.ndarray:
    """Inverse of `srgb_encode`: encoded sRGB -> linear (float64).

    With `bits` (8 or 16), `encoded` holds integer codes 0 .. 2^bits - 1 (an 8- or 16-bit image), decoded as
    code / (2^bits - 1) through a lookup table of every code, so an image costs one gather.
    """
    if bits is None:
        return _srgb_decode_float(encoded)
    codes = np.asarray(encoded)
    if bits not in _CODE_BITS:
        raise ValueError(f"sRGB integer codes must have 8 or 16 bits, not {bits!r}")
    if codes.dtype.kind not in "ui":
        raise ValueError(f"{bits}-bit sRGB codes must be integers, got {codes.dtype}")
    if codes.size and (int(codes.min()) < 0 or int(codes.max()) >= 1 << bits):
        raise ValueError(f"{bits}-bit sRGB codes must lie in 0..{(1 << bits) - 1}")
    return _srgb_code_table(bits)[codes]


_CODE_BITS = (8, 16)


def _srgb_decode_float(encoded: np.ndarray) -> np.ndarray:
    encoded = np.asarray(encoded, dtype=np.float64)
    base = (np.maximum(encoded, _SRGB_ENCODED_LIMIT) + _SRGB_OFFSET) / (1 + _SRGB_OFFSET)
    return np.where(encoded <= _SRGB_ENCODED_LIMIT, encoded / _SRGB_SLOPE, np.power(base, _SRGB_GAMMA))


@cache
def _srgb_code_table(bits: int) -> np.ndarray:
    table = _srgb_decode_float(np.arange(1 << bits) / ((1 << bits) - 1))
    table.setflags(write=False)
    return table
