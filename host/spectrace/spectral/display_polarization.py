"""The polarisation of a display's light, and what an ideal linear polariser (an analyser, polarised sunglasses, a
camera's filter) passes of it.

A display's light is described by its normalised Stokes vector (S0 = 1): an LCD's front polariser makes it linear
at the polariser's axis; an OLED's anti-reflection circular polariser also ends in a linear polariser on the viewer's
side, so its light leaves linearly polarised too, unless a further quarter-wave layer on top makes it circular; a CRT
or an LED wall emits unpolarised light. Angles are in degrees, counter-clockwise from the screen's horizontal as the
viewer sees it.

A linear polariser at angle θ with principal transmittances k1 (along its axis) and k2 (across it; 1 and 0 for an
ideal one) has the Mueller matrix first row ½ (k1 + k2, (k1 − k2) cos 2θ, (k1 − k2) sin 2θ, 0), so it passes
    I(θ) = ½ ((k1 + k2) S0 + (k1 − k2) (S1 cos 2θ + S2 sin 2θ))
of the light: for an ideal one cos²(θ − φ) of light linearly polarised at φ (Malus's law), ½ of unpolarised or
circular light. Being neutral (k1, k2 the same at every wavelength), it changes the luminance and never the
chromaticity.

In a display CSV: `# polarization: linear 45`, `# polarization: unpolarized`, `# polarization: circular`, or
`# polarization: unknown`; text after the value (in parentheses) says how it is known.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

import numpy as np

from spectrace.errors import SpectraceError

KINDS = ("linear", "circular", "unpolarized", "unknown")
_SPEC = re.compile(r"^\s*(linear|circular|unpolarized|unpolarised|unknown)\b\s*([^\s(]*)", re.IGNORECASE)


@dataclass(frozen=True)
class Polarization:
    kind: str = "unknown"
    axis_deg: float = 0.0  # linear only: the electric field's direction
    note: str = ""  # how it is known ("assumed: ...")

    @property
    def known(self) -> bool:
        return self.kind != "unknown"

    def stokes(self) -> np.ndarray:
        """(S0, S1, S2, S3) with S0 = 1."""
        if self.kind == "linear":
            angle = math.radians(2.0 * self.axis_deg)
            return np.array([1.0, math.cos(angle), math.sin(angle), 0.0])
        if self.kind == "circular":
            return np.array([1.0, 0.0, 0.0, 1.0])
        if self.kind == "unpolarized":
            return np.array([1.0, 0.0, 0.0, 0.0])
        raise SpectraceError("the display's polarisation is unknown; give it (linear <axis>, circular, unpolarized)")

    def text(self) -> str:
        return f"linear {self.axis_deg:g}°" if self.kind == "linear" else self.kind


def linear_polarizer_row(angle_deg: float | np.ndarray, k1: float = 1.0, k2: float = 0.0) -> np.ndarray:
    """The first row of a linear polariser's Mueller matrix at `angle_deg` (principal transmittances k1, k2):
    (..., 4)."""
    angle = np.radians(2.0 * np.asarray(angle_deg, dtype=np.float64))
    mean, difference = 0.5 * (k1 + k2), 0.5 * (k1 - k2)
    return np.stack(
        [np.full_like(angle, mean), difference * np.cos(angle), difference * np.sin(angle), np.zeros_like(angle)],
        axis=-1,
    )


def transmitted_fraction(
    polarization: Polarization, analyser_deg: float | np.ndarray, k1: float = 1.0, k2: float = 0.0
) -> np.ndarray:
    """The fraction of the display's light a linear polariser at `analyser_deg` passes (ideal by default)."""
    return linear_polarizer_row(analyser_deg, k1, k2) @ polarization.stokes()


def check_principal_transmittances(k1: float, k2: float, where: str | None = None) -> None:
    if not (math.isfinite(k1) and math.isfinite(k2) and 0.0 <= k2 <= k1 <= 1.0):
        raise SpectraceError(
            f"a polariser's principal transmittances need 0 <= k2 <= k1 <= 1 (k1 along its axis), got {k1:g}, {k2:g}",
            where=where,
        )


def parse_polarization(text: str, where: str | None = None) -> Polarization:
    """`linear 45`, `unpolarized`, `circular`, `unknown`, each optionally followed by a note in parentheses."""
    match = _SPEC.match(text)
    if match is None:
        raise SpectraceError(
            f"polarization must be 'linear <axis degrees>', 'circular', 'unpolarized' or 'unknown', got '{text}'",
            where=where,
        )
    kind = match.group(1).lower().replace("unpolarised", "unpolarized")
    note = text[match.end() :].strip().strip("()").strip()
    if kind != "linear":
        if match.group(2):
            raise SpectraceError(f"'{kind}' takes no angle, got '{match.group(2)}'", where=where)
        return Polarization(kind, 0.0, note)
    angle_text = match.group(2).rstrip("°")
    try:
        axis = float(angle_text)
    except ValueError:
        axis = math.nan
    if not math.isfinite(axis):
        raise SpectraceError(f"'linear' needs its axis in degrees, as 'linear 45', got '{text.strip()}'", where=where)
    return Polarization("linear", axis % 180.0, note)
