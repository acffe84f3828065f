"""Figures: spectra on a wavelength axis, and false-colour luminance maps of rendered images with a scale bar.

Luminance. The film's Y is ∫ L(λ) ȳ(λ) dλ / ∫ ȳ dλ (CIE 1931 2°; `spectrace.spectral.colorimetry`), so for
radiance L in W/(m² sr nm) the photometric luminance is

    L_v = K_m ∫ L ȳ dλ = K_m · ∫ȳ dλ · Y_film,   K_m = 683 lm/W (CIE 15:2004), ∫ȳ dλ ≈ 106.857 nm,

in cd/m² (= lm/(m² sr)). Exposure does not enter: it only scales the RGB outputs.
"""

from __future__ import annotations

import re
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Literal

import numpy as np

from spectrace.errors import SpectraceError
from spectrace.spectral.colorimetry import (
    CIE_1931_CMFS,
    CIE_Y_INTEGRAL,
    spectrum_to_xyz,
    srgb_encode,
    xyz_to_linear_srgb,
)
from spectrace.spectral.grid import GRID_NM
from spectrace.spectral.illuminants import cie_illuminant
from spectrace.spectral.spectrum import Spectrum

LUMINOUS_EFFICACY_LM_PER_W = 683.0  # K_m for photopic vision (CIE 15:2004; the SI definition of the candela)
FALSE_COLOUR_MAP = "inferno"  # perceptually uniform and monotonic in lightness, so it reads in grey print too
LOG_RANGE_DECADES = 4.0  # default lower end of a log map: this many decades below its upper end
_UPPER_PERCENTILE = 99.9  # the default upper end ignores the brightest 0.1 % (fireflies, the light itself)
_LINE_STYLES = ("-", "--", "-.", ":")

Scale = Literal["log", "linear"]


def _pyplot():
    from spectrace.plot_extra import pyplot

    return pyplot("figures")


# ---------------------------------------------------------------- spectra


def _line_colour(spectrum: Spectrum) -> tuple[float, float, float]:
    """The spectrum's own colour for its line: its colour as light, or, for values within [0, 1], as a
    reflectance under D65; near-neutral colours get dark grey so the line stays visible on white."""
    values = spectrum.values
    if values.max() <= 1.0:
        values = values * cie_illuminant("D65").values
    rgb = np.clip(xyz_to_linear_srgb(spectrum_to_xyz(values)), 0.0, None)
    if not rgb.max() > 0:
        return (0.35, 0.35, 0.35)
    encoded = srgb_encode(rgb / rgb.max())
    if encoded.max() - encoded.min() < 0.15:
        return (0.35, 0.35, 0.35)
    r, g, b = 0.85 * encoded
    return float(r), float(g), float(b)


def _visible_strip(axes) -> None:
    """The colour of monochromatic light at each wavelength (sRGB, brightness normalised), as an axis legend."""
    rgb = np.clip(xyz_to_linear_srgb(CIE_1931_CMFS), 0.0, None)
    rgb = rgb / np.maximum(rgb.max(axis=1, keepdims=True), 1e-12) * np.clip(CIE_1931_CMFS[:, 1:2] / 0.1, 0, 1)
    axes.imshow(srgb_encode(rgb)[None, :, :], extent=(GRID_NM[0], GRID_NM[-1], 0, 1), aspect="auto")
    axes.set_yticks([])
    axes.set_xlabel("wavelength (nm)")


def text_problem(text: str) -> str | None:
    """Why matplotlib cannot typeset `text` (text between two $ signs is math, which may not parse), or None."""
    from spectrace.plot_extra import require_matplotlib

    require_matplotlib("--title")
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    figure = Figure(figsize=(1, 1))
    FigureCanvasAgg(figure)
    figure.text(0, 0, text)
    try:
        figure.canvas.draw()
    except ValueError as error:
        lines = [line.strip() for line in str(error).splitlines() if line.strip()]
        reason = re.sub(r"Expected \{.*\}, found", "Expected ..., found", lines[-1]) if lines else "math error"
        return f"cannot typeset {text!r}: {reason} (text between $ signs is math; write \\$ for a dollar sign)"
    return None


def plot_spectra(
    spectra: Mapping[str, Spectrum] | Sequence[Spectrum],
    path: str | Path | None = None,
    normalise: bool = False,
    title: str | None = None,
    y_label: str | None = None,
):
    """Draw spectra (by label, or a list labelled by their names) on one wavelength axis; returns the matplotlib
    Figure (a notebook shows it), also written to `path` (.png, .pdf, .svg) when given. normalise=True divides
    each by its peak, to compare shapes of different units. See `spectra_figure` for when ratios get an axis of
    their own."""
    figure = spectra_figure(spectra, normalise, title, y_label)
    if path is not None:
        _write_figure(figure, Path(path))
    return figure


# Spectra whose peak is this many times a ratio's (within [0, 1]) would draw it as a flat line on a shared axis.
_SECOND_AXIS_RATIO = 2.0


def spectra_figure(
    spectra: Mapping[str, Spectrum] | Sequence[Spectrum],
    normalise: bool = False,
    title: str | None = None,
    y_label: str | None = None,
):
    """The matplotlib Figure of `plot_spectra`. Without `normalise`, spectra whose values all lie in [0, 1]
    (reflectances, transmittances) drawn with others that peak more than twice as high (a light's radiance) go on a
    second y axis on the right, from 0 to 1, so they do not lie flat along the bottom; the legend marks them."""
    items = list(spectra.items()) if isinstance(spectra, Mapping) else [(s.name, s) for s in spectra]
    if not items:
        raise SpectraceError("no spectra to plot")
    from spectrace.plot_extra import require_matplotlib

    require_matplotlib("figures")
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    # A Figure of its own, not pyplot's: pyplot would keep every figure returned to a notebook open, and its
    # backend is the notebook's to choose.
    figure = Figure(figsize=(7.5, 4.8))
    FigureCanvasAgg(figure)
    axes, strip = figure.subplots(2, 1, sharex=True, gridspec_kw={"height_ratios": [14, 1], "hspace": 0.06})
    ratios = {label for label, s in items if s.values.min() >= 0 and s.values.max() <= 1}
    peak = max((s.values.max() for label, s in items if label not in ratios), default=0.0)
    second = None
    if not normalise and ratios and peak > _SECOND_AXIS_RATIO * max(_peak_of(items, ratios), 1e-12):
        second = axes.twinx()
        second.set_ylim(0, 1.05)
        second.set_ylabel("reflectance, transmittance (right axis, 0–1)")
    lines = []
    for index, (label, spectrum) in enumerate(items):
        values = spectrum.values
        if normalise and values.max() > 0:
            values = values / values.max()
        target = second if second is not None and label in ratios else axes
        on_right = target is not axes
        (line,) = target.plot(
            GRID_NM,
            values,
            color=_line_colour(spectrum),
            linestyle=_LINE_STYLES[index % len(_LINE_STYLES)],
            linewidth=1.6,
            label=f"{label} (right axis)" if on_right else label,
        )
        lines.append(line)
    axes.set_xlim(GRID_NM[0], GRID_NM[-1])
    axes.set_ylim(bottom=0)
    if y_label:
        axes.set_ylabel(y_label)
    elif normalise:
        axes.set_ylabel("value / peak")
    else:
        axes.set_ylabel("value (in the spectrum's own unit)" + (", left axis" if second is not None else ""))
    axes.grid(alpha=0.3)
    axes.legend(handles=lines, fontsize=8, loc="best")
    if title:
        axes.set_title(title)
    _visible_strip(strip)
    return figure


def _peak_of(items: Sequence[tuple[str, Spectrum]], labels: set[str]) -> float:
    return max((s.values.max() for label, s in items if label in labels), default=0.0)


# ---------------------------------------------------------------- false colour


def luminance_cd_m2(xyz_film: np.ndarray) -> np.ndarray:
    """Photometric luminance (cd/m²) of film XYZ on the last axis: 683 lm/W · ∫ȳ dλ · Y."""
    return LUMINOUS_EFFICACY_LM_PER_W * CIE_Y_INTEGRAL * np.asarray(xyz_film, np.float64)[..., 1]


def default_limits(values: np.ndarray, scale: Scale) -> tuple[float, float]:
    """Colour-scale range: up to the 99.9th percentile; from 0 (linear) or LOG_RANGE_DECADES below the top (log),
    but no lower than the darkest lit pixel."""
    finite = values[np.isfinite(values)]
    positive = finite[finite > 0]
    if positive.size == 0:
        return (0.0, 1.0) if scale == "linear" else (1e-3, 1.0)
    top = float(np.percentile(positive, _UPPER_PERCENTILE))
    if scale == "linear":
        return 0.0, top
    return max(float(positive.min()), top / 10**LOG_RANGE_DECADES), top


def false_colour(values: np.ndarray, limits: tuple[float, float], scale: Scale = "log") -> np.ndarray:
    """(H, W, 4) RGBA: `values` mapped linearly, or by log10, from `limits` onto the colour map; values outside
    the limits take the end colours, zero or negative values on a log scale black."""
    import matplotlib

    low, high = limits
    values = np.asarray(values, np.float64)
    if scale == "log":
        with np.errstate(divide="ignore", invalid="ignore"):
            position = (np.log10(values) - np.log10(low)) / (np.log10(high) - np.log10(low))
    else:
        position = (values - low) / (high - low)
    rgba = matplotlib.colormaps[FALSE_COLOUR_MAP](np.clip(np.nan_to_num(position, nan=0.0, neginf=0.0), 0, 1))
    if scale == "log":
        rgba[~(values > 0)] = (0.0, 0.0, 0.0, 1.0)
    return rgba


def plot_false_colour_luminance(
    xyz_film: np.ndarray,
    path: str | Path,
    scale: Scale = "log",
    limits_cd_m2: tuple[float, float] | None = None,
    title: str | None = None,
) -> tuple[float, float]:
    """Write a false-colour map of the luminance (cd/m²) of film XYZ, one cell per pixel, with a scale bar in
    cd/m², to an image file; returns the (low, high) range of the scale."""
    if scale not in ("log", "linear"):
        raise SpectraceError(f"unknown scale '{scale}' (use log or linear)", where="--false-color-scale")
    luminance = luminance_cd_m2(xyz_film)
    title = title or f"luminance, {scale} scale; mean {np.nanmean(luminance):.4g} cd/m²"
    return plot_false_colour_map(luminance, path, "luminance (cd/m²)", scale, limits_cd_m2, title)


def plot_delta_e_map(delta_e: np.ndarray, path: str | Path, title: str) -> tuple[float, float]:
    """Write a per-pixel colour difference (ΔE) as a false-colour map with a scale bar, on a linear scale from 0 to
    the 99.9th percentile, and at least to 1 (about a just-noticeable difference), so that a map of differences
    too small to see does not fill the colour map; returns the scale's range."""
    finite = np.asarray(delta_e, np.float64)[np.isfinite(delta_e)]
    top = max(float(np.percentile(finite, _UPPER_PERCENTILE)) if finite.size else 0.0, 1.0)
    return plot_false_colour_map(delta_e, path, "CIEDE2000 ΔE₀₀", "linear", (0.0, top), title)


def plot_false_colour_map(
    values: np.ndarray,
    path: str | Path,
    label: str,
    scale: Scale = "log",
    limits: tuple[float, float] | None = None,
    title: str | None = None,
) -> tuple[float, float]:
    """Write (H, W) values as a false-colour map, one cell per pixel, with a scale bar labelled `label`; returns
    the (low, high) range of the scale (by default `default_limits`)."""
    values = np.asarray(values, np.float64)
    low, high = limits or default_limits(values, scale)
    if not (np.isfinite(low) and np.isfinite(high) and high > low and (scale == "linear" or low > 0)):
        raise SpectraceError(f"bad range {low:g}..{high:g} for a {scale} scale of {label}")
    import matplotlib

    pyplot = _pyplot()
    height, width = values.shape
    inches = 6.0 / max(height, width)
    figure, axes = pyplot.subplots(figsize=(max(width * inches, 3.0) + 1.8, max(height * inches, 3.0) + 0.8))
    axes.imshow(false_colour(values, (low, high), scale), interpolation="nearest")
    axes.set_axis_off()
    norm = matplotlib.colors.LogNorm(low, high) if scale == "log" else matplotlib.colors.Normalize(low, high)
    extend = "max" if scale == "linear" and low == 0 and not np.nanmin(values) < 0 else "both"
    mappable = matplotlib.cm.ScalarMappable(norm=norm, cmap=FALSE_COLOUR_MAP)
    bar = figure.colorbar(mappable, ax=axes, fraction=0.046, pad=0.04, extend=extend)
    bar.set_label(label)
    if title:
        axes.set_title(title, fontsize=9)
    _save(figure, path)
    return float(low), float(high)


def _write_figure(figure, path: Path) -> None:
    """`figure` written to `path` (.png, .pdf or .svg), all or nothing."""
    from spectrace.io.atomic import write_atomically

    if path.suffix.lower() not in (".png", ".pdf", ".svg"):
        raise SpectraceError(f"unknown figure format '{path.suffix}' (use .png, .pdf or .svg)", where=str(path))
    try:
        write_atomically(path, lambda temp: figure.savefig(temp, dpi=150, bbox_inches="tight"))
    except OSError as error:
        raise SpectraceError(f"cannot write the figure ({error.strerror or error})", where=str(path)) from None


def _save(figure, path: str | Path) -> Path:
    path = Path(path)
    try:
        _write_figure(figure, path)
    finally:
        figure.canvas.figure.clf()
        _pyplot().close(figure)
    return path
