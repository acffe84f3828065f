"""One figure for a comparison: each display's primaries and the triple's emission, the gamuts and the triple's
chromaticity on the CIE 1931 diagram (colour-science's plotting), and the patches side by side."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from spectrace.displays.compare import Comparison
from spectrace.errors import SpectraceError
from spectrace.io.atomic import write_atomically
from spectrace.spectral import GRID_NM

CHANNEL_COLOURS = ("#d62728", "#2ca02c", "#1f77b4")
SPECTRA_COLUMNS = 3
MARKERS = "os^Dvp<>h*XP"


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")  # files only; never open a window
    import matplotlib.pyplot as pyplot

    return pyplot


def _plot_emissions(figure, grid_cell, comparison: Comparison) -> None:
    count = len(comparison.colours)
    rows = math.ceil(count / SPECTRA_COLUMNS)
    cells = grid_cell.subgridspec(rows, SPECTRA_COLUMNS, hspace=0.7, wspace=0.35)
    for index, colour_on_display in enumerate(comparison.colours):
        axes = figure.add_subplot(cells[index // SPECTRA_COLUMNS, index % SPECTRA_COLUMNS])
        display = colour_on_display.display
        for primary, line_colour in zip(display.primaries, CHANNEL_COLOURS):
            axes.plot(GRID_NM, primary.values, color=line_colour, linewidth=0.8)
        axes.plot(GRID_NM, display.emission_from_drive(colour_on_display.drive), color="black", linewidth=1.2)
        axes.set_title(display.name, fontsize=8)
        axes.set_xlim(380, 780)
        axes.tick_params(labelsize=6)
        axes.yaxis.get_offset_text().set_fontsize(6)
        if index % SPECTRA_COLUMNS == 0:
            axes.set_ylabel("W/(sr m² nm)", fontsize=6)


def _plot_chromaticities(figure, grid_cell, comparison: Comparison) -> None:
    from colour.plotting import plot_chromaticity_diagram_CIE1931

    axes = figure.add_subplot(grid_cell)
    plot_chromaticity_diagram_CIE1931(
        figure=figure,
        axes=axes,
        show=False,
        tight_layout=False,
        transparent_background=False,
    )
    axes.set_title("gamuts and the triple's chromaticity (CIE 1931)", pad=16)
    zoom = axes.inset_axes((0.52, 0.52, 0.46, 0.46))
    palette = _display_palette(len(comparison.colours))
    for index, colour_on_display in enumerate(comparison.colours):
        primaries_xy = colour_on_display.display.primaries_xy()
        closed = np.vstack([primaries_xy, primaries_xy[:1]])
        name = colour_on_display.display.name
        axes.plot(closed[:, 0], closed[:, 1], linewidth=0.9, color=palette[index], label=name)
        for panel, size in ((axes, 5), (zoom, 8)):
            panel.plot(
                *colour_on_display.xy,
                marker=MARKERS[index % len(MARKERS)],
                color=palette[index],
                markeredgecolor="black",
                markersize=size,
                linestyle="none",
            )
    points = np.array([item.xy for item in comparison.colours])
    points = points[np.isfinite(points).all(axis=1)]  # black (0, 0, 0) emits nothing and has no chromaticity
    if len(points):
        centre, half_width = points.mean(axis=0), max(np.ptp(points, axis=0).max() * 0.6, 0.01)
        zoom.set_xlim(centre[0] - half_width, centre[0] + half_width)
        zoom.set_ylim(centre[1] - half_width, centre[1] + half_width)
    zoom.set_title("the triple (zoomed)" if len(points) else "the triple: black, no chromaticity", fontsize=7)
    zoom.tick_params(labelsize=6)
    axes.set_xlim(-0.05, 0.8)
    axes.set_ylim(-0.05, 0.9)
    axes.legend(fontsize=6, loc="upper left", bbox_to_anchor=(1.02, 1.0))


def _display_palette(count: int) -> list:
    from matplotlib import colormaps

    return [colormaps["tab20"](index % 20) for index in range(count)]


def _plot_patches(figure, grid_cell, comparison: Comparison) -> None:
    axes = figure.add_subplot(grid_cell)
    for index, colour_on_display in enumerate(comparison.colours):
        axes.add_patch(_rectangle(index, colour_on_display.srgb))
        label = colour_on_display.display.name + ("" if colour_on_display.srgb_in_gamut else "\n(clipped)")
        axes.text(index + 0.45, -0.08, label, rotation=90, ha="center", va="top", fontsize=6)
    axes.set_xlim(0, len(comparison.colours))
    axes.set_ylim(0, 1)
    axes.set_axis_off()
    rgb = ", ".join(f"{value:g}" for value in comparison.rgb)
    axes.set_title(f"RGB ({rgb}) on each display, shown in sRGB", fontsize=9)


def _rectangle(index: int, srgb: np.ndarray):
    from matplotlib.patches import Rectangle

    return Rectangle((index, 0), 0.9, 1, facecolor=np.clip(srgb, 0, 1), edgecolor="none")


def plot_comparison(comparison: Comparison, path: str | Path) -> Path:
    """Draw the comparison into an image file (format from the suffix: .png, .pdf, .svg)."""
    pyplot = _pyplot()
    path = Path(path)
    if not path.parent.is_dir():
        raise SpectraceError("the folder for the plot does not exist", where=str(path))
    supported = pyplot.gcf().canvas.get_supported_filetypes()
    pyplot.close("all")
    if path.suffix.lstrip(".").lower() not in supported:
        raise SpectraceError(f"cannot write a plot as '{path.suffix}' (use .png, .pdf or .svg)", where=str(path))

    figure = pyplot.figure(figsize=(16, 10))
    layout = figure.add_gridspec(2, 2, width_ratios=(1.25, 1), height_ratios=(2.2, 1), hspace=0.35, wspace=0.15)
    _plot_emissions(figure, layout[:, 0], comparison)
    _plot_chromaticities(figure, layout[0, 1], comparison)
    _plot_patches(figure, layout[1, 1], comparison)
    figure.suptitle("primaries at full drive (red, green, blue) and the triple's emission (black)", x=0.3, fontsize=10)
    try:
        write_atomically(path, lambda temp: figure.savefig(temp, dpi=120, bbox_inches="tight"))
    except OSError as error:
        raise SpectraceError(f"cannot write the plot ({error.strerror or error})", where=str(path)) from None
    finally:
        pyplot.close(figure)
    return path
