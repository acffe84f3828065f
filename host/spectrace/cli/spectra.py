"""`spectrace spectra list | plot`: the spectra the library and a scene file know, listed and drawn."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Annotated

import typer
from rich.console import Console
from rich.table import Table

from spectrace.cli.common import GROUP_SETTINGS, JsonOption
from spectrace.errors import SpectraceError

spectra_app = typer.Typer(
    help="Spectra: list the library's and a scene's spectra, and plot any of them.",
    no_args_is_help=True,
    **GROUP_SETTINGS,
)

SceneOption = Annotated[
    Path | None,
    typer.Option(
        "--scene",
        "-s",
        help="Also the spectra of this scene file (or bundled scene: cornell_box), by key path "
        "(spectra.NAME, materials.NAME.reflectance, shapes[I].emitter.radiance, lights[I].intensity, ...).",
    ),
]


def _known_spectra(scene: Path | None) -> dict:
    from spectrace.resources import resolve_scene_path
    from spectrace.scene.spectra_index import scene_spectra

    return scene_spectra(resolve_scene_path(scene)) if scene is not None else {}


def _resolve(name: str, scene_spectra: dict):
    """A scene key path first, then a library name ("cornell_box/light", "cie:D65")."""
    from spectrace.spectral.spectrum_io import library_spectrum, list_library_spectra

    if name in scene_spectra:
        return scene_spectra[name]
    if f"spectra.{name}" in scene_spectra:
        return scene_spectra[f"spectra.{name}"]
    try:
        return library_spectrum(name)
    except SpectraceError:
        import difflib

        close = difflib.get_close_matches(name, list(scene_spectra) + list_library_spectra(), n=1)
        hint = f" (did you mean '{close[0]}'?)" if close else ""
        raise SpectraceError(
            f"unknown spectrum '{name}'{hint}; `spectrace spectra list` shows them", where="NAME"
        ) from None


@spectra_app.command("list")
def list_spectra(
    scene: SceneOption = None,
    as_json: JsonOption = False,
) -> None:
    """Every spectrum `plot` accepts: the library's (files under spectra/, CIE illuminants) and, with --scene, the
    scene's, each with its range of values and its colour (CIE 1931 x, y as light)."""
    from spectrace.spectral.colorimetry import spectrum_to_xyz, xyz_to_xy
    from spectrace.spectral.spectrum_io import list_library_spectra

    in_scene = _known_spectra(scene)
    rows = [(key, "scene", spectrum) for key, spectrum in in_scene.items()]
    rows += [(name, "library", None) for name in list_library_spectra()]
    if as_json:
        print(
            json.dumps(
                {
                    "scene": {key: {"min": s.min(), "max": s.max()} for key, _, s in rows if s is not None},
                    "library": [name for name, origin, _ in rows if origin == "library"],
                },
                indent=2,
            )
        )
        return
    table = Table(title="spectra (plot with `spectrace spectra plot NAME... -o FILE.png`)")
    for heading in ("name", "from", "min", "max", "x, y (as light)"):
        table.add_column(heading)
    for name, origin, spectrum in rows:
        if spectrum is None:
            table.add_row(name, origin, "", "", "")
            continue
        xyz = spectrum_to_xyz(spectrum)
        xy = "" if not xyz.sum() > 0 else "{:.4f}, {:.4f}".format(*xyz_to_xy(xyz))
        table.add_row(name, origin, f"{spectrum.min():.4g}", f"{spectrum.max():.4g}", xy)
    Console(width=160, markup=False).print(table)


@spectra_app.command()
def plot(
    names: Annotated[
        list[str],
        typer.Argument(
            help="Spectra to draw: library names (cie:D65, cornell_box/light) or, with --scene, the scene's key paths."
        ),
    ],
    output: Annotated[Path, typer.Option("--output", "-o", help="Figure file: .png, .pdf or .svg.")],
    scene: SceneOption = None,
    normalise: Annotated[
        bool, typer.Option("--normalise", "--normalize", help="Divide each spectrum by its peak (compare shapes).")
    ] = False,
    title: Annotated[str | None, typer.Option(help="Figure title.")] = None,
) -> None:
    """Draw spectra against wavelength (360-830 nm, as the renderer samples them: linear between data points,
    end values held) into a figure file; each line takes the spectrum's own colour."""
    from spectrace.cli.checks import check_output_file
    from spectrace.plot_extra import require_matplotlib
    from spectrace.plots import plot_spectra, text_problem

    require_matplotlib("spectra plot")

    if title and (problem := text_problem(title)):
        raise SpectraceError(problem, where="--title")
    if output.suffix.lower() not in (".png", ".pdf", ".svg"):
        raise SpectraceError(f"unknown figure format '{output.suffix}' (use .png, .pdf or .svg)", where=str(output))
    check_output_file(output, "--output")
    known = _known_spectra(scene)
    spectra = {name: _resolve(name, known) for name in names}
    plot_spectra(spectra, output, normalise=normalise, title=title)
    Console(stderr=True, markup=False).print(f"wrote {output}", highlight=False)
