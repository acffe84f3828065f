"""How an RGB triple given to a display turns into linear drive (the fraction of each primary's full emission).

The measured data ship each primary's emission at full drive only; the sources' gamma tables were not copied, so
a display's own transfer curve is unknown here. A triple is therefore read in one of three stated encodings:
- `linear`: the triple *is* the linear drive (default: exact, and the same meaning on every display);
- `srgb`: encoded with the sRGB curve (IEC 61966-2-1), decoded before driving the primaries;
- `gamma2.2`: encoded with a pure power law, drive = value ** 2.2 (the usual model of a CRT/LCD without a table).
"""

from __future__ import annotations

from collections.abc import Callable
from enum import StrEnum

import numpy as np

from spectrace.errors import SpectraceError
from spectrace.spectral import srgb_decode, srgb_encode

DISPLAY_GAMMA = 2.2


class Encoding(StrEnum):
    LINEAR = "linear"
    SRGB = "srgb"
    GAMMA_2_2 = "gamma2.2"


def parse_encoding(text: str, where: str | None = None) -> Encoding:
    try:
        return Encoding(text.strip().lower())
    except ValueError:
        choices = ", ".join(encoding.value for encoding in Encoding)
        raise SpectraceError(f"unknown encoding '{text}' (choose {choices})", where=where) from None


def checked_rgb(rgb: np.ndarray | tuple[float, float, float], where: str = "rgb") -> np.ndarray:
    """The triple as a float64 (3,) array; a display cannot be driven below 0 or beyond full drive (1)."""
    array = np.asarray(rgb, dtype=np.float64)
    if array.shape != (3,):
        raise SpectraceError(f"an RGB triple needs 3 values, got shape {array.shape}", where=where)
    if not np.all(np.isfinite(array)) or np.any(array < 0) or np.any(array > 1):
        values = ", ".join(f"{value:g}" for value in array)
        raise SpectraceError(f"RGB values must lie in [0, 1], got ({values})", where=where)
    return array


def _transfer(
    values: np.ndarray, encoding: Encoding, srgb: Callable[[np.ndarray], np.ndarray], gamma: float
) -> np.ndarray:
    values = np.asarray(values, dtype=np.float64)
    if encoding is Encoding.LINEAR:
        return values.copy()
    if encoding is Encoding.SRGB:
        return srgb(values)
    return np.power(values, gamma)


def decode_to_drive(encoded: np.ndarray, encoding: Encoding) -> np.ndarray:
    """Encoded values in [0, 1] (last axis RGB) -> linear drive in [0, 1]."""
    return _transfer(encoded, encoding, srgb_decode, DISPLAY_GAMMA)


def encode_drive(drive: np.ndarray, encoding: Encoding) -> np.ndarray:
    """Inverse of `decode_to_drive`: linear drive in [0, 1] -> encoded values."""
    return _transfer(drive, encoding, srgb_encode, 1.0 / DISPLAY_GAMMA)
