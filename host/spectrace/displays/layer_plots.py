"""One figure for a display's layer model: measured and modelled primaries, the model's layers (backlight and
colour filters), and the gamuts of the model and its variants on the CIE 1931 diagram."""

from __future__ import annotations

from pathlib import Path

from spectrace.displays.layer_experiments import Variant
from spectrace.displays.layers import FitResult
from spectrace.displays.plots import CHANNEL_COLOURS, _display_palette, _pyplot, save_figure
from spectrace.spectral import GRID_NM


def layer_model_figure(fit: FitResult, variants: list[Variant]):
    pyplot = _pyplot()
    from colour.plotting import plot_chromaticity_diagram_CIE1931

    figure, (spectra, layers, diagram) = pyplot.subplots(1, 3, figsize=(17, 5.2))
    measured = fit.measured.primaries_values
    model = fit.model.primaries_values()
    for channel, colour in enumerate(CHANNEL_COLOURS):
        spectra.plot(GRID_NM, measured[channel], color=colour, linewidth=1.4)
        spectra.plot(GRID_NM, model[channel], color="black", linewidth=0.9, linestyle="--")
    spectra.set_title(f"{fit.measured.name}: measured (colour) and layer model (dashed)", fontsize=10)
    spectra.set_xlabel("wavelength (nm)")
    spectra.set_xlim(380, 780)

    backlight = fit.model.backlight.spectrum()
    layers.plot(GRID_NM, backlight / backlight.max(), color="black", linewidth=1.3, label="backlight (relative)")
    for colour, colour_filter in zip(CHANNEL_COLOURS, fit.model.filters):
        layers.plot(GRID_NM, colour_filter.transmittance(), color=colour, linewidth=1.1)
    layers.set_title(f"layers: {fit.model.backlight.kind} backlight and the colour filters (peak 1)", fontsize=10)
    layers.set_xlabel("wavelength (nm)")
    layers.set_xlim(380, 780)
    layers.legend(fontsize=8, loc="upper right")

    plot_chromaticity_diagram_CIE1931(
        figure=figure, axes=diagram, show=False, tight_layout=False, transparent_background=False
    )
    measured_xy = fit.measured_xy()
    palette = _display_palette(len(variants) + 1)
    closed = [0, 1, 2, 0]
    diagram.plot(measured_xy[closed, 0], measured_xy[closed, 1], color="black", linewidth=2.0, label="measured")
    for index, variant in enumerate(variants):
        xy = variant.primaries_xy
        label = f"{variant.name}: area {variant.gamut_xy:.3f}"
        diagram.plot(xy[closed, 0], xy[closed, 1], color=palette[index + 1], linewidth=1.1, linestyle="--", label=label)
    diagram.set_xlim(-0.1, 0.8)
    diagram.set_ylim(-0.05, 0.9)
    diagram.set_title("gamuts (CIE 1931 xy)", fontsize=10)
    diagram.legend(fontsize=7, loc="upper right")
    figure.tight_layout()
    return figure


def plot_layer_model(fit: FitResult, variants: list[Variant], path: str | Path) -> Path:
    return save_figure(lambda: layer_model_figure(fit, variants), path)
