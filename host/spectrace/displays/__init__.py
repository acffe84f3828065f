"""Displays as spectral emitters: measured primaries, the same RGB on different displays, matching across
displays, and observer metamerism. See docs/displays.md for the experiment and its conventions."""

from spectrace.displays.compare import Comparison, DisplayColour, PairDifference, compare_displays
from spectrace.displays.layer_experiments import Variant, layer_variants
from spectrace.displays.layers import Backlight, ColourFilter, FitResult, LayerModel, fit_layer_model
from spectrace.displays.match import MatchResult, match_colour
from spectrace.displays.polarizer import PolarizerComparison, through_polarizer
from spectrace.displays.viewing import DEFAULT_WHITE_LUMINANCE_CD_M2, ViewingConditions, delta_e_2000
from spectrace.spectral.display import CHANNELS, Display
from spectrace.spectral.display_catalog import display_names, load_all_displays, load_display, load_display_csv
from spectrace.spectral.display_polarization import Polarization, transmitted_fraction
from spectrace.spectral.display_transfer import Encoding, decode_to_drive, encode_drive, parse_encoding
from spectrace.spectral.observers import (
    ALL_OBSERVERS,
    LUMINOUS_EFFICACY_LM_PER_W,
    Observer,
    luminance_cd_m2,
    observer_cmfs,
    photometric_xyz,
)

__all__ = [
    "ALL_OBSERVERS",
    "CHANNELS",
    "DEFAULT_WHITE_LUMINANCE_CD_M2",
    "LUMINOUS_EFFICACY_LM_PER_W",
    "Backlight",
    "ColourFilter",
    "Comparison",
    "Display",
    "DisplayColour",
    "Encoding",
    "FitResult",
    "LayerModel",
    "MatchResult",
    "Observer",
    "PairDifference",
    "Polarization",
    "PolarizerComparison",
    "Variant",
    "ViewingConditions",
    "compare_displays",
    "fit_layer_model",
    "layer_variants",
    "through_polarizer",
    "transmitted_fraction",
    "decode_to_drive",
    "delta_e_2000",
    "display_names",
    "encode_drive",
    "load_all_displays",
    "load_display",
    "load_display_csv",
    "luminance_cd_m2",
    "match_colour",
    "observer_cmfs",
    "parse_encoding",
    "photometric_xyz",
]
