"""The viewing conditions every display comparison shares: a common luminance scale and one reference white.

Reference white: CIE D65 at `white_luminance_cd_m2` (100 cd/m² by default), the same for every display and
every observer (its XYZ under each observer is computed from the D65 spectrum). One white for all displays means
CIELAB describes what one viewer, adapted to one white, sees on either screen: two emissions with equal XYZ have
ΔE 0, so `compare` and `match` agree. (Each display's own white would instead hide white-point differences,
which are part of what the experiment shows, and make an exact XYZ match differ in CIELAB.)

Luminance scale: by default every display is rescaled so that its white (1, 1, 1) has the same luminance as the
reference white, since the measured peak luminance is the brightness setting during the measurement, not a
property of the primaries. With `keep_measured_radiance`, displays with absolute data keep their measured
radiance (L* may then exceed 100); relative displays are still set to the reference luminance.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache

import colour
import numpy as np

from spectrace.errors import SpectraceError
from spectrace.spectral import cie_illuminant, srgb_encode, xyz_to_linear_srgb
from spectrace.spectral.display import Display
from spectrace.spectral.observers import Observer, luminance_cd_m2, photometric_xyz

DEFAULT_WHITE_LUMINANCE_CD_M2 = 100.0
# From about the absolute threshold of vision to beyond the Sun's disc (1.6e9 cd/m²): outside, no display exists,
# and far outside the spectra under- or overflow and every figure becomes NaN.
WHITE_LUMINANCE_RANGE_CD_M2 = (1e-6, 1e10)
REFERENCE_WHITE_NAME = "CIE D65"


@cache
def _d65_at_luminance(white_luminance_cd_m2: float) -> np.ndarray:
    d65 = cie_illuminant("D65").values
    values = d65 * (white_luminance_cd_m2 / luminance_cd_m2(d65))
    values.setflags(write=False)
    return values


@dataclass(frozen=True)
class ViewingConditions:
    white_luminance_cd_m2: float = DEFAULT_WHITE_LUMINANCE_CD_M2
    keep_measured_radiance: bool = False

    def __post_init__(self) -> None:
        low, high = WHITE_LUMINANCE_RANGE_CD_M2
        if not (np.isfinite(self.white_luminance_cd_m2) and self.white_luminance_cd_m2 > 0):
            raise SpectraceError(
                f"white luminance must be a positive number of cd/m², got {self.white_luminance_cd_m2:g}",
                where="--white-luminance",
            )
        if not low <= self.white_luminance_cd_m2 <= high:
            raise SpectraceError(
                f"white luminance must lie in {low:g}..{high:g} cd/m² (from the threshold of vision "
                f"to beyond the Sun's disc), got {self.white_luminance_cd_m2:g}",
                where="--white-luminance",
            )

    def as_viewed(self, display: Display) -> Display:
        """The display on this comparison's luminance scale (see the module docstring)."""
        if self.keep_measured_radiance and display.absolute:
            return display
        return display.scaled_to_white_luminance(self.white_luminance_cd_m2)

    def reference_white_radiance(self) -> np.ndarray:
        """Grid samples of D65 scaled to the reference luminance, in W/(sr m^2 nm)."""
        return _d65_at_luminance(float(self.white_luminance_cd_m2))

    def reference_white_xyz(self, observer: Observer) -> np.ndarray:
        return photometric_xyz(self.reference_white_radiance(), observer)

    def lab(self, xyz: np.ndarray, observer: Observer) -> np.ndarray:
        """CIELAB of photometric XYZ (same observer) relative to the reference white."""
        white = self.reference_white_xyz(observer)
        return colour.XYZ_to_Lab(np.asarray(xyz) / white[1], colour.XYZ_to_xy(white))

    def linear_srgb(self, xyz_cie1931: np.ndarray) -> np.ndarray:
        """Linear sRGB (unclipped) of CIE 1931 photometric XYZ, sRGB white (1, 1, 1) = the reference white."""
        return xyz_to_linear_srgb(np.asarray(xyz_cie1931) / self.white_luminance_cd_m2)

    def to_json(self) -> dict:
        return {
            "reference_white": REFERENCE_WHITE_NAME,
            "white_luminance_cd_m2": self.white_luminance_cd_m2,
            "keep_measured_radiance": self.keep_measured_radiance,
        }


def delta_e_2000(lab_a: np.ndarray, lab_b: np.ndarray) -> float | np.ndarray:
    """CIEDE2000 colour difference (Sharma, Wu & Dalal 2005), via colour-science."""
    return colour.delta_E(lab_a, lab_b, method="CIE 2000")


def encoded_srgb_for_screen(linear_srgb: np.ndarray) -> np.ndarray:
    """sRGB-encoded values clipped to [0, 1], for showing a patch on an sRGB screen."""
    return srgb_encode(np.clip(linear_srgb, 0.0, 1.0))
