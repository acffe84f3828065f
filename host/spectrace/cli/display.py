"""`spectrace display list | compare | match | metamerism | model | polariser`: displays as spectral emitters (see
docs/displays.md)."""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Annotated

import numpy as np
import typer
from rich.console import Console
from rich.table import Table

from spectrace.cli.common import GROUP_SETTINGS, JsonOption
from spectrace.displays.compare import Comparison, compare_displays
from spectrace.displays.match import MatchResult, match_colour
from spectrace.displays.viewing import DEFAULT_WHITE_LUMINANCE_CD_M2, ViewingConditions
from spectrace.errors import SpectraceError
from spectrace.spectral.display import CHANNELS, Display
from spectrace.spectral.display_catalog import load_all_displays, load_display
from spectrace.spectral.display_transfer import Encoding, checked_rgb
from spectrace.spectral.observers import ALL_OBSERVERS, Observer

display_app = typer.Typer(
    help="Displays as spectral emitters: the same RGB on LCD, OLED and CRT displays.",
    no_args_is_help=True,
    **GROUP_SETTINGS,
)

# Independent meter estimates per patch reading, from which its standard error comes.
METER_STREAMS = 32


def _checked_rgb_option(value: tuple[float, float, float]) -> tuple[float, float, float]:
    """The triple checked as the command line reads it, so that a value out of range names the option as typed
    (the library's own check can only name its argument)."""
    try:
        checked_rgb(value)
    except SpectraceError as error:
        raise typer.BadParameter(error.message) from None  # click adds the option it was reading
    return value


RgbOption = Annotated[
    tuple[float, float, float],
    typer.Option("--rgb", help="The triple R G B, each in [0, 1], read with --encoding.", callback=_checked_rgb_option),
]
EncodingOption = Annotated[
    Encoding,
    typer.Option(
        "--encoding",
        help="How the triple maps to linear drive: linear (the triple is the drive), "
        "srgb (IEC 61966-2-1 curve) or gamma2.2.",
    ),
]
WhiteLuminanceOption = Annotated[
    float,
    typer.Option("--white-luminance", help="cd/m² of every display's white (1,1,1) and of the D65 reference white."),
]
MeasuredOption = Annotated[
    bool,
    typer.Option(
        "--measured-radiance",
        help="Displays with absolute data keep their measured radiance "
        "(relative ones are still set to --white-luminance).",
    ),
]


PIPED_OUTPUT_WIDTH = 200  # columns for tables written to a file or a pipe, where no terminal width exists


def _stdout_console() -> Console:
    return Console(markup=False) if sys.stdout.isatty() else Console(width=PIPED_OUTPUT_WIDTH, markup=False)


def _print_json(payload: dict) -> None:
    print(json.dumps(payload, indent=2))


def _xy_text(xy: np.ndarray) -> str:
    return f"{xy[0]:.4f}, {xy[1]:.4f}"


def _triple_text(values: np.ndarray, digits: int = 3) -> str:
    return " ".join(f"{value:.{digits}f}" for value in values)


def _displays_from_options(specs: list[str] | None, option: str) -> list[Display]:
    if not specs:
        return load_all_displays()
    return [load_display(spec, where=option) for spec in specs]


# ---------------------------------------------------------------- list


def _listing_json(display: Display) -> dict:
    return {
        "name": display.name,
        "technology": display.technology,
        "absolute": display.absolute,
        "radiance_scale": display.radiance_scale,
        "white_luminance_cd_m2": display.white_luminance_cd_m2 if display.absolute else None,
        "primaries_xy": dict(zip(CHANNELS, display.primaries_xy().tolist())),
        "white_xy": display.white_xy().tolist(),
        "source": display.source,
        "polarization": {
            "kind": display.polarization.kind,
            "axis_deg": display.polarization.axis_deg if display.polarization.kind == "linear" else None,
            "note": display.polarization.note,
        },
    }


@display_app.command("list")
def list_displays(
    extra: Annotated[
        list[str] | None, typer.Option("--display", "-d", help="Also list this display CSV (repeatable).")
    ] = None,
    as_json: JsonOption = False,
) -> None:
    """Every known display: technology, primaries' and white's CIE 1931 xy, white luminance."""
    displays = load_all_displays() + [load_display(spec, where="--display") for spec in extra or []]
    if as_json:
        _print_json({"displays": [_listing_json(display) for display in displays]})
        return
    table = Table(title="displays (CIE 1931 xy; white = RGB (1, 1, 1))")
    for heading in ("display", "technology", "red xy", "green xy", "blue xy", "white xy", "white cd/m²", "light"):
        table.add_column(heading)
    for display in displays:
        luminance = f"{display.white_luminance_cd_m2:.1f}" if display.absolute else "relative"
        table.add_row(
            display.name,
            display.technology,
            *(_xy_text(xy) for xy in display.primaries_xy()),
            _xy_text(display.white_xy()),
            luminance,
            display.polarization.text() + (" (assumed)" if display.polarization.note.startswith("assumed") else ""),
        )
    _stdout_console().print(table)


# ---------------------------------------------------------------- compare


def _comparison_tables(comparison: Comparison) -> tuple[Table, Table]:
    rgb = ", ".join(f"{value:g}" for value in comparison.rgb)
    white = comparison.viewing.white_luminance_cd_m2
    colours = Table(title=f"RGB ({rgb}); CIELAB and sRGB relative to D65 at {white:g} cd/m²; * = outside sRGB, clipped")
    for heading in ("display", "luminance scale", "X Y Z (cd/m²)", "x, y", "Y cd/m²", "sRGB", "L* a* b* (1931 2°)"):
        colours.add_column(heading)
    for item in comparison.colours:
        colours.add_row(
            item.display.name,
            item.display.radiance_scale,
            _triple_text(item.xyz_cd_m2, 2),
            _xy_text(item.xy),
            f"{item.luminance_cd_m2:.2f}",
            _triple_text(item.srgb) + ("" if item.srgb_in_gamut else " *"),
            _triple_text(item.lab[Observer.CIE_1931_2], 2),
        )
    pairs = Table(title="CIEDE2000 of every pair")
    for heading in ("display", "display", *(f"ΔE00 {observer.label}" for observer in ALL_OBSERVERS)):
        pairs.add_column(heading)
    for pair in comparison.pairs:
        pairs.add_row(pair.first, pair.second, *(f"{pair.delta_e_2000[observer]:.2f}" for observer in ALL_OBSERVERS))
    return colours, pairs


@display_app.command()
def compare(
    rgb: RgbOption,
    display: Annotated[
        list[str] | None,
        typer.Option("--display", "-d", help="Display name or CSV file (repeatable; default: every known display)."),
    ] = None,
    encoding: EncodingOption = Encoding.LINEAR,
    white_luminance: WhiteLuminanceOption = DEFAULT_WHITE_LUMINANCE_CD_M2,
    measured_radiance: MeasuredOption = False,
    plot: Annotated[Path | None, typer.Option("--plot", help="Also draw the comparison into this image file.")] = None,
    as_json: JsonOption = False,
) -> None:
    """The same RGB on several displays: XYZ, xy, luminance, sRGB, CIELAB, and ΔE2000 of every pair."""
    if plot is not None:
        from spectrace.cli.checks import check_output_file

        check_output_file(plot, "--plot")  # before the work, like every output
        from spectrace.plot_extra import require_matplotlib

        require_matplotlib("--plot")
    displays = [item.with_transfer(encoding) for item in _displays_from_options(display, "--display")]
    viewing = ViewingConditions(white_luminance_cd_m2=white_luminance, keep_measured_radiance=measured_radiance)
    comparison = compare_displays(displays, np.array(rgb), viewing)
    if plot is not None:
        from spectrace.displays.plots import plot_comparison

        plot_comparison(comparison, plot)
    if as_json:
        payload = comparison.to_json() | {"encoding": encoding.value, "plot": str(plot) if plot else None}
        _print_json(payload)
        return
    console = _stdout_console()
    for table in _comparison_tables(comparison):
        console.print(table)
    if plot is not None:
        console.print(f"wrote {plot}", highlight=False, markup=False)


# ---------------------------------------------------------------- match


def _match_table(result: MatchResult) -> Table:
    status = "exact (in gamut)" if result.in_gamut else "out of gamut: closest in [0, 1]³ by ΔE00 (1931 2°)"
    table = Table(title=f"match from {result.source.name} to {result.target.name}: {status}")
    table.add_column("")
    table.add_column(result.source.name)
    table.add_column(result.target.name)
    table.add_row("RGB", _triple_text(result.rgb, 4), _triple_text(result.target_rgb, 4))
    table.add_row("linear drive", _triple_text(result.source_drive, 4), _triple_text(result.target_drive, 4))
    table.add_row("X Y Z (cd/m²)", _triple_text(result.source_xyz_cd_m2, 3), _triple_text(result.target_xyz_cd_m2, 3))
    if not result.in_gamut:
        table.add_row("exact drive (outside [0, 1])", "", _triple_text(result.exact_drive, 4))
    for observer in ALL_OBSERVERS:
        table.add_row(f"residual ΔE00 {observer.label}", "", f"{result.delta_e_2000[observer]:.3f}")
    return table


@display_app.command()
def match(
    rgb: RgbOption,
    source: Annotated[str, typer.Option("--from", help="Display name or CSV file showing the triple.")],
    target: Annotated[str, typer.Option("--to", help="Display name or CSV file to find the matching RGB on.")],
    encoding: EncodingOption = Encoding.LINEAR,
    white_luminance: WhiteLuminanceOption = DEFAULT_WHITE_LUMINANCE_CD_M2,
    measured_radiance: MeasuredOption = False,
    as_json: JsonOption = False,
) -> None:
    """The RGB on --to whose emission has the CIE 1931 XYZ of the triple on --from, and the residual ΔE2000."""
    source_display = load_display(source, where="--from").with_transfer(encoding)
    target_display = load_display(target, where="--to").with_transfer(encoding)
    viewing = ViewingConditions(white_luminance_cd_m2=white_luminance, keep_measured_radiance=measured_radiance)
    result = match_colour(source_display, np.array(rgb), target_display, viewing)
    if as_json:
        _print_json(result.to_json() | {"encoding": encoding.value, "viewing": viewing.to_json()})
        return
    _stdout_console().print(_match_table(result))


@display_app.command()
def metamerism(
    source: Annotated[str, typer.Option("--from", help="Display lighting the first half.")],
    target: Annotated[str, typer.Option("--to", help="Display lighting the second half, matched to --from.")],
    rgb: Annotated[
        tuple[float, float, float],
        typer.Option(
            "--rgb",
            help="The triple --from shows (default a light grey, which most displays can match).",
            callback=_checked_rgb_option,
        ),
    ] = (0.8, 0.8, 0.8),
    encoding: EncodingOption = Encoding.LINEAR,
    white_luminance: WhiteLuminanceOption = DEFAULT_WHITE_LUMINANCE_CD_M2,
    scene: Annotated[
        Path | None,
        typer.Option(
            help="Also measure the two halves of a rendered scene (shapes named 'left <patch>' / 'right <patch>', "
            "e.g. the bundled display_lcd_vs_led) with radiance meters: a scene file of any format `render` takes, "
            "or a bundled scene's name."
        ),
    ] = None,
    spp: Annotated[
        int,
        typer.Option(
            help="With --scene: samples per patch reading (rounded up to a multiple of 32); the ΔE standard errors "
            "fall as 1/sqrt(spp).",
            min=1,
            max=1 << 20,
        ),
    ] = METER_STREAMS * 32,
    device: Annotated[str | None, typer.Option("--device", "-d", help="OpenCL device for --scene.")] = None,
    as_json: JsonOption = False,
    quiet: Annotated[bool, typer.Option("--quiet", "-q", help="No progress bar.")] = False,
) -> None:
    """Illuminant metamerism: the ColorChecker lit by --from showing the triple vs lit by --to showing the triple
    that matches it (same CIE 1931 XYZ): the per-patch ΔE2000 between the two halves."""
    from spectrace.displays.metamerism import measure_scene_patches, patch_metamerism

    report = patch_metamerism(
        load_display(source, where="--from").with_transfer(encoding),
        rgb,
        load_display(target, where="--to").with_transfer(encoding),
        ViewingConditions(white_luminance_cd_m2=white_luminance),
    )
    rendered = None
    if scene is not None:
        from contextlib import nullcontext

        from spectrace.cli.common import console
        from spectrace.interop.scene_files import load_any_scene
        from spectrace.progress import progress_bar

        loaded = load_any_scene(scene, report=console.say)
        bar = (
            nullcontext(None) if quiet else progress_bar(2 * 24, 0, console.rich(), unit="readings", label="measuring")
        )
        with bar as progress:
            rendered = measure_scene_patches(loaded, device, METER_STREAMS, -(-spp // METER_STREAMS), progress=progress)
    if as_json:
        result = report.to_json()
        if rendered is not None:
            result["rendered"] = [
                {
                    "patch": r.patch,
                    "lab_left": r.lab_left.tolist(),
                    "lab_right": r.lab_right.tolist(),
                    "delta_e_2000": r.delta_e_2000,
                    "delta_e_standard_error": r.delta_e_standard_error,
                }
                for r in rendered
            ]
        print(json.dumps(result, indent=2))
        return
    screens = report.to_json()["screens_delta_e_2000"]
    target_rgb = ", ".join(f"{v:.4f}" for v in report.match.target_drive)
    table = Table(
        title=f"ColorChecker lit by {report.match.source.name} showing {tuple(rgb)} vs by "
        f"{report.match.target.name} showing ({target_rgb}); the screens differ by ΔE2000 {screens:.2f}"
    )
    for column in (
        "patch",
        f"L*a*b* under {report.match.source.name}",
        f"L*a*b* under {report.match.target.name}",
        "ΔE2000",
    ):
        table.add_column(column)
    for p in report.patches:
        table.add_row(
            p.patch,
            " ".join(f"{v:6.2f}" for v in p.lab_under_source),
            " ".join(f"{v:6.2f}" for v in p.lab_under_target),
            f"{p.delta_e_2000:.2f}",
        )
    table.add_row("mean / max", "", "", f"{report.mean_delta_e:.2f} / {report.max_delta_e:.2f}")
    Console(width=140, markup=False).print(table)
    if rendered is not None:
        measured = Table(
            title=f"Measured in the render of {scene} (radiance meters from the camera, "
            f"{METER_STREAMS * -(-spp // METER_STREAMS)} samples a patch)"
        )
        for column in ("patch", "L*a*b* left", "L*a*b* right", "ΔE2000 ± s.e."):
            measured.add_column(column)
        for r in rendered:
            measured.add_row(
                r.patch,
                " ".join(f"{v:6.2f}" for v in r.lab_left),
                " ".join(f"{v:6.2f}" for v in r.lab_right),
                f"{r.delta_e_2000:.2f} ± {r.delta_e_standard_error:.2f}",
            )
        Console(width=140, markup=False).print(measured)


# ---------------------------------------------------------------- model


def _fit_table(fit) -> Table:
    table = Table(
        title=f"{fit.measured.name}: measured primaries vs the layer model ({fit.model.backlight.describe()}; "
        f"spectral rms residual {fit.rms_residual:.3f} of the peak)"
    )
    for heading in ("primary", "measured x, y", "model x, y", "Δxy"):
        table.add_column(heading)
    for channel, measured, model, delta in zip(CHANNELS, fit.measured_xy(), fit.model_xy(), fit.delta_xy()):
        table.add_row(channel, _xy_text(measured), _xy_text(model), f"{delta:.4f}")
    measured, model = fit.white_xy()
    table.add_row("white", _xy_text(measured), _xy_text(model), f"{np.linalg.norm(model - measured):.4f}")
    return table


def _variants_table(variants) -> Table:
    table = Table(
        title="one layer changed (each white balanced to the model's white by channel gains); metamerism against the "
        "model: a grey (0.8) matched for CIE 1931 2°, seen by CIE 1964 10°, and the ColorChecker lit by each"
    )
    for heading in (
        "variant",
        "red xy",
        "green xy",
        "blue xy",
        "gamut area xy",
        "gamut area u'v'",
        "white efficiency",
        "grey ΔE00 10°",
        "ColorChecker ΔE00 mean / max",
    ):
        table.add_column(heading)
    for variant in variants:
        table.add_row(
            variant.name,
            *(_xy_text(xy) for xy in variant.primaries_xy),
            f"{variant.gamut_xy:.4f}",
            f"{variant.gamut_uv:.4f}",
            f"{variant.white_efficiency:.3f}",
            f"{variant.grey_delta_e_1964:.2f}",
            f"{variant.colorchecker_mean_delta_e:.2f} / {variant.colorchecker_max_delta_e:.2f}",
        )
    return table


@display_app.command("model")
def model_command(
    name: Annotated[str, typer.Argument(help="An LCD's name or CSV file (see `display list`).")],
    backlight: Annotated[
        str | None,
        typer.Option(
            "--backlight",
            help="wled_yag (blue LED + YAG:Ce), qd (blue LED + quantum-dot films) or ccfl; "
            "default: from the display's technology.",
        ),
    ] = None,
    plot: Annotated[Path | None, typer.Option("--plot", help="Also draw the model into this image file.")] = None,
    as_json: JsonOption = False,
) -> None:
    """An LCD described by its layers (backlight × colour filters × polarisers), fitted to its measured primaries:
    measured vs modelled xy, and how the gamut and metamerism change when one layer changes."""
    from spectrace.displays.layer_experiments import layer_variants
    from spectrace.displays.layers import BACKLIGHTS, fit_layer_model

    if plot is not None:
        from spectrace.cli.checks import check_output_file

        check_output_file(plot, "--plot")
        from spectrace.plot_extra import require_matplotlib

        require_matplotlib("--plot")
        from spectrace.displays.plots import check_plot_path

        check_plot_path(plot)  # its format too, before the fit
    if backlight is not None and backlight not in BACKLIGHTS:
        raise SpectraceError(f"unknown backlight '{backlight}' (one of {', '.join(BACKLIGHTS)})", where="--backlight")
    display = load_display(name, where="NAME")
    if backlight is None and "lcd" not in f"{display.name} {display.technology}".casefold():
        raise SpectraceError(
            f"{display.name} is not an LCD (technology: {display.technology}): a layer model is a backlight behind "
            "colour filters; give --backlight to fit one anyway",
            where="NAME",
        )
    fit = fit_layer_model(display, backlight)
    variants = layer_variants(fit)
    if plot is not None:
        from spectrace.displays.layer_plots import plot_layer_model

        plot_layer_model(fit, variants, plot)
    if as_json:
        _print_json(fit.to_json() | {"variants": [v.to_json() for v in variants], "plot": str(plot) if plot else None})
        return
    console = _stdout_console()
    console.print(_fit_table(fit))
    console.print(_variants_table(variants))
    if plot is not None:
        console.print(f"wrote {plot}", highlight=False, markup=False)


# ---------------------------------------------------------------- polarizer


def _with_polarization(displays: list[Display], overrides: list[str] | None) -> list[Display]:
    """Each display with the polarisation `NAME=SPEC` gives it, for the displays it names."""
    from dataclasses import replace

    from spectrace.spectral.display_polarization import parse_polarization

    given = {}
    for item in overrides or []:
        name, separator, spec = item.partition("=")
        if not separator or not name.strip():
            raise SpectraceError(f"expected NAME=SPEC (as 'LCD-Dell_CCFL=linear 90'), got '{item}'", "--polarization")
        given[name.strip().casefold()] = parse_polarization(spec, where=f"--polarization {name.strip()}")
    unknown = set(given) - {display.name.casefold() for display in displays}
    if unknown:
        raise SpectraceError(f"'{sorted(unknown)[0]}' is not one of the displays compared", where="--polarization")
    return [
        replace(display, polarization=given[display.name.casefold()]) if display.name.casefold() in given else display
        for display in displays
    ]


@display_app.command("polarizer")
def polarizer_command(
    display: Annotated[
        list[str],
        typer.Option("--display", "-d", help="Display name or CSV file (repeatable; two or more to compare)."),
    ],
    angle: Annotated[
        list[float] | None,
        typer.Option(
            "--angle", "-a", help="Polariser angle in degrees from horizontal (repeatable; default 0..180 every 15)."
        ),
    ] = None,
    rgb: Annotated[
        tuple[float, float, float],
        typer.Option("--rgb", help="The triple each display shows (default white).", callback=_checked_rgb_option),
    ] = (1.0, 1.0, 1.0),
    polarization: Annotated[
        list[str] | None,
        typer.Option(
            "--polarization",
            help="NAME=SPEC: the polarisation of a display's light instead of the catalogue's "
            "('linear 90', 'circular', 'unpolarized'; repeatable).",
        ),
    ] = None,
    transmittances: Annotated[
        tuple[float, float],
        typer.Option(
            "--transmittances",
            help="The polariser's principal transmittances K1 K2 (along and across its axis; default ideal, 1 0).",
        ),
    ] = (1.0, 0.0),
    encoding: EncodingOption = Encoding.LINEAR,
    white_luminance: WhiteLuminanceOption = DEFAULT_WHITE_LUMINANCE_CD_M2,
    as_json: JsonOption = False,
) -> None:
    """Displays seen through a linear polariser at each angle: luminance and chromaticity (Malus's law on polarised
    light, ½ of unpolarised light), and the CIEDE2000 between each pair."""
    import math

    from spectrace.displays.polarizer import DEFAULT_ANGLES_DEG, through_polarizer

    angles = tuple(angle) if angle else DEFAULT_ANGLES_DEG
    bad = next((value for value in angles if not math.isfinite(value)), None)
    if bad is not None:
        raise SpectraceError(f"an angle must be a finite number of degrees, got {bad}", where="--angle")
    displays = [load_display(spec, where="--display").with_transfer(encoding) for spec in display]
    displays = _with_polarization(displays, polarization)
    viewing = ViewingConditions(white_luminance_cd_m2=white_luminance)
    result = through_polarizer(displays, angles, np.array(rgb), viewing, transmittances)
    if as_json:
        _print_json(result.to_json() | {"encoding": encoding.value})
        return
    names = [seen.display for seen in result.rows[0]]
    polarizations = ", ".join(f"{seen.display}: {seen.polarization}" for seen in result.rows[0])
    table = Table(
        title=f"RGB ({', '.join(f'{v:g}' for v in result.rgb)}) through a linear polariser, k1 {transmittances[0]:g}, "
        f"k2 {transmittances[1]:g} ({polarizations}); "
        f"white {white_luminance:g} cd/m² without it"
    )
    table.add_column("angle °")
    for name in names:
        table.add_column(f"{name} cd/m²")
        table.add_column(f"{name} x, y")
    pairs = list(result.pair_delta_e[0])
    for first, second in pairs:
        table.add_column(f"ΔE00 {first} / {second}")
    for angle_deg, row, deltas in zip(result.angles_deg, result.rows, result.pair_delta_e):
        cells = [f"{angle_deg:g}"]
        for seen in row:
            cells += [f"{seen.luminance_cd_m2:.2f}", _xy_text(seen.xy) if seen.luminance_cd_m2 > 0 else "black"]
        cells += [f"{deltas[pair]:.2f}" for pair in pairs]
        table.add_row(*cells)
    _stdout_console().print(table)
