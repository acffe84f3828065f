"""Vary one layer of a fitted display model and see what changes: the gamut (triangle area in CIE 1931 xy and in
CIE 1976 u'v'), and metamerism against the fitted model (a light grey matched for the CIE 1931 observer: how far
apart the 1964 10° observer sees the two screens, and how differently they light a ColorChecker).

Variants: the backlight swapped for a blue LED with the published YAG:Ce phosphor, or with the published CdSe
quantum dots (green and red films), each converter's amount chosen to bring white (R+G+B through the model's
filters) nearest the fitted model's white; and the model's filters narrowed by 10 nm at each edge. Every variant is
then white balanced as a panel is calibrated: each channel's full drive scaled down (gains in (0, 1], the largest 1)
so that white has the fitted model's white chromaticity exactly.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from scipy.optimize import least_squares

from spectrace.displays.layers import QD_GREEN, QD_RED, YAG, Backlight, FitResult, LayerModel
from spectrace.displays.match import match_colour
from spectrace.displays.metamerism import patch_metamerism
from spectrace.spectral import xyz_to_xy
from spectrace.spectral.display import Display
from spectrace.spectral.observers import Observer, photometric_xyz

GREY = (0.8, 0.8, 0.8)
NARROWED_NM = 10.0


def triangle_area(points: np.ndarray) -> float:
    """Area of the triangle of three 2-D points (shoelace formula)."""
    (ax, ay), (bx, by), (cx, cy) = np.asarray(points, dtype=np.float64)
    return float(abs((bx - ax) * (cy - ay) - (cx - ax) * (by - ay)) / 2.0)


def xy_to_uv_prime(xy: np.ndarray) -> np.ndarray:
    """CIE 1976 UCS u', v' of CIE 1931 x, y (CIE 15:2004, eq. 8.9)."""
    x, y = np.moveaxis(np.asarray(xy, dtype=np.float64), -1, 0)
    denominator = -2.0 * x + 12.0 * y + 3.0
    return np.stack([4.0 * x / denominator, 9.0 * y / denominator], axis=-1)


@dataclass(frozen=True)
class Variant:
    name: str
    description: str
    display: Display
    primaries_xy: np.ndarray  # (3, 2)
    white_xy: np.ndarray
    gamut_xy: float
    gamut_uv: float
    # white's luminance over the backlight's through open cells (each subpixel a third of the area, the brightest
    # channel's filter peak 1): what the filters and the white balance keep
    white_efficiency: float
    grey_delta_e_1964: float  # the grey matched for 1931 2°, seen by the 1964 10° observer
    colorchecker_mean_delta_e: float  # the ColorChecker lit by the model vs by the variant showing the match
    colorchecker_max_delta_e: float

    def to_json(self) -> dict:
        return {
            "name": self.name,
            "description": self.description,
            "primaries_xy": self.primaries_xy.tolist(),
            "white_xy": self.white_xy.tolist(),
            "gamut_area_xy": self.gamut_xy,
            "gamut_area_uv": self.gamut_uv,
            "white_efficiency": self.white_efficiency,
            "grey_delta_e_2000_cie1964_10": self.grey_delta_e_1964,
            "colorchecker_mean_delta_e_2000": self.colorchecker_mean_delta_e,
            "colorchecker_max_delta_e_2000": self.colorchecker_max_delta_e,
        }


def _white_balanced(model: LayerModel, converters: dict[str, tuple[float, float, float]], name: str) -> LayerModel:
    """The model with a blue LED (the fitted one, or 450 nm / 20 nm for a CCFL model) and these converters, their
    weights chosen so that white has the model's white xy (least squares on xy; exact when it can be reached)."""
    led = model.backlight.led if model.backlight.kind != "ccfl" else (450.0, 20.0)
    target = xyz_to_xy(photometric_xyz(model.primaries_values().sum(axis=0)))
    names = list(converters)

    def candidate(weights: np.ndarray) -> LayerModel:
        chosen = {n: (float(w), *converters[n][1:]) for n, w in zip(names, weights)}
        return model.with_backlight(Backlight("qd" if QD_GREEN in chosen else "wled_yag", led, chosen), name)

    def residual(weights: np.ndarray) -> np.ndarray:
        return xyz_to_xy(photometric_xyz(candidate(weights).primaries_values().sum(axis=0))) - target

    start = np.array([converters[n][0] for n in names])
    solution = least_squares(residual, start, bounds=(1e-4, 100.0), xtol=1e-10, ftol=1e-12)
    return candidate(solution.x)


def white_balanced(model: LayerModel, white_xy: np.ndarray) -> LayerModel:
    """The model with each channel's amplitude scaled by a gain in (0, 1] (the largest 1) so that white has
    `white_xy`; as it is when the primaries cannot mix that white with positive gains."""
    matrix = photometric_xyz(model.primaries_values()).T
    x, y = white_xy
    gains = np.linalg.solve(matrix, np.array([x / y, 1.0, (1.0 - x - y) / y]))
    if not np.all(gains > 0):
        return model
    gains = gains / gains.max()
    amplitudes = tuple(float(a * g) for a, g in zip(model.amplitudes, gains))
    return replace(model, amplitudes=amplitudes)  # type: ignore[arg-type]


def _variant(model: LayerModel, fitted: LayerModel, description: str) -> Variant:
    base = fitted.display()
    balanced = white_balanced(model, base.white_xy())
    display = balanced.display(technology=description)
    xy = display.primaries_xy()
    match = match_colour(base, GREY, display)
    metamerism = patch_metamerism(base, GREY, display)
    backlight_y = float(photometric_xyz(model.backlight.spectrum())[1])
    white_y = float(photometric_xyz(balanced.primaries_values().sum(axis=0))[1])
    return Variant(
        name=model.name,
        description=description,
        display=display,
        primaries_xy=xy,
        white_xy=display.white_xy(),
        gamut_xy=triangle_area(xy),
        gamut_uv=triangle_area(xy_to_uv_prime(xy)),
        white_efficiency=white_y / (3.0 * max(model.amplitudes) * backlight_y),
        grey_delta_e_1964=float(match.delta_e_2000[Observer.CIE_1964_10]),
        colorchecker_mean_delta_e=metamerism.mean_delta_e,
        colorchecker_max_delta_e=metamerism.max_delta_e,
    )


def layer_variants(fit: FitResult) -> list[Variant]:
    """The fitted model itself, then one variant per changed layer (see the module docstring)."""
    fitted = fit.model
    yag = _white_balanced(fitted, {YAG: (0.5, 0.0, 1.0)}, "YAG:Ce phosphor backlight")
    qd = _white_balanced(fitted, {QD_GREEN: (0.5, 0.0, 1.0), QD_RED: (0.5, 0.0, 1.0)}, "CdSe QD film backlight")
    narrow = fitted.with_filters(
        tuple(f.narrowed(NARROWED_NM) for f in fitted.filters),  # type: ignore[arg-type]
        f"filters narrowed {NARROWED_NM:g} nm",
    )
    return [
        _variant(fitted, fitted, f"fitted: {fitted.backlight.describe()}"),
        _variant(yag, fitted, "blue LED + published YAG:Ce, model's filters, white balanced"),
        _variant(qd, fitted, "blue LED + published CdSe QD green/red, model's filters, white balanced"),
        _variant(narrow, fitted, f"fitted backlight, each filter edge moved {NARROWED_NM:g} nm inward"),
    ]
