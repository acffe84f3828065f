"""OpenEXR output: linear sRGB as 32-bit float R, G, B, optionally the film's X, Y, Z, plus render metadata."""

import errno
import os
import re
from pathlib import Path

import numpy as np
import OpenEXR

from spectrace.io.atomic import write_atomically


def spectral_channel_name(wavelength_nm: float) -> str:
    """Emissive channel of Fichet, Pacanowski & Wilkie 2021 ("An OpenEXR Layout for Spectral Images", JCGT 10(3)):
    Stokes component S0, the wavelength with a decimal comma, then the unit."""
    return f"S0.{wavelength_nm:.6f}".replace(".", ",").replace("S0,", "S0.") + "nm"


def parse_spectral_channel(name: str) -> float | None:
    match = re.fullmatch(r"S0\.(\d+(?:,\d*)?)nm", name)
    return float(match.group(1).replace(",", ".")) if match else None


def write_exr(
    path: Path,
    linear_srgb: np.ndarray,
    xyz: np.ndarray | None,
    metadata: dict[str, str],
    spectral=None,
    attributes: dict | None = None,
    channels: dict[str, np.ndarray] | None = None,
) -> None:
    """spectral: SpectralBands (band-averaged radiance) written as one S0 channel per band centre, with the
    layout's attributes (spectralLayoutVersion, emissiveUnits, polarisationHandedness). attributes: standard
    header attributes, e.g. "chromaticities" when the RGB channels are not linear sRGB. channels: more (H, W)
    channels by name (names must not be R, G, B, X, Y, Z or spectral channels)."""
    extra_channels = channels or {}
    channels = {"RGB": np.ascontiguousarray(linear_srgb, dtype=np.float32)}
    header_extra = {}
    if spectral is not None:
        for i, centre in enumerate(spectral.centres_nm):
            channels[spectral_channel_name(centre)] = np.ascontiguousarray(spectral.radiance[..., i], np.float32)
        # Values are spectral radiance per nm; the unit string follows the layout's reference files.
        header_extra = {
            "spectralLayoutVersion": "1.0",
            "emissiveUnits": "W.m^-2.sr^-1",
            "polarisationHandedness": "right",
            "spectrace:spectral_band_edges_nm": ",".join(f"{e:g}" for e in spectral.edges_nm),
        }
    if xyz is not None:
        for i, name in enumerate("XYZ"):
            channels[name] = np.ascontiguousarray(xyz[..., i], dtype=np.float32)
    for name, values in extra_channels.items():
        if name in channels or name in {"R", "G", "B", "X", "Y", "Z"} or parse_spectral_channel(name) is not None:
            raise ValueError(f"EXR channel name {name!r} is reserved")
        channels[name] = np.ascontiguousarray(values, dtype=np.float32)
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    header.update({f"spectrace:{k}": str(v) for k, v in metadata.items()})
    header.update(header_extra)
    header.update(attributes or {})

    def write(temp: Path) -> None:
        try:
            with OpenEXR.File(header, channels) as exr:
                exr.write(str(temp))
        except RuntimeError as error:
            raise _os_error(error, temp) from None

    write_atomically(path, write)


def _os_error(error: RuntimeError, temp: Path) -> OSError:
    """OpenEXR reports a failed write (disk full, file too large, I/O error) as a RuntimeError whose text ends
    with the system's reason; as an OSError with that errno, callers handle it like any other failed write."""
    text = " ".join(str(error).split())
    for code in (errno.ENOSPC, errno.EDQUOT, errno.EFBIG, errno.EIO, errno.EROFS, errno.EACCES):
        if os.strerror(code) in text:
            return OSError(code, os.strerror(code), str(temp))
    return OSError(errno.EIO, f"OpenEXR: {text}", str(temp))


def read_exr(path: Path) -> tuple[dict[str, np.ndarray], dict]:
    """Channels (RGB as one (H, W, 3) array, others (H, W)) and the header."""
    with OpenEXR.File(str(path)) as exr:
        channels = {name: np.array(ch.pixels) for name, ch in exr.channels().items()}
        return channels, dict(exr.header())


def read_exr_header(path: Path) -> dict:
    """The header's attributes alone (no pixels read)."""
    with OpenEXR.File(str(path), header_only=True) as exr:
        return dict(exr.header())


def read_spectral_exr(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """(wavelengths_nm (bins,), radiance (height, width, bins)) from the S0 channels of a spectral EXR."""
    channels, _ = read_exr(path)
    bands = sorted((wavelength, name) for name in channels if (wavelength := parse_spectral_channel(name)) is not None)
    if not bands:
        raise ValueError(f"{path} has no spectral (S0.*nm) channels")
    return (np.array([w for w, _ in bands]), np.stack([channels[name] for _, name in bands], axis=-1))
