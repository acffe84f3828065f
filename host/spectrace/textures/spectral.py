"""`spectral`: a spectral OpenEXR image in the layout spectrace writes (Fichet, Pacanowski & Wilkie 2021: channels
`S0.<λ>nm`, spectrace.io.exr), each texel a spectrum sampled at the channels' wavelengths. The device interpolates
between them at the path's wavelengths (the end bands held beyond them): no RGB round trip, so spectra no RGB
triple can describe (a narrow-band pigment, a fluorescent-looking peak, a metamer) render as measured. Band centres
that are not equally spaced are resampled linearly onto equal spacing at the smallest gap. docs/textures.md."""

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from spectrace.core.contract import TEXEL_BANDS
from spectrace.core.equality import fields_equal, identity_hash
from spectrace.errors import SpectraceError
from spectrace.textures.shared import (
    FILE,
    FILTER,
    UV_OFFSET,
    WRAP,
    Placement,
    checked_placement,
    mip_pyramid,
    placement,
    uv_scale,
)

NAME = "spectral"
API_NAME = "spectral_texture"  # beside spectrace.spectrum, a bare "spectral" would not say what it makes
COMPOSITE = False
PARAMETERS = (FILE, WRAP, FILTER, uv_scale(1.0), UV_OFFSET)
# More bands than the 1 nm grid has samples would add nothing the renderer can resolve.
MAX_BANDS = 471
MITSUBA_PLUGINS: tuple[str, ...] = ()
MITSUBA_NONE = (
    "Mitsuba 3 has no spectral image texture (its bitmap holds RGB, uplifted to spectra in its spectral variants)"
)
PBRT_TEXTURES: tuple[str, ...] = ()
PBRT_NONE = "pbrt-v4 has no spectral image texture"


@dataclass(frozen=True, eq=False)
class SpectralTexture:
    """values (height, width, bands) at equally spaced band centres wavelengths_nm, row 0 at the top (v = 0)."""

    __eq__ = fields_equal  # by value (arrays too), hashed by identity
    __hash__ = identity_hash

    wavelengths_nm: np.ndarray
    values: np.ndarray
    placement: Placement = Placement()
    source: str = "array"

    @property
    def channels(self) -> int:
        return int(self.values.shape[-1])


MODEL = SpectralTexture


def _equally_spaced(wavelengths: np.ndarray, values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    if len(wavelengths) < 2:
        return wavelengths, values
    gaps = np.diff(wavelengths)
    if np.allclose(gaps, gaps[0], rtol=0.0, atol=1e-3):
        return wavelengths, values
    count = min(int(round((wavelengths[-1] - wavelengths[0]) / gaps.min())) + 1, MAX_BANDS)
    grid = np.linspace(wavelengths[0], wavelengths[-1], count)
    upper = np.clip(np.searchsorted(wavelengths, grid, side="right"), 1, len(wavelengths) - 1)
    frac = (grid - wavelengths[upper - 1]) / (wavelengths[upper] - wavelengths[upper - 1])
    return grid, values[..., upper - 1] * (1.0 - frac) + values[..., upper] * frac


def read_spectral_texture(path: Path, where: str) -> tuple[np.ndarray, np.ndarray]:
    """(wavelengths_nm (bands,), values (height, width, bands)) of a spectral OpenEXR; errors name `where`."""
    from spectrace.io.exr import parse_spectral_channel
    from spectrace.io.images import read_exr_checked

    channels = read_exr_checked(path, where, "texture")
    bands = sorted((nm, name) for name in channels if (nm := parse_spectral_channel(name)) is not None)
    if not bands:
        raise SpectraceError(f"texture '{path}' has no spectral channels (S0.<λ>nm)", where=where)
    if len(bands) > MAX_BANDS:
        raise SpectraceError(f"texture '{path}' has {len(bands)} spectral channels; at most {MAX_BANDS}", where=where)
    wavelengths = np.array([nm for nm, _ in bands], np.float64)
    if np.any(np.diff(wavelengths) <= 0):
        raise SpectraceError(f"texture '{path}' has two channels at the same wavelength", where=where)
    values = np.stack([np.asarray(channels[name], np.float64) for _, name in bands], axis=-1)
    if not np.all(np.isfinite(values)):
        raise SpectraceError(f"texture '{path}' has NaN or infinite values", where=where)
    return _equally_spaced(wavelengths, values)


def from_spec(spec, resolver, key: str) -> SpectralTexture:
    path = resolver.folder / spec.file
    wavelengths, values = read_spectral_texture(path, resolver.where(f"{key}.file"))
    return SpectralTexture(wavelengths, _read_only(values), placement(spec, resolver.where(key)), source=str(path))


def make(
    source,
    wavelengths_nm=None,
    *,
    wrap: str = "repeat",
    filter: str = "bilinear",
    uv_scale: float | tuple[float, float] = 1.0,
    uv_offset: tuple[float, float] = (0.0, 0.0),
) -> SpectralTexture:
    """A spectral texture, `spectrace.spectral_texture`: a spectral OpenEXR file (S0.<λ>nm channels, as spectrace
    writes them) or an array (height, width, bands) with the bands' wavelengths in nm (ascending); each texel's
    spectrum is interpolated at the path's wavelengths, with no RGB round trip (docs/textures.md)."""
    where = "texture"
    if isinstance(source, (str, Path)):
        wavelengths, values = read_spectral_texture(Path(source), where)
        name = str(source)
    else:
        values = np.asarray(source, np.float64)
        given = np.asarray(wavelengths_nm if wavelengths_nm is not None else [], np.float64)
        if values.ndim != 3 or given.shape != (values.shape[-1],):
            raise SpectraceError("a spectral texture array is (H, W, bands) with one wavelength per band", where)
        if not (np.all(np.isfinite(values)) and np.all(np.diff(given) > 0)):
            raise SpectraceError("a spectral texture needs finite values and ascending wavelengths", where)
        wavelengths, values = _equally_spaced(given, values)
        name = "array"
    return SpectralTexture(
        wavelengths, _read_only(values), checked_placement(uv_scale, uv_offset, wrap, filter), source=name
    )


def _read_only(array: np.ndarray) -> np.ndarray:
    array = np.ascontiguousarray(array, np.float32)
    array.setflags(write=False)
    return array


def device_texels(texture: SpectralTexture, kind: str) -> tuple[int, int, list[np.ndarray]]:
    """(TEXEL_BANDS, bands, levels); the pyramid averages each band."""
    if kind not in ("spectrum", "emission"):
        raise SpectraceError(f"spectral texture '{texture.source}' can only give a spectrum")
    values = texture.values.astype(np.float64)
    levels = mip_pyramid(values) if texture.placement.filter == "trilinear" else [values]
    return TEXEL_BANDS, texture.channels, levels
