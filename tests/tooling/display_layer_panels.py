"""Writes scenes/display_layers/*.csv, the primaries of two LCD layer models (spectrace.displays.layers) for the
scene scenes/display_qd_vs_wled.toml.

Both are the layer model fitted to LCD-Apple_WLED's measured primaries (a blue LED and a YAG:Ce phosphor, through
its colour filters); the second keeps the fitted filters and LED and replaces the phosphor by the published CdSe
green and red quantum-dot emissions, white balanced to the fitted model's white (`layer_variants`, as
`spectrace display model LCD-Apple_WLED` lists them). Run `python -m tests.tooling.display_layer_panels` after
changing the layer models; tests/displays/test_display_layer_panels.py checks the files are what this writes.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from spectrace.spectral.grid import GRID_NM

ROOT = Path(__file__).resolve().parents[2]
FOLDER = ROOT / "scenes" / "display_layers"
MEASURED = "LCD-Apple_WLED"
# file stem -> index in layer_variants(): the fitted model, and its CdSe quantum-dot backlight variant
PANELS = {"wled_yag_lcd": 0, "qd_cdse_lcd": 2}


def panel_texts() -> dict[str, str]:
    """The CSV text of each panel's display, by file stem."""
    from spectrace.displays.layer_experiments import layer_variants
    from spectrace.displays.layers import fit_layer_model
    from spectrace.spectral.display_catalog import load_display

    variants = layer_variants(fit_layer_model(load_display(MEASURED)))
    texts = {}
    for stem, index in PANELS.items():
        variant = variants[index]
        display = variant.display
        lines = [
            f"# Display primaries, {stem}: an LCD layer model (spectrace.displays.layers) after {MEASURED}",
            f"# technology: LCD, {variant.description}",
            f"# source: {display.source}; written by tests/tooling/display_layer_panels.py",
            "# units: relative spectral radiance per channel at full drive",
            "# polarization: unknown",
            "wavelength_nm,red,green,blue",
        ]
        values = np.stack([spectrum.values for spectrum in display.primaries], axis=1)
        scale = 1.0 / values.max()
        lines += [f"{nm:g}," + ",".join(f"{v * scale:.6g}" for v in row) for nm, row in zip(GRID_NM, values)]
        texts[stem] = "\n".join(lines) + "\n"
    return texts


def main() -> None:
    FOLDER.mkdir(exist_ok=True)
    for stem, text in panel_texts().items():
        (FOLDER / f"{stem}.csv").write_text(text, encoding="utf-8")
        print(f"wrote scenes/display_layers/{stem}.csv")


if __name__ == "__main__":
    main()
