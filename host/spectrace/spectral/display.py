"""`Display`: three primaries' emission spectra and how an RGB triple mixes them.

A display is additive: driving the channels with linear drive d = (d_r, d_g, d_b) in [0, 1] emits
    L(lambda) = d_r P_r(lambda) + d_g P_g(lambda) + d_b P_b(lambda),
P_c being channel c's spectral radiance at full drive with the other channels off (the measured data). So
every colorimetric quantity of the emission is a 3x3 matrix times d. Black-level emission and channel
interaction, which real panels have a little of, are not modelled: the shipped data do not measure them.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from spectrace.errors import SpectraceError
from spectrace.spectral import Spectrum, spectrum_to_xyz, xyz_to_xy
from spectrace.spectral.display_polarization import Polarization
from spectrace.spectral.display_transfer import Encoding, checked_rgb, decode_to_drive
from spectrace.spectral.observers import Observer, luminance_cd_m2, photometric_xyz

CHANNELS = ("red", "green", "blue")


@dataclass(frozen=True)
class Display:
    """An RGB display described by its primaries.

    primaries: spectral radiance of red, green, blue at full drive, on the project grid; in W/(sr m^2 nm) when
        `absolute`, else on an arbitrary relative scale.
    absolute: whether the primaries carry a radiance scale (measured, or set by `scaled_to_white_luminance`).
    radiance_scale: how that scale came about, for reports ("measured", "relative", "white set to 100 cd/m²").
    transfer: how `emission`/`drive` read an RGB triple (see `spectrace.spectral.display_transfer`).
    technology: a short label ("LCD with CCFL backlight (inferred)"); source: where the data come from.
    polarization: of the light it emits (see `spectrace.spectral.display_polarization`).
    """

    name: str
    technology: str
    primaries: tuple[Spectrum, Spectrum, Spectrum]
    absolute: bool
    radiance_scale: str
    transfer: Encoding = Encoding.LINEAR
    source: str = ""
    polarization: Polarization = Polarization()

    def __post_init__(self) -> None:
        if len(self.primaries) != 3:
            raise ValueError(f"display '{self.name}' needs 3 primaries, got {len(self.primaries)}")
        for channel, primary in zip(CHANNELS, self.primaries):
            if primary.min() < 0:
                raise SpectraceError(f"{channel} primary has negative radiance", where=self.source or self.name)
            if not luminance_cd_m2(primary) > 0:
                raise SpectraceError(f"{channel} primary emits no visible light", where=self.source or self.name)

    # ------------------------------------------------------------ drive and emission

    @property
    def primaries_values(self) -> np.ndarray:
        """(3, 471): the primaries' grid samples, one row per channel."""
        return np.stack([primary.values for primary in self.primaries])

    def drive(self, rgb: np.ndarray | tuple[float, float, float]) -> np.ndarray:
        """Linear drive in [0, 1]^3 of an RGB triple read with this display's transfer."""
        return decode_to_drive(checked_rgb(rgb), self.transfer)

    def emission_from_drive(self, drive: np.ndarray) -> np.ndarray:
        """Grid samples of the emitted radiance for linear drive values (last axis RGB; any leading shape)."""
        return np.asarray(drive, dtype=np.float64) @ self.primaries_values

    def emission(self, rgb: np.ndarray | tuple[float, float, float]) -> Spectrum:
        """The spectral radiance the display emits for an RGB triple (units of the primaries)."""
        values = self.emission_from_drive(self.drive(rgb))
        triple = ", ".join(f"{value:g}" for value in np.asarray(rgb, dtype=np.float64))
        return Spectrum(values, name=f"{self.name} ({triple})", source=self.source)

    # ------------------------------------------------------------ colorimetry

    def primaries_matrix(self, observer: Observer = Observer.CIE_1931_2) -> np.ndarray:
        """(3, 3) photometric XYZ of each primary at full drive, as columns: XYZ = M @ drive."""
        return photometric_xyz(self.primaries_values, observer).T

    def photometric_xyz(
        self, rgb: np.ndarray | tuple[float, float, float], observer: Observer = Observer.CIE_1931_2
    ) -> np.ndarray:
        """683 lm/W * integral L cmf dlambda of the emission: cd/m^2 (CIE 1931 Y) for an absolute display."""
        return self.primaries_matrix(observer) @ self.drive(rgb)

    def film_xyz(self, rgb: np.ndarray | tuple[float, float, float]) -> np.ndarray:
        """The renderer's film XYZ of the emission (integral L cmf / integral ybar; see spectral.colorimetry)."""
        return spectrum_to_xyz(self.emission_from_drive(self.drive(rgb)))

    @property
    def white_luminance_cd_m2(self) -> float:
        """Luminance of white (1, 1, 1); in cd/m^2 when `absolute`, else on the primaries' relative scale."""
        return float(luminance_cd_m2(self.primaries_values.sum(axis=0)))

    def primaries_xy(self) -> np.ndarray:
        """(3, 2) CIE 1931 xy of red, green, blue."""
        return xyz_to_xy(self.primaries_matrix().T)

    def white_xy(self) -> np.ndarray:
        return xyz_to_xy(self.primaries_matrix().sum(axis=1))

    # ------------------------------------------------------------ variants

    def scaled_to_white_luminance(self, white_cd_m2: float) -> Display:
        """The same display with its primaries scaled so that white (1, 1, 1) has `white_cd_m2` cd/m^2."""
        if not (np.isfinite(white_cd_m2) and white_cd_m2 > 0):
            raise SpectraceError(f"white luminance must be a positive number of cd/m², got {white_cd_m2:g}")
        factor = white_cd_m2 / self.white_luminance_cd_m2
        red, green, blue = (primary.scaled(factor) for primary in self.primaries)
        return replace(
            self, primaries=(red, green, blue), absolute=True, radiance_scale=f"white set to {white_cd_m2:g} cd/m²"
        )

    def with_transfer(self, transfer: Encoding) -> Display:
        """The same display reading RGB triples with another transfer curve."""
        return replace(self, transfer=transfer)
