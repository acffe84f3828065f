"""What the film responds to: the observer of its XYZ, more observers' XYZ, a camera's measured channels.

The default film is CIE 1931 2° XYZ (spectrace.spectral.colorimetry). A `FilmResponse` can instead give the film's
XYZ for another CIE observer, add the XYZ of further observers (one render, the same paths), and add the channels of
a measured sensor (a camera's raw R, G, B, a monochrome sensor, a multispectral camera's bands) read from a CSV file.
Each extra curve r(λ) becomes one film channel holding ∫ L(λ) r(λ) dλ (kernels/film.cl). Observers' curves are
divided by their own ∫ȳ, so that a constant radiance 1 has Y = 1 for every observer, as for the default film;
a sensor's channels are its sensitivities as the file gives them (∫ L s dλ, radiance × sensitivity × nm).

Observer data: CIE 1931 2° is the table shipped in spectra/observers/ (colour-science's, from CVRL); CIE 1964 10°
and the CIE 2012 2° and 10° "physiologically relevant" colour matching functions (CIE 170-2:2015; colour-science
names them "CIE 2015 ...") are read from colour-science's `MSDS_CMFS` (from CVRL, cvrl.org) when asked for, and are
zero where their tables have no data (the 2012 tables start at 390 nm).

Wavelength sampling follows the film's curves: any film other than the default one draws wavelengths from a
tabulated pdf ∝ (1 − u) · mean of the curves (each scaled to unit integral) + u · uniform, u = UNIFORM_FRACTION, so
that every curve has samples where it responds and none of them goes without samples anywhere on the grid. The
default film keeps the visible-range pdf of kernels/wavelengths.cl (and so its exact bits).

A sensor's white balance and colour-correction matrix (when `sensor_white` names a CIE illuminant): white-balance
gains make that illuminant's white (reflectance 1) give each channel the illuminant's film Y; the 3×3 matrix to CIE
1931 XYZ is colour-science's least-squares `matrix_colour_correction` (Cheung et al. 2004) fitted on the 24
ColorChecker reflectances (colour-science's "ColorChecker N Ohta", held flat beyond 380..780 nm) under that
illuminant. The corrected XYZ then becomes the image's XYZ (and its RGB outputs).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cache
from pathlib import Path
from typing import Any

import numpy as np

from spectrace.core.equality import fields_equal, identity_hash
from spectrace.errors import SpectraceError
from spectrace.spectral.colorimetry import CIE_1931_CMFS, cmf_table_normalised, spectrum_to_xyz
from spectrace.spectral.grid import (
    GRID_MAX_NM,
    GRID_MIN_NM,
    GRID_NM,
    GRID_STEP_NM,
    TRAPEZOID_WEIGHTS_NM,
    integrate_on_grid,
)

DEFAULT_OBSERVER = "CIE 1931 2°"
# label (the scene format's name) -> (channel prefix, colour-science's MSDS_CMFS key)
OBSERVERS: dict[str, tuple[str, str]] = {
    "CIE 1931 2°": ("cie1931_2", "CIE 1931 2 Degree Standard Observer"),
    "CIE 1964 10°": ("cie1964_10", "CIE 1964 10 Degree Standard Observer"),
    "CIE 2012 2°": ("cie2012_2", "CIE 2015 2 Degree Standard Observer"),
    "CIE 2012 10°": ("cie2012_10", "CIE 2015 10 Degree Standard Observer"),
}
UNIFORM_FRACTION = 0.1  # of the tabulated wavelength pdf
DELTA_E_CHANNEL = "deltaE00"
SENSOR_PREFIX = "sensor."


WAVELENGTH_LIMITS_NM = (200.0, 2500.0)  # what film.wavelengths may ask for (silicon to short-wave infrared)


def wavelength_range_problem(wavelengths: tuple[float, float]) -> str | None:
    lo, hi = (float(value) for value in wavelengths)
    if not (WAVELENGTH_LIMITS_NM[0] <= lo < hi <= WAVELENGTH_LIMITS_NM[1]):
        return (
            f"film wavelengths must be [lo, hi] with {WAVELENGTH_LIMITS_NM[0]:g} <= lo < hi <= "
            f"{WAVELENGTH_LIMITS_NM[1]:g} nm, got [{lo:g}, {hi:g}]"
        )
    if lo != round(lo) or hi != round(hi):
        return f"film wavelengths must be whole nanometres (the grid is 1 nm), got [{lo:g}, {hi:g}]"
    return None


def observer_problem(label: str) -> str | None:
    if label in OBSERVERS:
        return None
    return f"unknown observer '{label}' (use {', '.join(repr(name) for name in OBSERVERS)})"


def observer_range_problem(label: str, wavelengths: tuple[float, float]) -> str | None:
    """Why observer `label` sees nothing over the film's `wavelengths` (all of x̄, ȳ, z̄ zero there), or None."""
    lo, hi = (float(value) for value in wavelengths)
    inside = np.abs(GRID_NM - 0.5 * (lo + hi)) <= 0.5 * (hi - lo)
    if np.any(observer_cmfs(label)[inside] > 0.0):
        return None
    seen = GRID_NM[np.any(observer_cmfs(label) > 0.0, axis=1)]
    return (
        f"observer '{label}' is zero over the film's wavelengths {lo:g}-{hi:g} nm (it responds over "
        f"{seen[0]:g}-{seen[-1]:g} nm): its X, Y, Z would all be 0; widen or move film.wavelengths"
    )


@cache
def observer_cmfs(label: str) -> np.ndarray:
    """(grid, 3) x̄, ȳ, z̄ of the observer `label` on the grid, zero where its table has no data."""
    if label == DEFAULT_OBSERVER:
        return CIE_1931_CMFS
    import colour  # only for the non-default observers: it takes about a second to import

    cmfs = colour.MSDS_CMFS[OBSERVERS[label][1]]
    wavelengths = np.asarray(cmfs.wavelengths, np.float64)
    values = np.asarray(cmfs.values, np.float64)
    table = np.stack([np.interp(GRID_NM, wavelengths, values[:, i], left=0.0, right=0.0) for i in range(3)], axis=1)
    table.setflags(write=False)
    return table


def observer_xyz_curves(label: str, wavelengths_nm: np.ndarray = GRID_NM) -> np.ndarray:
    """(wavelengths, 3): the observer's CMFs divided by its ∫ȳ, so that a constant radiance 1 has Y = 1; zero
    beyond the common grid (no observer's table goes further)."""
    cmfs = observer_cmfs(label) / float(integrate_on_grid(observer_cmfs(label)[:, 1]))
    if wavelengths_nm is GRID_NM:
        return cmfs
    return np.stack([np.interp(wavelengths_nm, GRID_NM, cmfs[:, i], left=0.0, right=0.0) for i in range(3)], axis=1)


@dataclass(frozen=True, eq=False)
class Sensor:
    """Measured channel sensitivities: the file's samples, (wavelengths,) and (wavelengths, channels)."""

    __eq__ = fields_equal  # by value (arrays too), hashed by identity
    __hash__ = identity_hash

    source: str
    channel_names: tuple[str, ...]
    wavelengths_nm: np.ndarray
    sensitivities: np.ndarray

    def curves_on(self, wavelengths_nm: np.ndarray) -> np.ndarray:
        """(channels, len(wavelengths_nm)): linear between the samples, zero beyond them."""
        return np.stack(
            [
                np.interp(wavelengths_nm, self.wavelengths_nm, self.sensitivities[:, i], left=0.0, right=0.0)
                for i in range(self.sensitivities.shape[1])
            ]
        )

    @property
    def curves(self) -> np.ndarray:
        """(channels, grid) on the common grid."""
        return self.curves_on(GRID_NM)


def _is_multi_spectral(value: object) -> bool:
    """Whether `value` is a colour-science MultiSpectralDistributions (read by its attributes: colour-science is
    imported only by whoever made it)."""
    return all(hasattr(value, name) for name in ("wavelengths", "values", "labels")) and not isinstance(
        value, str | Path
    )


def sensor_from_multi_spectral(distributions: Any) -> Sensor:
    """A Sensor from colour-science's MultiSpectralDistributions, such as a camera's
    `colour.MSDS_CAMERA_SENSITIVITIES["Nikon 5100 (NPL)"]`: its wavelengths, one channel per label."""
    source = str(getattr(distributions, "name", "") or "MultiSpectralDistributions")
    wavelengths = np.asarray(distributions.wavelengths, np.float64)
    data = np.asarray(distributions.values, np.float64)
    names = tuple(str(label) for label in distributions.labels)
    if data.ndim != 2 or data.shape != (len(wavelengths), len(names)) or len(wavelengths) < 2:
        raise SpectraceError(f"expected (wavelengths, channels) sensitivities, got shape {data.shape}", where=source)
    if not np.all(np.diff(wavelengths) > 0):
        raise SpectraceError("wavelengths must ascend", where=source)
    if not np.all(np.isfinite(data)) or np.any(data < 0):
        raise SpectraceError("sensitivities must be finite and non-negative", where=source)
    for name, row in zip(names, data.T):
        if not row.max() > 0:
            raise SpectraceError(f"channel '{name}' has no sensitivity", where=source)
    return Sensor(source, names, wavelengths, data)


def load_sensor(path: Any) -> Sensor:
    """A sensor CSV: header `wavelength_nm,<channel>[,<channel>...]`, '#' comment lines, ascending wavelengths; or
    colour-science's MultiSpectralDistributions (a camera's `colour.MSDS_CAMERA_SENSITIVITIES[...]`).

    A sensor responds only where its file says it does: outside the file's wavelengths its sensitivity is zero.
    """
    from spectrace.spectral.spectrum_io import _check_ascending, _parse_number, _read_csv_table

    if _is_multi_spectral(path):
        return sensor_from_multi_spectral(path)
    path = Path(path)
    table = _read_csv_table(path)
    width = 1 + len(table.columns)
    wavelengths: list[float] = []
    rows: list[list[float]] = []
    for line_number, fields in table.rows:
        at = f"{path}:{line_number}"
        if len(fields) != width:
            raise SpectraceError(f"expected {width} comma-separated fields, got {len(fields)}", where=at)
        wavelength = _parse_number(fields[0], "wavelength_nm", at)
        _check_ascending(wavelengths[-1] if wavelengths else None, wavelength, at)
        values = [_parse_number(text, f"value in column '{name}'", at) for name, text in zip(table.columns, fields[1:])]
        if any(not np.isfinite(v) or v < 0 for v in values):
            raise SpectraceError("sensitivities must be finite and non-negative", where=at)
        wavelengths.append(wavelength)
        rows.append(values)
    if len(wavelengths) < 2:
        raise SpectraceError("a sensor file needs at least two wavelengths", where=str(path))
    data = np.asarray(rows, np.float64)
    sensor = Sensor(str(path), tuple(table.columns), np.asarray(wavelengths, np.float64), data)
    for name, row in zip(table.columns, data.T):
        if not row.max() > 0:
            raise SpectraceError(f"channel '{name}' has no sensitivity", where=str(path))
    return sensor


@dataclass(frozen=True, eq=False)
class FilmResponse:
    """The film's observer (of its X, Y, Z and RGB outputs), extra observers, and an optional measured sensor."""

    __eq__ = fields_equal  # by value (arrays too), hashed by identity
    __hash__ = identity_hash

    observer: str = DEFAULT_OBSERVER
    observers: tuple[str, ...] = ()
    sensor: Sensor | None = None
    sensor_white: str | None = None  # CIE illuminant for the white balance and colour-correction matrix
    delta_e_pair: tuple[str, str] | None = field(default=None)  # observers whose CIEDE2000 map the image gets
    # Film Y of the ΔE map's reference white (CIELAB's Y_n); None: the scene's own white (`scene_white_y`).
    delta_e_white_y: float | None = None
    wavelengths: tuple[float, float] = (GRID_MIN_NM, GRID_MAX_NM)  # the film's range, nm (a 1 nm grid over it)
    extend_rgb: bool = False  # RGB uplifts continue beyond the visible when the range goes there

    def __post_init__(self) -> None:
        if self.sensor is not None and not isinstance(self.sensor, Sensor):
            if not _is_multi_spectral(self.sensor):
                raise SpectraceError(
                    "sensor must be a Sensor (load_sensor) or colour-science's MultiSpectralDistributions, got "
                    f"{type(self.sensor).__name__}"
                )
            object.__setattr__(self, "sensor", sensor_from_multi_spectral(self.sensor))
        for label in (self.observer, *self.observers):
            if problem := observer_problem(label):
                raise SpectraceError(problem)
        if len(set(self.observers)) != len(self.observers):
            raise SpectraceError("film observers are listed more than once")
        if self.sensor_white is not None and (self.sensor is None or len(self.sensor.channel_names) != 3):
            raise SpectraceError("sensor_white (white balance and colour correction) needs a 3-channel sensor")
        if self.delta_e_white_y is not None and not (np.isfinite(self.delta_e_white_y) and self.delta_e_white_y > 0):
            raise SpectraceError(f"the ΔE map's white Y must be a positive number, got {self.delta_e_white_y}")
        if problem := wavelength_range_problem(self.wavelengths):
            raise SpectraceError(problem)
        # An observer zero over the whole range records nothing, and a film of nothing else has no wavelength to
        # sample (its pdf is 0/0: every sample NaN). The film's own observer may be zero there when a sensor's
        # channels are what the film is for (an infrared camera); its X, Y, Z are then black by request.
        for label in (*([] if self.sensor is not None else [self.observer]), *self.observers):
            if problem := observer_range_problem(label, self.wavelengths):
                raise SpectraceError(problem, where="film.wavelengths")
        if self.sensor is not None:
            for name, curve in zip(self.sensor.channel_names, self.sensor.curves_on(self.grid_nm)):
                if not curve.max() > 0:
                    lo, hi = self.wavelengths
                    raise SpectraceError(
                        f"sensor channel '{name}' has no sensitivity within the film's wavelengths {lo:g}-{hi:g} nm "
                        "(film.wavelengths sets them)",
                        where=self.sensor.source,
                    )
        if self.delta_e_pair is not None:
            missing = [label for label in self.delta_e_pair if label not in self.observers]
            if missing or self.delta_e_pair[0] == self.delta_e_pair[1]:
                raise SpectraceError(
                    "the ΔE map compares two different observers of film.observers, "
                    f"got {' and '.join(self.delta_e_pair)}"
                )

    @property
    def is_default(self) -> bool:
        return (
            self.observer == DEFAULT_OBSERVER and not self.observers and self.sensor is None and not self.has_own_grid
        )

    @property
    def has_own_grid(self) -> bool:
        """The film's range is not the common grid's: spectra go to the device on the film's own 1 nm grid."""
        return tuple(self.wavelengths) != (GRID_MIN_NM, GRID_MAX_NM)

    @property
    def grid_nm(self) -> np.ndarray:
        """The film's wavelength grid: 1 nm over `wavelengths` (the common grid by default)."""
        if not self.has_own_grid:
            return GRID_NM
        lo, hi = self.wavelengths
        return np.arange(lo, hi + 0.5 * GRID_STEP_NM, GRID_STEP_NM)

    @property
    def channel_names(self) -> tuple[str, ...]:
        """Names of the response film's channels, in film order (the EXR channel names)."""
        names = [f"{OBSERVERS[label][0]}.{axis}" for label in self.observers for axis in "XYZ"]
        if self.sensor is not None:
            names += [SENSOR_PREFIX + name for name in self.sensor.channel_names]
        return tuple(names)

    def curves(self) -> np.ndarray:
        """(channels, film grid) response curves of the response film."""
        grid = self.grid_nm
        parts = [observer_xyz_curves(label, grid).T for label in self.observers]
        if self.sensor is not None:
            parts.append(self.sensor.curves_on(grid))
        return np.concatenate(parts) if parts else np.zeros((0, grid.size))

    def xyz_curves(self) -> np.ndarray:
        """(film grid, 3) float32: the XYZ film's table (the default film's exact one for CIE 1931)."""
        if self.observer == DEFAULT_OBSERVER and not self.has_own_grid:
            return cmf_table_normalised()
        return observer_xyz_curves(self.observer, self.grid_nm).astype(np.float32)

    def sampling_pdf(self) -> np.ndarray:
        """(grid − 1,) pdf (1/nm) of the wavelengths on the grid's intervals: see the module's docstring."""
        curves = np.concatenate([self.xyz_curves().T.astype(np.float64), self.curves()])
        shapes = curves / np.maximum(curves.sum(axis=1), 1e-300)[:, None]
        mean = shapes.mean(axis=0)
        on_intervals = 0.5 * (mean[1:] + mean[:-1])
        span = GRID_STEP_NM * (self.grid_nm.size - 1)
        pdf = (1.0 - UNIFORM_FRACTION) * on_intervals / (on_intervals.sum() * GRID_STEP_NM) + UNIFORM_FRACTION / span
        return pdf

    def sampling_table(self) -> tuple[np.ndarray, np.ndarray]:
        """float32 CDF at the grid's nodes (0 … 1) and the pdf on each interval made consistent with it, so that
        the kernel's pdf is exactly the rate its CDF rises at."""
        cdf64 = np.concatenate([[0.0], np.cumsum(self.sampling_pdf() * GRID_STEP_NM)])
        cdf = (cdf64 / cdf64[-1]).astype(np.float32)
        cdf[-1] = 1.0
        pdf = (np.diff(cdf.astype(np.float64)) / GRID_STEP_NM).astype(np.float32)
        return cdf, pdf

    def device_table(self) -> np.ndarray:
        """(rows, 4) float32: the film table kernels/film.cl reads (XYZ CMFs, response curves, sampling table)."""
        size = self.grid_nm.size
        xyz = np.zeros((size, 4), np.float32)
        xyz[:, :3] = self.xyz_curves()
        curves = self.curves()
        groups = (len(curves) + 3) // 4
        responses = np.zeros((groups, size, 4), np.float32)
        for channel, curve in enumerate(curves):
            responses[channel // 4, :, channel % 4] = curve
        cdf, pdf = self.sampling_table()
        sampling = np.concatenate([cdf, pdf])
        sampling = np.concatenate([sampling, np.zeros((-sampling.size) % 4, np.float32)]).reshape(-1, 4)
        return np.ascontiguousarray(np.concatenate([xyz, responses.reshape(-1, 4), sampling]))

    def defines(self) -> dict[str, int | float]:
        """Kernel defines for this film (none for the default film); a film range of its own sets the grid of
        every tabulated spectrum (kernels/spectrum.cl) to the film's. The count of response curves is a run-time
        value (RenderParams.film_responses), so films of one grid share a program."""
        if self.is_default:
            return {}
        defines: dict[str, int | float] = {"WAVELENGTH_TABLE": 1}
        if self.has_own_grid:
            grid = self.grid_nm
            defines |= {"GRID_MIN_NM": float(grid[0]), "GRID_MAX_NM": float(grid[-1]), "GRID_SAMPLES": int(grid.size)}
        return defines

    def metadata(self) -> dict[str, str]:
        """What the film responds to, for an image's metadata (nothing for the default film)."""
        if self.is_default:
            return {}
        lo, hi = self.wavelengths
        metadata = {"observer": self.observer, "wavelengths_nm": f"{lo:g}-{hi:g}"}
        if self.sensor is not None:
            metadata["sensor"] = self.sensor.source
        if self.sensor_white is not None:
            metadata["sensor_white"] = self.sensor_white
        return metadata

    def outputs(self, xyz: np.ndarray, responses: np.ndarray) -> tuple[np.ndarray, dict[str, np.ndarray]]:
        """The image's XYZ and named extra channels from the film's means: xyz (H, W, 3), responses (H, W, N)."""
        channels = {name: responses[..., i] for i, name in enumerate(self.channel_names)}
        if self.sensor_white is not None:
            assert self.sensor is not None
            gains, matrix = sensor_correction(self.sensor, self.sensor_white)
            raw = np.stack([channels[SENSOR_PREFIX + name] for name in self.sensor.channel_names], axis=-1)
            xyz = ((raw * gains) @ matrix.T).astype(np.float32)
        if self.delta_e_pair is not None:
            first, second = (observer_xyz_image(channels, label) for label in self.delta_e_pair)
            white_y = self.delta_e_white_y or scene_white_y(first[..., 1])
            delta_e = delta_e_2000_map(first, second, *self.delta_e_pair, white_y=white_y)
            channels[DELTA_E_CHANNEL] = delta_e.astype(np.float32)
        return xyz, channels


def scene_white_y(film_y: np.ndarray) -> float:
    """The film Y of the scene's own white, CIELAB's Y_n for the ΔE map: the brightest area of at least 3 × 3
    pixels (the largest Y after a 3 × 3 median filter), so that one bright pixel (a firefly) is not taken for it
    while a white patch a few pixels across is. A light source seen over 3 × 3 pixels or more is taken for the
    white too: give the white patch's Y then (`--delta-e-white-y`). 1 for a black image."""
    from scipy.ndimage import median_filter

    values = np.nan_to_num(np.asarray(film_y, np.float64), nan=0.0, posinf=0.0, neginf=0.0)
    white = float(median_filter(values, size=3, mode="nearest").max()) if values.size else 0.0
    return white if white > 0 else 1.0


def observer_xyz_image(channels: dict[str, np.ndarray], label: str) -> np.ndarray:
    """(H, W, 3) XYZ of observer `label` from an image's extra channels."""
    prefix = OBSERVERS[label][0]
    return np.stack([channels[f"{prefix}.{axis}"] for axis in "XYZ"], axis=-1)


@cache
def reference_white_xy(label: str) -> tuple[float, float]:
    """Chromaticity of CIE D65 for observer `label` (colour-science's `sd_to_XYZ` of its D65 table with that
    observer's CMFs): the reference white of that observer's CIELAB in the ΔE map."""
    import colour

    xyz = colour.sd_to_XYZ(colour.SDS_ILLUMINANTS["D65"], cmfs=colour.MSDS_CMFS[OBSERVERS[label][1]])
    x, y = colour.XYZ_to_xy(xyz)
    return float(x), float(y)


def delta_e_2000_map(
    first: np.ndarray, second: np.ndarray, first_label: str, second_label: str, white_y: float = 1.0
) -> np.ndarray:
    """Per-pixel CIEDE2000 between two observers' XYZ images (colour-science's `delta_E`). Each image goes to CIELAB
    with its own observer's D65 chromaticity as the reference white, at film Y = `white_y` (by default 1: a constant
    radiance 1 is L* = 100)."""
    import colour

    lab_first = colour.XYZ_to_Lab(first.astype(np.float64) / white_y, reference_white_xy(first_label))
    lab_second = colour.XYZ_to_Lab(second.astype(np.float64) / white_y, reference_white_xy(second_label))
    return np.asarray(colour.delta_E(lab_first, lab_second, method="CIE 2000"))


@cache
def _training_reflectances() -> np.ndarray:
    import colour

    patches = colour.SDS_COLOURCHECKERS["ColorChecker N Ohta"]
    return np.stack([np.interp(GRID_NM, sd.wavelengths, sd.values) for sd in patches.values()])


def sensor_correction(sensor: Sensor, illuminant: str) -> tuple[np.ndarray, np.ndarray]:
    """White-balance gains (3,) and the 3×3 matrix M with XYZ = M @ (gains · raw): see the module's docstring."""
    import colour

    from spectrace.spectral.illuminants import cie_illuminant

    light = cie_illuminant(illuminant, where="film.sensor_white").values
    weights = TRAPEZOID_WEIGHTS_NM
    white_raw = (light * weights) @ sensor.curves.T
    light_y = float(spectrum_to_xyz(light)[1])
    gains = light_y / white_raw
    reflected = _training_reflectances() * light
    camera = (reflected * weights) @ sensor.curves.T * gains
    target = spectrum_to_xyz(reflected)
    matrix = np.asarray(colour.characterisation.matrix_colour_correction(camera, target, method="Cheung 2004"))
    return gains, matrix
