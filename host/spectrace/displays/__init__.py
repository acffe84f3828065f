"""Displays as spectral emitters: measured primaries, the same RGB on different displays, matching across
displays, and observer metamerism. See docs/displays.md for the experiment and its conventions."""

from spectrace.displays.compare import Comparison, DisplayColour, PairDifference, compare_displays
from spectrace.displays.match import MatchResult, match_colour
from spectrace.displays.viewing import DEFAULT_WHITE_LUMINANCE_CD_M2, ViewingConditions, delta_e_2000
from spectrace.spectral.display import CHANNELS, Display
from spectrace.spectral.display_catalog import display_names, load_all_displays, load_display, load_display_csv
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
    "Comparison",
    "Display",
    "DisplayColour",
    "Encoding",
    "MatchResult",
    "Observer",
    "PairDifference",
    "ViewingConditions",
    "compare_displays",
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
