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
SPECTRA_COLUMNS = 4
MARKERS = "os^Dvp<>h*XP"


def _pyplot():
    from spectrace.plot_extra import pyplot

    return pyplot("--plot")


def _plot_emissions(figure, grid_cell, comparison: Comparison) -> None:
    """One panel per display, side by side across the figure's width, each with its own power scale."""
    count = len(comparison.colours)
    columns = min(count, SPECTRA_COLUMNS)
    rows = math.ceil(count / columns)
    cells = grid_cell.subgridspec(rows, columns, hspace=0.55, wspace=0.22)
    palette = _display_palette(count)
    for index, colour_on_display in enumerate(comparison.colours):
        row, column = divmod(index, columns)
        axes = figure.add_subplot(cells[row, column])
        display = colour_on_display.display
        for primary, line_colour in zip(display.primaries, CHANNEL_COLOURS):
            axes.plot(GRID_NM, primary.values, color=line_colour, linewidth=0.8)
        axes.plot(GRID_NM, display.emission_from_drive(colour_on_display.drive), color="black", linewidth=1.3)
        # The display's marker and colour, as in the chromaticity panels, so each panel names its point there.
        axes.set_title(f"{_marker_symbol(index)}  {display.name}", fontsize=9, color=_darker(palette[index]))
        axes.set_xlim(380, 780)
        axes.set_ylim(bottom=0)
        axes.tick_params(labelsize=7)
        axes.yaxis.get_offset_text().set_fontsize(7)
        axes.grid(alpha=0.25)
        if row == rows - 1 or index + columns >= count:
            axes.set_xlabel("wavelength (nm)", fontsize=8)
        if column == 0:
            axes.set_ylabel("radiance (W/(sr m² nm))", fontsize=8)


_MARKER_SYMBOLS = {"o": "●", "s": "■", "^": "▲", "D": "◆", "v": "▼", "p": "⬟", "<": "◀", ">": "▶", "h": "⬢", "*": "★"}


def _marker_symbol(index: int) -> str:
    return _MARKER_SYMBOLS.get(MARKERS[index % len(MARKERS)], "")


def _darker(rgba) -> tuple[float, float, float]:
    r, g, b = rgba[:3]
    return (0.75 * r, 0.75 * g, 0.75 * b)


def _plot_chromaticities(figure, diagram_cell, zoom_cell, comparison: Comparison) -> None:
    """The whole diagram with each display's gamut and its point, and beside it (not over it) the points zoomed;
    the legend's entries carry each display's line and marker, so gamut, point and spectrum panel match."""
    from colour.plotting import plot_chromaticity_diagram_CIE1931
    from matplotlib.lines import Line2D

    axes = figure.add_subplot(diagram_cell)
    plot_chromaticity_diagram_CIE1931(
        figure=figure,
        axes=axes,
        show=False,
        tight_layout=False,
        transparent_background=False,
    )
    axes.set_title("gamuts and the triple's chromaticity (CIE 1931)", fontsize=10)
    zoom = figure.add_subplot(zoom_cell)
    palette = _display_palette(len(comparison.colours))
    handles = []
    for index, colour_on_display in enumerate(comparison.colours):
        primaries_xy = colour_on_display.display.primaries_xy()
        closed = np.vstack([primaries_xy, primaries_xy[:1]])
        marker = MARKERS[index % len(MARKERS)]
        axes.plot(closed[:, 0], closed[:, 1], linewidth=1.1, color=palette[index])
        for panel, size in ((axes, 6), (zoom, 10)):
            panel.plot(
                *colour_on_display.xy,
                marker=marker,
                color=palette[index],
                markeredgecolor="black",
                markersize=size,
                linestyle="none",
            )
        handles.append(
            Line2D(
                [],
                [],
                color=palette[index],
                linewidth=1.1,
                marker=marker,
                markeredgecolor="black",
                markersize=7,
                label=colour_on_display.display.name,
            )
        )
    points = np.array([item.xy for item in comparison.colours])
    points = points[np.isfinite(points).all(axis=1)]  # black (0, 0, 0) emits nothing and has no chromaticity
    if len(points):
        centre, half_width = points.mean(axis=0), max(np.ptp(points, axis=0).max() * 0.6, 0.01)
        zoom.set_xlim(centre[0] - half_width, centre[0] + half_width)
        zoom.set_ylim(centre[1] - half_width, centre[1] + half_width)
        zoom.set_aspect("equal")
        # Where the zoomed square lies on the diagram.
        from matplotlib.patches import Rectangle

        axes.add_patch(
            Rectangle(
                tuple(centre - half_width), 2 * half_width, 2 * half_width, fill=False, linewidth=0.8, linestyle="--"
            )
        )
    zoom.set_title("the triple, zoomed (dashed square)" if len(points) else "the triple: black, no chromaticity")
    zoom.title.set_fontsize(10)
    zoom.set_xlabel("CIE x", fontsize=8)
    zoom.set_ylabel("CIE y", fontsize=8)
    zoom.tick_params(labelsize=7)
    zoom.grid(alpha=0.3)
    zoom.legend(handles=handles, fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.16), ncol=1, frameon=False)
    axes.set_xlim(-0.1, 0.8)  # room for the 500 and 510 nm labels left of the locus
    axes.set_ylim(-0.05, 0.9)


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


def comparison_figure(comparison: Comparison):
    """The comparison as a matplotlib Figure (for a notebook, or to save): a row of spectra across the width, then
    the chromaticity diagram, the points zoomed beside it, and the patches."""
    pyplot = _pyplot()
    rows = math.ceil(len(comparison.colours) / SPECTRA_COLUMNS)
    figure = pyplot.figure(figsize=(16, 6.5 + 2.8 * rows))
    layout = figure.add_gridspec(2, 1, height_ratios=(1.1 * rows, 2.0), hspace=0.3)
    _plot_emissions(figure, layout[0], comparison)
    bottom = layout[1].subgridspec(1, 3, width_ratios=(1.15, 0.8, 1.05), wspace=0.28)
    _plot_chromaticities(figure, bottom[0], bottom[1], comparison)
    _plot_patches(figure, bottom[2], comparison)
    figure.suptitle(
        "each display's primaries at full drive (red, green, blue) and its emission for the triple (black)", fontsize=11
    )
    return figure


def plot_comparison(comparison: Comparison, path: str | Path) -> Path:
    """Draw the comparison into an image file (format from the suffix: .png, .pdf, .svg)."""
    return save_figure(lambda: comparison_figure(comparison), path)


def check_plot_path(path: str | Path) -> Path:
    """One line naming the file unless its folder exists and matplotlib writes its suffix's format."""
    pyplot = _pyplot()
    path = Path(path)
    if not path.parent.is_dir():
        raise SpectraceError("the folder for the plot does not exist", where=str(path))
    supported = pyplot.gcf().canvas.get_supported_filetypes()
    pyplot.close("all")
    if path.suffix.lstrip(".").lower() not in supported:
        raise SpectraceError(f"cannot write a plot as '{path.suffix}' (use .png, .pdf or .svg)", where=str(path))
    return path


def save_figure(make_figure, path: str | Path) -> Path:
    """The figure `make_figure()` returns, written atomically to an image file (format from the suffix), its folder
    and format checked before the figure is made."""
    pyplot = _pyplot()
    path = check_plot_path(path)
    figure = make_figure()
    try:
        write_atomically(path, lambda temp: figure.savefig(temp, dpi=120, bbox_inches="tight"))
    except OSError as error:
        raise SpectraceError(f"cannot write the plot ({error.strerror or error})", where=str(path)) from None
    finally:
        pyplot.close(figure)
    return path
