"""An LCD described by its physical layers instead of its measured primaries.

Channel c's primary is the backlight's spectrum through the polarisers and liquid crystal and through colour
filter c:

    P_c(λ) = s · B(λ) · T_pol · F_c(λ)

B: a blue LED with a YAG:Ce phosphor (`wled_yag`), a blue LED with green and red quantum-dot films (`qd`), or a cold
cathode fluorescent lamp's mercury lines and tri-phosphor (`ccfl`). Converter emission comes from
`spectra/fluorescent/` (photons per nm, turned into energy per nm by the factor 1/λ), allowed to shift and widen
in the fit since a product's phosphor or dots are not the published sample. T_pol: the polarisers and LC at full
drive, a number (two parallel polarisers of principal transmittances k1, k2 pass (k1² + k2²)/2 of unpolarised
light: about 0.4). F_c: a band-pass, a logistic rising and a logistic falling edge over a leakage floor. s: the
radiance scale, which with T_pol and the filters' peaks the measured primaries cannot separate: only their
product is measured, so filters are reported with peak 1 and each channel's product in `amplitudes`.

Fitting (`fit_layer_model`) adjusts the backlight's component weights and shapes and the filters' edges by least
squares on the three measured spectra (380–780 nm, each channel scaled to its peak); the xy of the modelled
primaries against the measured ones is the check of the fit.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from functools import cache

import numpy as np
from scipy.optimize import least_squares

from spectrace.errors import SpectraceError
from spectrace.spectral import GRID_NM, Spectrum, xyz_to_xy
from spectrace.spectral.display import CHANNELS, Display
from spectrace.spectral.fluorophores import load_fluorophore
from spectrace.spectral.observers import Observer, observer_cmfs, photometric_xyz

BACKLIGHTS = ("wled_yag", "qd", "ccfl")
FIT_RANGE_NM = (380.0, 780.0)
# The fit's weight on the primaries' xy against the spectra's residuals (each channel scaled to its peak): the
# spectra set the layers' shapes, the xy terms make the small tails that move a chromaticity count as much as the
# eye counts them.
XY_WEIGHT = 100.0
FIT_EVALUATIONS = 100
# Mercury's visible lines (NIST Atomic Spectra Database, Hg I, wavelengths in air), and the strongest lines of the
# tri-phosphor's terbium (LaPO4:Ce,Tb; 5D4 -> 7F6..3) and europium (Y2O3:Eu; 5D0 -> 7F1, 7F2, 7F4) emission
# (S. Shionoya, W. M. Yen, H. Yamamoto (eds.), Phosphor Handbook, 2nd ed., CRC Press 2006, the chapter on lamp
# phosphors). The blue phosphor BaMgAl10O17:Eu2+ (BAM) is a band, peak 450 nm, FWHM about 50 nm (same source).
CCFL_LINES_NM = {
    "Hg 405": 404.7,
    "Hg 436": 435.8,
    "Hg 546": 546.1,
    "Hg 577/579": 578.0,
    "Tb 489": 489.0,
    "Tb 543": 543.0,
    "Tb 586": 586.0,
    "Tb 621": 621.0,
    "Eu 593": 593.0,
    "Eu 611": 611.0,
    "Eu 627": 627.0,
    "Eu 707": 707.0,
}
BAM_PEAK_NM, BAM_FWHM_NM = 450.0, 50.0


def parallel_polarisers_transmittance(k1: float = 0.9, k2: float = 0.001) -> float:
    """The fraction of unpolarised light two ideal-axis-aligned parallel polarisers pass, each with principal
    transmittances k1 (along its axis) and k2 (across): (k1² + k2²)/2 (Malus's law for partial polarisers)."""
    return (k1 * k1 + k2 * k2) / 2.0


DEFAULT_POLARISER_TRANSMITTANCE = parallel_polarisers_transmittance()


def _gaussian(nm: np.ndarray, peak_nm: float, fwhm_nm: float) -> np.ndarray:
    return np.exp(-4.0 * math.log(2.0) * ((nm - peak_nm) / fwhm_nm) ** 2)


def _rise(nm: np.ndarray, edge_nm: float, width_nm: float) -> np.ndarray:
    return 0.5 * (1.0 + np.tanh((nm - edge_nm) / (2.0 * width_nm)))


@cache
def _converter_emission(name: str) -> tuple[np.ndarray, float]:
    """(grid samples of the emission in photons per nm, its peak wavelength)."""
    values = load_fluorophore(name).emission.values
    return values, float(GRID_NM[np.argmax(values)])


def converter_energy(name: str, shift_nm: float = 0.0, width_scale: float = 1.0) -> np.ndarray:
    """A phosphor's or quantum dots' emission as energy per nm (peak 1), moved by `shift_nm` and widened by
    `width_scale` about its peak."""
    photons, peak = _converter_emission(name)
    source_nm = peak + (GRID_NM - peak - shift_nm) / width_scale
    energy = np.interp(source_nm, GRID_NM, photons, left=0.0, right=0.0) / GRID_NM
    return energy / energy.max()


@dataclass(frozen=True)
class Backlight:
    """`kind` in BACKLIGHTS; `led` = (peak nm, FWHM nm) of the blue LED (unused by `ccfl`); `converters`: per
    converter name, (weight relative to the LED's peak, shift nm, width scale); `lines`: the CCFL's line and band
    weights (names of CCFL_LINES_NM and "BAM"), `line_fwhm_nm` their width as the spectrometer saw them."""

    kind: str
    led: tuple[float, float] = (450.0, 20.0)
    converters: dict[str, tuple[float, float, float]] = field(default_factory=dict)
    lines: dict[str, float] = field(default_factory=dict)
    line_fwhm_nm: float = 4.0

    def spectrum(self) -> np.ndarray:
        """Grid samples of the backlight's spectral radiance, relative (the LED's peak, or the sum's peak, near 1)."""
        if self.kind == "ccfl":
            values = self.lines.get("BAM", 0.0) * _gaussian(GRID_NM, BAM_PEAK_NM, BAM_FWHM_NM)
            for name, peak in CCFL_LINES_NM.items():
                values = values + self.lines.get(name, 0.0) * _gaussian(GRID_NM, peak, self.line_fwhm_nm)
            return values
        values = _gaussian(GRID_NM, *self.led)
        for name, (weight, shift, scale) in self.converters.items():
            values = values + weight * converter_energy(name, shift, scale)
        return values

    def describe(self) -> str:
        if self.kind == "ccfl":
            return f"CCFL: Hg lines + Tb/Eu lines + BAM band, lines {self.line_fwhm_nm:.1f} nm wide as measured"
        parts = [f"blue LED {self.led[0]:.0f} nm (FWHM {self.led[1]:.0f} nm)"]
        parts += [
            f"{name} ×{weight:.2f} (shift {shift:+.0f} nm, width ×{scale:.2f})"
            for name, (weight, shift, scale) in self.converters.items()
        ]
        return " + ".join(parts)


@dataclass(frozen=True)
class ColourFilter:
    """A band-pass: floor + (1 - floor) · rise(λ; lo) · (1 - rise(λ; hi)); logistic edges, widths in nm."""

    lo_nm: float
    lo_width_nm: float
    hi_nm: float
    hi_width_nm: float
    floor: float = 0.0

    def transmittance(self) -> np.ndarray:
        band = _rise(GRID_NM, self.lo_nm, self.lo_width_nm) * (1.0 - _rise(GRID_NM, self.hi_nm, self.hi_width_nm))
        return self.floor + (1.0 - self.floor) * band

    def narrowed(self, nm: float) -> ColourFilter:
        """Both edges moved inward by `nm` (an open side, beyond the visible, stays where it is)."""
        lo = self.lo_nm + nm if self.lo_nm > FIT_RANGE_NM[0] else self.lo_nm
        hi = self.hi_nm - nm if self.hi_nm < FIT_RANGE_NM[1] else self.hi_nm
        return replace(self, lo_nm=lo, hi_nm=hi, floor=self.floor / 2)


@dataclass(frozen=True)
class LayerModel:
    name: str
    backlight: Backlight
    filters: tuple[ColourFilter, ColourFilter, ColourFilter]
    amplitudes: tuple[float, float, float]  # s · T_pol · each filter's peak: only the product is measured
    polariser_transmittance: float = DEFAULT_POLARISER_TRANSMITTANCE

    def primaries_values(self) -> np.ndarray:
        """(3, grid) spectral radiance of red, green, blue at full drive, on the fitted display's scale."""
        backlight = self.backlight.spectrum()
        return np.stack(
            [amplitude * backlight * f.transmittance() for amplitude, f in zip(self.amplitudes, self.filters)]
        )

    def display(self, name: str | None = None, technology: str | None = None) -> Display:
        red, green, blue = (
            Spectrum(values, name=f"{name or self.name}:{channel}", source="layer model")
            for channel, values in zip(CHANNELS, self.primaries_values())
        )
        return Display(
            name=name or self.name,
            technology=technology or f"LCD layer model ({self.backlight.kind})",
            primaries=(red, green, blue),
            absolute=False,
            radiance_scale="relative",
            source=f"layer model: {self.backlight.describe()}",
        )

    def with_backlight(self, backlight: Backlight, name: str) -> LayerModel:
        return replace(self, backlight=backlight, name=name)

    def with_filters(self, filters: tuple[ColourFilter, ColourFilter, ColourFilter], name: str) -> LayerModel:
        return replace(self, filters=filters, name=name)


# ---------------------------------------------------------------- fitting


def _unpack_filters(values: np.ndarray) -> tuple[ColourFilter, ColourFilter, ColourFilter]:
    """Red: a high-pass (hi beyond the visible); green: a band-pass; blue: a low-pass (lo below the visible)."""
    red_lo, red_w, green_lo, green_lw, green_hi, green_hw, blue_hi, blue_w, floor_r, floor_g, floor_b = values
    return (
        ColourFilter(red_lo, red_w, 900.0, 10.0, floor_r),
        ColourFilter(green_lo, green_lw, green_hi, green_hw, floor_g),
        ColourFilter(300.0, 10.0, blue_hi, blue_w, floor_b),
    )


# start, low, high of each filter parameter (nm; floors dimensionless)
_FILTER_START = (
    (585, 540, 660),  # red: rising edge
    (10, 2, 40),  # its width
    (480, 440, 530),  # green: rising edge
    (10, 2, 40),
    (590, 550, 640),  # green: falling edge
    (10, 2, 40),
    (510, 460, 560),  # blue: falling edge
    (12, 2, 40),
    (0.01, 0.0, 0.3),  # floors: red, green, blue
    (0.01, 0.0, 0.3),
    (0.01, 0.0, 0.3),
)


def _filter_start_bounds() -> tuple[list[float], list[float], list[float]]:
    start, low, high = zip(*_FILTER_START)
    return list(start), list(low), list(high)


def _backlight_parameters(kind: str) -> tuple[list[str], list[float], list[float], list[float]]:
    """Names, starts and bounds of a backlight's free parameters."""
    if kind == "wled_yag":
        return (
            ["led_peak", "led_fwhm", "yag_weight", "yag_shift", "yag_scale"],
            [450, 20, 0.4, 0, 1.0],
            [435, 10, 0.01, -40, 0.6],
            [465, 40, 20, 40, 1.8],
        )
    if kind == "qd":
        return (
            [
                "led_peak",
                "led_fwhm",
                "green_weight",
                "green_shift",
                "green_scale",
                "red_weight",
                "red_shift",
                "red_scale",
            ],
            [450, 20, 0.5, 0, 1.0, 0.5, 0, 1.0],
            [435, 10, 0.01, -40, 0.5, 0.01, -40, 0.5],
            [465, 40, 20, 40, 2.5, 20, 40, 2.5],
        )
    if kind == "ccfl":
        names = ["line_fwhm", "BAM", *CCFL_LINES_NM]
        return (
            names,
            [4.0, 0.3, *[0.3] * len(CCFL_LINES_NM)],
            [0.5, 0, *[0] * len(CCFL_LINES_NM)],
            [
                20,
                5,
                *[5] * len(CCFL_LINES_NM),
            ],
        )
    raise SpectraceError(f"unknown backlight '{kind}' (one of {', '.join(BACKLIGHTS)})", where="--backlight")


QD_GREEN, QD_RED, YAG = "cdse_qd_green", "cdse_qd_red", "yag_ce"


def _backlight_from(kind: str, values: np.ndarray) -> Backlight:
    if kind == "wled_yag":
        peak, fwhm, weight, shift, scale = values
        return Backlight(kind, (peak, fwhm), {YAG: (weight, shift, scale)})
    if kind == "qd":
        peak, fwhm, gw, gs, gsc, rw, rs, rsc = values
        return Backlight(kind, (peak, fwhm), {QD_GREEN: (gw, gs, gsc), QD_RED: (rw, rs, rsc)})
    names = ["BAM", *CCFL_LINES_NM]
    return Backlight(kind, lines=dict(zip(names, values[1:])), line_fwhm_nm=float(values[0]))


@dataclass(frozen=True)
class FitResult:
    measured: Display
    model: LayerModel
    rms_residual: float  # of the spectra, each channel scaled to its peak

    def measured_xy(self) -> np.ndarray:
        return self.measured.primaries_xy()

    def model_xy(self) -> np.ndarray:
        return xyz_to_xy(photometric_xyz(self.model.primaries_values()))

    def white_xy(self) -> tuple[np.ndarray, np.ndarray]:
        """(measured, modelled) xy of white, R+G+B at full drive."""
        return self.measured.white_xy(), xyz_to_xy(photometric_xyz(self.model.primaries_values().sum(axis=0)))

    def delta_xy(self) -> np.ndarray:
        """(3,) Euclidean xy distance of each modelled primary from the measured one."""
        return np.linalg.norm(self.model_xy() - self.measured_xy(), axis=1)

    def to_json(self) -> dict:
        return {
            "display": self.measured.name,
            "backlight": self.model.backlight.kind,
            "backlight_description": self.model.backlight.describe(),
            "polariser_transmittance": self.model.polariser_transmittance,
            "rms_spectral_residual": self.rms_residual,
            "primaries": {
                channel: {"measured_xy": m.tolist(), "model_xy": f.tolist(), "delta_xy": float(d)}
                for channel, m, f, d in zip(CHANNELS, self.measured_xy(), self.model_xy(), self.delta_xy())
            },
            "white": {
                "measured_xy": self.white_xy()[0].tolist(),
                "model_xy": self.white_xy()[1].tolist(),
                "delta_xy": float(np.linalg.norm(self.white_xy()[1] - self.white_xy()[0])),
            },
            "filters": {
                channel: {
                    "lo_nm": f.lo_nm,
                    "lo_width_nm": f.lo_width_nm,
                    "hi_nm": f.hi_nm,
                    "hi_width_nm": f.hi_width_nm,
                    "floor": f.floor,
                }
                for channel, f in zip(CHANNELS, self.model.filters)
            },
        }


def default_backlight(display: Display) -> str:
    """The backlight kind a display's technology names: CCFL, white LED, or else narrow-band (QD-like)."""
    text = f"{display.name} {display.technology}".casefold()
    if "ccfl" in text:
        return "ccfl"
    if "wled" in text or "white-led" in text or "white led" in text:
        return "wled_yag"
    return "qd"


def fit_layer_model(display: Display, backlight: str | None = None) -> FitResult:
    """The layer model closest to the display's measured primaries (see the module docstring)."""
    kind = backlight or default_backlight(display)
    names, b_start, b_low, b_high = _backlight_parameters(kind)
    f_start, f_low, f_high = _filter_start_bounds()
    lowest, highest = FIT_RANGE_NM
    inside = (lowest <= GRID_NM) & (highest >= GRID_NM)
    measured = display.primaries_values[:, inside]
    peak = float(measured.max())
    target = measured / peak
    count = len(names)
    cmfs = observer_cmfs(Observer.CIE_1931_2)[inside]
    measured_xyz = measured @ cmfs
    target_xy = xyz_to_xy(np.vstack([measured_xyz, measured_xyz.sum(axis=0)]))  # the primaries' and white's

    def model_primaries(parameters: np.ndarray) -> np.ndarray:
        light = _backlight_from(kind, parameters[:count]).spectrum()[inside]
        filters = _unpack_filters(parameters[count:])
        return np.stack([light * f.transmittance()[inside] for f in filters])

    def residuals(parameters: np.ndarray) -> np.ndarray:
        shapes = model_primaries(parameters)
        # the best common amplitude in closed form (linear least squares), so it is not a fitted parameter
        scale = np.sum(shapes * target) / max(float(np.sum(shapes**2)), 1e-300)
        xyz = shapes @ cmfs
        xy = xyz_to_xy(np.vstack([xyz, xyz.sum(axis=0)]))
        return np.concatenate([(scale * shapes - target).ravel(), XY_WEIGHT * (xy - target_xy).ravel()])

    start = np.array([*b_start, *f_start], dtype=np.float64)
    low = np.array([*b_low, *f_low], dtype=np.float64)
    high = np.array([*b_high, *f_high], dtype=np.float64)
    # tolerances at which the primaries' xy no longer move in the 4th decimal; tighter ones cost 5-10x the time
    solution = least_squares(
        residuals, start, bounds=(low, high), x_scale="jac", ftol=1e-6, xtol=1e-6, max_nfev=FIT_EVALUATIONS
    )
    shapes = model_primaries(solution.x)
    scale = float(np.sum(shapes * target) / np.sum(shapes**2)) * peak
    model = LayerModel(
        name=f"{display.name} (layer model)",
        backlight=_backlight_from(kind, solution.x[:count]),
        filters=_unpack_filters(solution.x[count:]),
        amplitudes=(scale, scale, scale),
    )
    rms = float(np.sqrt(np.mean(solution.fun**2)))
    return FitResult(measured=display, model=model, rms_residual=rms)
