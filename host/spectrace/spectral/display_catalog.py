"""The displays spectrace knows: measured primaries shipped under `spectra/displays/`, two more read from
colour-science at load time, and any user CSV of three primaries.

Display CSV format (the spectrum CSV of `spectrace.spectral.spectrum_io`, with three named columns):
    # technology: LCD with white-LED backlight (inferred from the spectrum)     <- optional, shown by `list`
    # polarization: linear 45 (assumed)                                         <- optional, default unknown
    # units: W/(sr m^2 nm)                                                      <- marks absolute radiance
    wavelength_nm,red,green,blue
    380,1.2e-05,3.1e-06,4.4e-05
    ...
Each column is one channel's spectral radiance at full drive with the others off. A file whose `# units:` line
does not start with W/(sr m^2 nm) is read as relative radiance (arbitrary scale). Spectra are joined linearly
onto the grid and hold their end values outside the measured range, as every spectrum in spectrace does.
"""

from __future__ import annotations

import re
from functools import cache
from pathlib import Path

import colour

from spectrace.errors import SpectraceError
from spectrace.io.input_files import is_regular_file, regular_file
from spectrace.resources import spectra_dir
from spectrace.spectral import load_spectrum_csv, spectrum_from_colour
from spectrace.spectral.display import CHANNELS, Display
from spectrace.spectral.display_polarization import Polarization, parse_polarization

DISPLAYS_FOLDER = "displays"
RELATIVE = "relative"
MEASURED = "measured"

# spectrace name -> (colour-science key in MSDS_DISPLAY_PRIMARIES, technology, reference, polarisation). Relative
# data.
_COLOUR_SCIENCE_DISPLAYS = {
    "CRT-Brainard1997": (
        "Typical CRT Brainard 1997",
        "CRT",
        "colour-science MSDS_DISPLAY_PRIMARIES 'Typical CRT Brainard 1997' (Brainard's typical CRT phosphors,"
        " as tabulated by Machado 2010)",
        "unpolarized (a CRT's phosphors emit unpolarised light)",
    ),
    "LCD-AppleStudioDisplay_CCFL": (
        "Apple Studio Display",
        "LCD with CCFL backlight (inferred)",
        "colour-science MSDS_DISPLAY_PRIMARIES 'Apple Studio Display' (Fairchild & Wyble 1998)",
        "linear 45 (assumed: an LCD's front polariser; the axis is not in the source)",
    ),
}

_ABSOLUTE_UNITS = re.compile(r"^W/\((sr m\^?2|m\^?2 sr) nm\)")
_TECHNOLOGY_END = re.compile(r" \(| - |;|,")


# ---------------------------------------------------------------- names


def _shipped_files() -> dict[str, Path]:
    folder = spectra_dir() / DISPLAYS_FOLDER
    return {path.stem: path for path in sorted(folder.glob("*.csv"))}


def display_names() -> list[str]:
    """Every display `load_display` knows by name: the shipped files, then those from colour-science."""
    return [*_shipped_files(), *_COLOUR_SCIENCE_DISPLAYS]


def _looks_like_path(spec: str) -> bool:
    return spec.lower().endswith(".csv") or "/" in spec or "\\" in spec or is_regular_file(spec)


def load_display(spec: str, where: str | None = None) -> Display:
    """A display by name (case-insensitive, see `display_names`) or by the path of a display CSV."""
    spec = spec.strip()
    if _looks_like_path(spec):
        return load_display_csv(Path(spec))
    by_folded_name = {name.casefold(): name for name in display_names()}
    name = by_folded_name.get(spec.casefold())
    if name is None:
        raise SpectraceError(
            f"unknown display '{spec}' (available: {', '.join(display_names())}; or a CSV file)", where=where
        )
    return _load_named_display(name)


def load_all_displays() -> list[Display]:
    return [_load_named_display(name) for name in display_names()]


@cache
def _load_named_display(name: str) -> Display:
    if name in _COLOUR_SCIENCE_DISPLAYS:
        return _colour_science_display(name)
    return load_display_csv(_shipped_files()[name])


# ---------------------------------------------------------------- colour-science


def _colour_science_display(name: str) -> Display:
    key, technology, reference, polarization = _COLOUR_SCIENCE_DISPLAYS[name]
    multi_sd = colour.MSDS_DISPLAY_PRIMARIES[key]
    red, green, blue = (
        spectrum_from_colour(sd, name=f"{name}:{channel}") for channel, sd in zip(CHANNELS, multi_sd.to_sds())
    )
    return Display(
        name=name,
        technology=technology,
        primaries=(red, green, blue),
        absolute=False,
        radiance_scale=RELATIVE,
        source=reference,
        polarization=parse_polarization(polarization),
    )


# ---------------------------------------------------------------- CSV files


def _comment_keys_and_header(path: Path) -> tuple[dict[str, str], list[str]]:
    """`# key: text` comment lines (first occurrence of each key) and the header's data columns."""
    regular_file(path, what="display file")
    try:
        lines = path.read_text(encoding="utf-8-sig").splitlines()
    except (OSError, UnicodeDecodeError) as error:
        problem = f"{error.__class__.__name__}: {error}"
        raise SpectraceError(f"cannot read display file ({problem})", where=str(path)) from None
    keys: dict[str, str] = {}
    for line in lines:
        stripped = line.strip()
        if not stripped:
            continue
        if not stripped.startswith("#"):
            fields = [field.strip() for field in stripped.split(",")]
            return keys, fields[1:]
        key, separator, text = stripped.lstrip("#").partition(":")
        if separator:
            keys.setdefault(key.strip().lower(), text.strip())
    return keys, []


def short_technology(text: str) -> str:
    """ "LCD with CCFL backlight (INFERRED from ...)" -> "LCD with CCFL backlight (inferred)"."""
    label = _TECHNOLOGY_END.split(text, maxsplit=1)[0].strip() or "unknown"
    return f"{label} (inferred)" if "inferred" in text.casefold() else label


def is_absolute_units(units: str) -> bool:
    """Whether a `# units:` text declares spectral radiance in W/(sr m^2 nm)."""
    return bool(_ABSOLUTE_UNITS.match(units.replace("²", "^2").strip()))


def load_display_csv(path: str | Path, name: str | None = None) -> Display:
    """A display from a CSV with columns red, green, blue (see the module docstring). Errors name the file."""
    path = Path(path)
    keys, columns = _comment_keys_and_header(path)
    if sorted(columns) != sorted(CHANNELS):
        raise SpectraceError(
            f"a display CSV needs the header 'wavelength_nm,red,green,blue', got columns {columns or 'none'}",
            where=str(path),
        )
    display_name = name or path.stem
    red, green, blue = (
        load_spectrum_csv(path, column=channel, name=f"{display_name}:{channel}") for channel in CHANNELS
    )
    absolute = is_absolute_units(keys.get("units", ""))
    return Display(
        name=display_name,
        technology=short_technology(keys.get("technology", "unknown")),
        primaries=(red, green, blue),
        absolute=absolute,
        radiance_scale=MEASURED if absolute else RELATIVE,
        source=str(path),
        polarization=_polarization(keys, path),
    )


def _polarization(keys: dict[str, str], path: Path) -> Polarization:
    text = keys.get("polarization")
    return Polarization() if text is None else parse_polarization(text, where=f"{path}: # polarization")
