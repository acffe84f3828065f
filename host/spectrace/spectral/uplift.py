"""RGB -> smooth spectra: Jakob & Hanika 2019, "A Low-Dimensional Function Space for Efficient
Spectral Upsampling" (Computer Graphics Forum 38(2)).

A reflectance is the sigmoid of a quadratic in the wavelength lambda (nm):

    R(lambda) = S(c0 lambda^2 + c1 lambda + c2),    S(x) = 1/2 + x / (2 sqrt(1 + x^2)),

so it is smooth and always inside [0, 1], and 3 coefficients describe it (the kernels evaluate it
from them, keeping textures small).

The fit is our own Gauss-Newton solve with Levenberg-Marquardt damping, as the paper does, written
against *this renderer's* colorimetry (trapezoid rule on the 1 nm grid, the lecture's XYZ -> sRGB
matrix, D65 from `illuminants.py`), on the CIELAB residual between the reflectance's colour under D65
and the target. It is not colour-science's `find_coefficients_Jakob2019`, which fits its own 5 nm
360..780 nm integration and stops at Delta E 0.024 after about 50 ms per colour; this solve runs to
Delta E 1e-6 in about 0.3 ms (at most ~20 ms for the hardest colours near the corners of the cube).
Internally the quadratic is in a dimensionless t = (lambda - 595 nm) / 235 nm, in [-1, 1] on the grid,
which keeps the normal equations well conditioned; the coefficients returned are for lambda in nm.
Started from the constant 0.5, the damped solve reaches every colour of the cube, corners included,
without the paper's continuation from grey. Evaluated in float32 in Horner form, ((c0 lambda + c1)
lambda + c2), the coefficients reproduce the float64 spectrum to ~2e-5.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from functools import cache, lru_cache
from numbers import Real

import numpy as np

from spectrace.errors import SpectraceError
from spectrace.spectral.colorimetry import CIE_1931_CMFS, XYZ_TO_LINEAR_SRGB
from spectrace.spectral.grid import GRID_MAX_NM, GRID_MIN_NM, GRID_NM, GRID_SIZE, TRAPEZOID_WEIGHTS_NM
from spectrace.spectral.illuminants import cie_illuminant, d65_normalised
from spectrace.spectral.spectrum import Extension, Spectrum

# |x| this large makes S(x) exactly 0 or 1 in float32 (1 + x^2 rounds to x^2) and 1 - 2.5e-13 in float64,
# while x^2 stays far from float32 overflow; used instead of +-inf, for which S is inf/inf = NaN.
SATURATED_SIGMOID_ARGUMENT = 1.0e6

# Cache key resolution for fits: rgb is rounded to this many decimals (a change below 5e-7 in linear
# sRGB is invisible and lets repeated texture colours share one fit).
RGB_CACHE_DECIMALS = 6

_CENTRE_NM = 0.5 * (GRID_MIN_NM + GRID_MAX_NM)
_HALF_SPAN_NM = 0.5 * (GRID_MAX_NM - GRID_MIN_NM)

_TARGET_DELTA_E = 1e-6  # CIELAB 1976 distance at which the fit stops (a just noticeable difference is ~2.3)
_MAX_ITERATIONS = 300
_INITIAL_DAMPING = 1e-3


def sigmoid(x: np.ndarray) -> np.ndarray:
    """S(x) = 1/2 + x / (2 sqrt(1 + x^2)): maps the real line onto (0, 1) without exp."""
    x = np.asarray(x, dtype=np.float64)
    return 0.5 + 0.5 * x / np.sqrt(1.0 + x * x)


def sigmoid_polynomial_spectrum(coefficients_nm: Sequence[float] | np.ndarray) -> np.ndarray:
    """S(c0 lambda^2 + c1 lambda + c2) at every grid wavelength (lambda in nm), in Horner form as a kernel would."""
    c0, c1, c2 = (float(c) for c in coefficients_nm)
    return sigmoid((c0 * GRID_NM + c1) * GRID_NM + c2)


def _dimensionless_to_nm(coefficients: np.ndarray) -> np.ndarray:
    # a t^2 + b t + c with t = (lambda - m) / h, expanded in powers of lambda.
    a, b, c = coefficients
    m, h = _CENTRE_NM, _HALF_SPAN_NM
    return np.array([a / h**2, b / h - 2 * a * m / h**2, a * m**2 / h**2 - b * m / h + c])


# ---------------------------------------------------------------- CIELAB under D65, our conventions


class _D65Colorimetry:
    """Precomputed weights so that a reflectance's XYZ under D65 is one (471) @ (471, 3) product."""

    def __init__(self) -> None:
        d65 = cie_illuminant("D65").values
        weights = d65[:, None] * CIE_1931_CMFS * TRAPEZOID_WEIGHTS_NM[:, None]
        self.xyz_weights = weights / weights[:, 1].sum()  # a perfect white reflector has Y = 1
        self.white_xyz = self.xyz_weights.sum(axis=0)
        # The exact inverse of the lecture's forward matrix, so that the round trip through it is exact.
        self.linear_srgb_to_xyz = np.linalg.inv(XYZ_TO_LINEAR_SRGB)
        t = (GRID_NM - _CENTRE_NM) / _HALF_SPAN_NM
        self.basis = np.stack([t * t, t, np.ones(GRID_SIZE)], axis=1)

    # CIE 1976 L*a*b*: Lab = A f(XYZ / XYZ_white) - (16, 0, 0), f = cube root with a linear toe.
    _LAB_MATRIX = np.array([[0.0, 116.0, 0.0], [500.0, -500.0, 0.0], [0.0, 200.0, -200.0]])
    _LAB_OFFSET = np.array([16.0, 0.0, 0.0])
    _DELTA = 6.0 / 29.0

    def _f(self, ratio: np.ndarray) -> np.ndarray:
        cube_root = np.cbrt(np.maximum(ratio, self._DELTA**3))
        return np.where(ratio > self._DELTA**3, cube_root, ratio / (3 * self._DELTA**2) + 4.0 / 29.0)

    def _f_derivative(self, ratio: np.ndarray) -> np.ndarray:
        cube_root = np.cbrt(np.maximum(ratio, self._DELTA**3))
        return np.where(ratio > self._DELTA**3, 1.0 / (3 * cube_root**2), 1.0 / (3 * self._DELTA**2))

    def lab_of_xyz(self, xyz: np.ndarray) -> np.ndarray:
        return self._LAB_MATRIX @ self._f(xyz / self.white_xyz) - self._LAB_OFFSET

    def lab_and_jacobian(self, coefficients: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Lab of S(basis @ coefficients) under D65 and d Lab / d coefficients (3 x 3)."""
        x = self.basis @ coefficients
        root = np.sqrt(1.0 + x * x)
        reflectance = 0.5 + 0.5 * x / root
        reflectance_slope = 0.5 / (root * root * root)  # S'(x)
        xyz = reflectance @ self.xyz_weights
        d_xyz = self.xyz_weights.T @ (reflectance_slope[:, None] * self.basis)
        d_lab_d_xyz = self._LAB_MATRIX * (self._f_derivative(xyz / self.white_xyz) / self.white_xyz)
        return self.lab_of_xyz(xyz), d_lab_d_xyz @ d_xyz


@cache
def _d65_colorimetry() -> _D65Colorimetry:
    return _D65Colorimetry()


def _fit_dimensionless(rgb: np.ndarray) -> np.ndarray:
    """Levenberg-Marquardt on the CIELAB residual, from the constant 0.5 (all coefficients 0)."""
    model = _d65_colorimetry()
    target_lab = model.lab_of_xyz(model.linear_srgb_to_xyz @ rgb)
    coefficients = np.zeros(3)
    lab, jacobian = model.lab_and_jacobian(coefficients)
    residual = lab - target_lab
    error = residual @ residual
    damping = _INITIAL_DAMPING
    for _ in range(_MAX_ITERATIONS):
        if error < _TARGET_DELTA_E**2:
            break
        normal = jacobian.T @ jacobian
        step = np.linalg.solve(normal + damping * np.diag(np.diag(normal)), -jacobian.T @ residual)
        trial = coefficients + step
        trial_lab, trial_jacobian = model.lab_and_jacobian(trial)
        trial_residual = trial_lab - target_lab
        trial_error = trial_residual @ trial_residual
        if trial_error < error:
            coefficients, jacobian, residual, error = trial, trial_jacobian, trial_residual, trial_error
            damping = max(damping * 0.1, 1e-12)
        else:
            damping *= 10.0
            if damping > 1e12:  # no descent direction left: the best fit the model allows
                break
    return coefficients


# ---------------------------------------------------------------- public API


def _validated_rgb(rgb: Sequence[float] | np.ndarray, what: str, where: str | None) -> np.ndarray:
    channels = list(rgb) if isinstance(rgb, (Sequence, np.ndarray)) and not isinstance(rgb, (str, bytes)) else None
    if channels is None or len(channels) != 3 or not all(_is_number(channel) for channel in channels):
        raise SpectraceError(f"{what} must be three numbers, got {rgb!r}", where=where)
    values = np.array([float(channel) for channel in channels])
    if not np.all(np.isfinite(values)):
        raise SpectraceError(f"{what} must be finite, got {tuple(values.tolist())}", where=where)
    return values


def _is_number(value: object) -> bool:
    return isinstance(value, (Real, np.number)) and not isinstance(value, (bool, np.bool_))


def _read_only(array: np.ndarray) -> np.ndarray:
    array.setflags(write=False)
    return array


@lru_cache(maxsize=65536)
def _uplift_rounded(rgb: tuple[float, float, float]) -> tuple[Spectrum, np.ndarray]:
    name = "rgb({:.4g}, {:.4g}, {:.4g}) reflectance".format(*rgb)
    source = "RGB uplift (Jakob & Hanika 2019)"
    if all(channel == 0.0 for channel in rgb):
        coefficients = np.array([0.0, 0.0, -SATURATED_SIGMOID_ARGUMENT])
        return Spectrum.constant(0.0, name=name, source=source, rgb_uplift=True), _read_only(coefficients)
    if all(channel == 1.0 for channel in rgb):
        coefficients = np.array([0.0, 0.0, SATURATED_SIGMOID_ARGUMENT])
        return Spectrum.constant(1.0, name=name, source=source, rgb_uplift=True), _read_only(coefficients)
    coefficients = _dimensionless_to_nm(_fit_dimensionless(np.array(rgb)))
    spectrum = Spectrum(
        sigmoid_polynomial_spectrum(coefficients), name=name, source=source, extension=_sigmoid_extension(coefficients)
    )
    return spectrum, _read_only(coefficients)


def _sigmoid_extension(coefficients_nm: np.ndarray) -> Extension:
    """The sigmoid polynomial beyond the grid: a smooth continuation with no physical meaning outside the visible,
    hence marked as an RGB uplift (used only when a scene asks for it)."""
    c0, c1, c2 = (float(c) for c in coefficients_nm)
    return Extension(-np.inf, np.inf, SigmoidPolynomialCurve(c0, c1, c2), rgb_uplift=True)


@dataclass(frozen=True)
class SigmoidPolynomialCurve:
    """nm -> S((c0 nm + c1) nm + c2), the curve of an uplifted reflectance (a plain dataclass, not a closure, so
    that scenes pickle)."""

    c0: float
    c1: float
    c2: float

    def __call__(self, nm: np.ndarray) -> np.ndarray:
        return sigmoid((self.c0 * nm + self.c1) * nm + self.c2)


def uplift_reflectance(rgb: Sequence[float] | np.ndarray, where: str | None = None) -> tuple[Spectrum, np.ndarray]:
    """Linear sRGB reflectance in [0, 1]^3 -> (smooth spectrum in [0, 1], coefficients (c0, c1, c2), lambda in nm).

    Under D65 (reflectance times D65, normalised by the integral of D65 * ybar, then the lecture's
    XYZ -> sRGB matrix) the spectrum reproduces `rgb` (to ~1e-8 across the cube). Black and white
    give the constants 0 and 1 with coefficients (0, 0, -+SATURATED_SIGMOID_ARGUMENT). Fits are cached
    on `rgb` rounded to RGB_CACHE_DECIMALS decimals. `where` (a scene key) is named in errors.
    """
    values = _validated_rgb(rgb, "an RGB reflectance", where)
    if np.any(values < 0.0) or np.any(values > 1.0):
        raise SpectraceError(
            f"an RGB reflectance must lie in [0, 1] (linear sRGB), got {tuple(values.tolist())}", where=where
        )
    rounded = tuple(float(channel) for channel in np.round(values, RGB_CACHE_DECIMALS))
    return _uplift_rounded(rounded)


def illuminant_coefficients(rgb: Sequence[float] | np.ndarray, where: str | None = None) -> tuple[np.ndarray, float]:
    """(coefficients in nm, multiplier) of an RGB emission: spectrum = multiplier * S(poly) * D65_normalised.

    pbrt-v4's RGBIlluminantSpectrum scheme: with m = max(rgb), the reflectance fitted to rgb / (2 m)
    (whose largest channel is 1/2, comfortably inside the reflectance gamut, instead of 1, on its edge)
    is scaled by 2 m. Black gives multiplier 0.
    """
    values = _validated_rgb(rgb, "an RGB emission", where)
    if np.any(values < 0.0):
        raise SpectraceError(f"an RGB emission must not be negative, got {tuple(values.tolist())}", where=where)
    largest = float(values.max())
    if largest == 0.0:
        return _read_only(np.array([0.0, 0.0, -SATURATED_SIGMOID_ARGUMENT])), 0.0
    _, coefficients = uplift_reflectance(values / (2.0 * largest), where=where)
    return coefficients, 2.0 * largest


def uplift_illuminant(rgb: Sequence[float] | np.ndarray, scale: float = 1.0, where: str | None = None) -> Spectrum:
    """Linear sRGB emission (any non-negative magnitude) -> emission spectrum, D65-shaped for greys.

    spectrum(lambda) = scale * 2 m * S(poly fitted to rgb / (2 m))(lambda) * D65_normalised(lambda), m = max(rgb),
    where D65_normalised has film Y = 1. Its film XYZ is therefore scale * 2 m * (XYZ of that reflectance
    under D65), i.e. linear sRGB = scale * rgb: (1, 1, 1) is D65 white with Y = 1, as in pbrt-v4 and
    Mitsuba 3, where RGB (1, 1, 1) emission is the colour space's white, not an equal-energy spectrum.
    """
    coefficients, multiplier = illuminant_coefficients(rgb, where=where)
    name = "rgb({:.4g}, {:.4g}, {:.4g}) emission".format(*(float(channel) for channel in rgb))
    if multiplier == 0.0:
        return Spectrum.constant(0.0, name=name, source="RGB uplift (Jakob & Hanika 2019)", rgb_uplift=True)
    shape = sigmoid_polynomial_spectrum(coefficients)
    d65 = d65_normalised()
    assert d65.extension is not None
    return Spectrum(
        float(scale) * multiplier * shape * d65.values,
        name=name,
        source="RGB illuminant uplift (Jakob & Hanika 2019, pbrt-v4 scheme)",
        extension=_sigmoid_extension(coefficients).times(d65.extension).scaled(float(scale) * multiplier),
    )


def uplift_unbounded(rgb: Sequence[float] | np.ndarray, where: str | None = None) -> Spectrum:
    """A smooth spectrum for a non-negative RGB triple that is no reflectance (an optical constant, any size): the
    reflectance uplift of rgb / max(rgb), times max(rgb). Its shape follows the triple's proportions; its values are
    not the channels' at any wavelength (an index of refraction has no colour of its own)."""
    values = _validated_rgb(rgb, "an RGB triple", where)
    if np.any(values < 0.0):
        raise SpectraceError(f"an RGB triple must not be negative here, got {tuple(values.tolist())}", where=where)
    largest = float(values.max())
    if largest == 0.0:
        return Spectrum.constant(0.0, source="RGB uplift (Jakob & Hanika 2019)", rgb_uplift=True)
    return uplift_reflectance(values / largest, where=where)[0] * largest


def normal_incidence_reflectance(eta, k):
    """Fresnel reflectance of a conductor of index η + ik at normal incidence, ((η−1)² + k²) / ((η+1)² + k²)."""
    eta, k = np.asarray(eta, np.float64), np.asarray(k, np.float64)
    return ((eta - 1.0) ** 2 + k**2) / ((eta + 1.0) ** 2 + k**2)


def conductor_from_rgb(
    eta_rgb: Sequence[float] | np.ndarray, k_rgb: Sequence[float] | np.ndarray, where: str | None = None
) -> tuple[Spectrum, Spectrum]:
    """Smooth spectra η(λ), k(λ) for a conductor given, as renderers working in RGB take it, by one η and one k per
    sRGB channel, such that its colour at normal incidence is the one an RGB renderer shows.

    An RGB renderer reflects R_c = ((η_c−1)² + k_c²) / ((η_c+1)² + k_c²) in channel c. Uplifting η and k each
    (`uplift_unbounded`) and taking the Fresnel term of the result is off by up to 7 % in a channel (gold's red),
    because the term is not linear in η and k. Instead: η(λ) is η's uplift; the reflectance R(λ) is the reflectance
    uplift of (R_r, R_g, R_b), whose colour under D65 is exactly that triple; and k(λ) is what makes the Fresnel
    term R at each wavelength, k² = (R (η+1)² − (η−1)²) / (1 − R). Where R is below the reflectance of a dielectric
    of index η, ((η−1)/(η+1))² (no metal: rare), k = 0 and the reflectance is that one."""
    eta_values = _validated_rgb(eta_rgb, "an RGB eta", where)
    k_values = _validated_rgb(k_rgb, "an RGB k", where)
    if not (np.all(eta_values > 0.0) and np.all(k_values >= 0.0)):
        raise SpectraceError(
            f"a conductor's eta must be > 0 and k >= 0, got eta {tuple(eta_values.tolist())}, "
            f"k {tuple(k_values.tolist())}",
            where=where,
        )
    eta = uplift_unbounded(eta_values, where).values.astype(np.float64)
    target = np.clip(normal_incidence_reflectance(eta_values, k_values), 0.0, 1.0)
    reflectance = np.minimum(uplift_reflectance(target, where)[0].values.astype(np.float64), 1.0 - 1e-7)
    k = np.sqrt(np.maximum(reflectance * (eta + 1.0) ** 2 - (eta - 1.0) ** 2, 0.0) / (1.0 - reflectance))
    source = "RGB conductor uplift (Jakob & Hanika 2019 reflectance, k solved from the Fresnel term)"
    return Spectrum(eta, name="eta from rgb", source=source), Spectrum(k, name="k from rgb", source=source)
