"""What the figures show, read from their matplotlib objects: a light drawn with reflectances puts them on a second
axis where they are not flat; the display comparison spreads its spectra across the width, labels the wavelength
axis, keeps the zoomed points beside (not over) the diagram, and its legend carries the points' markers."""

import numpy as np
import pytest

from spectrace.resources import scenes_dir
from spectrace.scene.spectra_index import scene_spectra
from spectrace.spectral.spectrum_io import library_spectrum

pytest.importorskip("matplotlib")


def _cornell_spectra() -> dict:
    known = scene_spectra(scenes_dir() / "cornell_box.toml")
    walls = {name: known[f"materials.{name}.reflectance"] for name in ("white", "red", "green")}
    return {"light": library_spectrum("cornell_box/light"), **walls}


def _fraction_of_height(line) -> float:
    """How much of its axes' height a line's values span."""
    low, high = line.axes.get_ylim()
    values = np.asarray(line.get_ydata(), float)
    return float((values.max() - values.min()) / (high - low))


def test_a_light_with_reflectances_puts_them_on_a_second_axis():
    from spectrace.plots import spectra_figure

    spectra = _cornell_spectra()
    assert spectra["light"].values.max() > 10  # the Cornell box light: 0-18, the walls within [0, 1]
    figure = spectra_figure(spectra)
    axes = [a for a in figure.axes if a.get_lines()]
    assert len(axes) == 2
    left, right = sorted(axes, key=lambda a: a.get_ylim()[1], reverse=True)
    assert [line.get_label() for line in left.get_lines()] == ["light"]
    assert right.get_ylim() == pytest.approx((0, 1.05))
    assert "right axis" in right.get_ylabel()
    for line in right.get_lines():  # the red wall rises from 0.04 to 0.65: most of the height, not a flat line
        assert "(right axis)" in line.get_label()
    red = next(line for line in right.get_lines() if line.get_label().startswith("red"))
    assert _fraction_of_height(red) > 0.5
    # The legend names every line, those of the second axis included.
    legend = left.get_legend()
    assert [text.get_text() for text in legend.get_texts()] == [
        line.get_label() for line in figure.axes[0].get_lines() + right.get_lines()
    ]


@pytest.mark.parametrize("normalise", [False, True])
def test_one_axis_when_the_scales_agree_or_are_normalised(normalise):
    from spectrace.plots import spectra_figure

    spectra = _cornell_spectra()
    if not normalise:
        del spectra["light"]
    figure = spectra_figure(spectra, normalise=normalise)
    assert len([a for a in figure.axes if a.get_lines()]) == 1


def test_the_display_comparison_layout():
    from spectrace.displays import load_display
    from spectrace.displays.compare import compare_displays
    from spectrace.displays.plots import MARKERS, comparison_figure

    names = ["LCD-Dell_CCFL", "LCD-Apple_WLED", "OLED-SonyPVM2541"]
    figure = comparison_figure(compare_displays([load_display(n) for n in names], (0.6, 0.3, 0.2)))
    figure.canvas.draw()
    spectra = [a for a in figure.axes if any(n in a.get_title() for n in names)]
    assert len(spectra) == 3
    assert all(a.get_xlabel() == "wavelength (nm)" for a in spectra)
    boxes = [a.get_position() for a in spectra]
    every = [a.get_position() for a in figure.axes]
    width = max(b.x1 for b in every) - min(b.x0 for b in every)
    assert max(b.x1 for b in boxes) - min(b.x0 for b in boxes) > 0.95 * width  # across the figure's width
    diagram = next(a for a in figure.axes if a.get_title().startswith("gamuts"))
    zoom = next(a for a in figure.axes if a.get_title().startswith("the triple"))
    assert not diagram.get_position().overlaps(zoom.get_position())
    legend = zoom.get_legend()
    handles = legend.legend_handles
    assert [text.get_text() for text in legend.get_texts()] == names
    points = [line for line in zoom.get_lines() if line.get_marker() not in (None, "None", "")]
    for index, (handle, point) in enumerate(zip(handles, points)):
        assert handle.get_marker() == point.get_marker() == MARKERS[index]
        assert handle.get_color() == point.get_color()
