"""Every Mitsuba 3 XML file under the folders named, as Mitsuba 3 and spectrace each take it: the corpus table of
"every file that Mitsuba 3 itself renders imports untouched and agrees".

    python -m tests.tooling.mitsuba_corpus ROOT... [--json OUT] [--render] [--size 16] [--spp 4] [--replicas 8]
                                                   [--timeout 60] [--device intel-cpu]

For each *.xml (recursively, in name order): whether Mitsuba 3's scalar_spectral variant loads it (a file whose
stokes integrator asks for the polarised mode: scalar_spectral_polarized), and whether it has a sensor, without which
Mitsuba renders nothing (a fragment for <include>); whether spectrace imports it
(`load_mitsuba_scene`, in this process, with a time limit per file); and where it refuses, its one line and the
features it lacks: the unsupported plugins the importer names, each once, or the first words of any other refusal.
The refusals are then grouped by feature, counting the files each keeps out, and among them those Mitsuba renders.

With --render, each file both take is rendered by both at `size` pixels wide (the file's aspect kept) as `replicas`
independent images of `spp` samples, and the whole-image means (each channel and their sum) compared in standard
errors of the difference (tests/replica_agreement.py, the comparison the Mitsuba tests make): agrees within 5,
with the comparison's power (the smallest relative error 5 standard errors would catch) beside it, so that a noisy
agreement is seen as one. Mitsuba's film gives linear sRGB (or XYZ, as its pixel_format says), compared with
spectrace's film XYZ converted alike. A scene the import renders polarised (a polariser, a retarder, the stokes
integrator) is rendered by Mitsuba's scalar_spectral_polarized, where its polarisers polarise.

One process, one file at a time, one render at a time. The files are public scenes fetched apart from the project;
nothing here writes into their folders. A Python exception other than spectrace's own error is a bug: it is counted
as a crash, its last line shown, and the run exits 1."""

from __future__ import annotations

import argparse
import gc
import json
import os
import re
import signal
import sys
import time
import traceback
from collections.abc import Iterator
from contextlib import contextmanager, suppress
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np

# The comparison helpers live beside the tests, which import them by their own names.
sys.path.append(str(Path(__file__).resolve().parents[1]))
os.environ.setdefault("SPECTRACE_GENERAL_KERNELS", "1")  # one program per integrator, not one per file

from spectrace.errors import SpectraceError  # noqa: E402

SIGMAS = 5.0
POWER = 0.05  # as tests/replica_agreement.py asks of a test: weaker comparisons are flagged
UNSUPPORTED = "unsupported Mitsuba 3 plugins: "
POLARISED = "scalar_spectral_polarized"


@dataclass
class Row:
    file: str
    mitsuba: str = ""  # "renders", "renders polarised", "no sensor" (loads, renders nothing), "refuses", "timeout"
    mitsuba_reason: str = ""
    imported: bool = False
    features: list[str] = field(default_factory=list)  # what the refusal names
    reason: str = ""
    crashed: bool = False
    compared: str = ""  # "agrees", "DIFFERS", or why not compared ("" without --render)
    z: float | None = None  # largest difference over the channels and their sum, in standard errors
    power: float | None = None  # of the channels' sum
    means: list[float] = field(default_factory=list)  # spectrace's then Mitsuba's whole-image means per channel
    seconds: float = 0.0


class FileTimeout(Exception):
    pass


@contextmanager
def time_limit(seconds: float) -> Iterator[None]:
    """Raises FileTimeout in this (the main) thread after `seconds`; a call inside native code is stopped only when
    it returns to Python."""

    def expire(signum, frame):
        raise FileTimeout(f"over {seconds:g} s")

    previous = signal.signal(signal.SIGALRM, expire)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)


def _mitsuba():
    """Mitsuba 3's scalar_spectral variant, quiet, or None where it is not installed."""
    try:
        import mitsuba as mi
    except ImportError:
        return None
    if "scalar_spectral" not in mi.variants():
        return None
    mi.set_variant("scalar_spectral")
    mi.set_log_level(mi.LogLevel.Error)
    # Its thread pool is left at its size: with one thread, loading a scene whose emitter builds its sampling tables
    # in tasks (matpreview's envmap) waits for ever.
    return mi


def _first_line(text: str, shown: dict[str, str]) -> str:
    line = next((part.strip() for part in str(text).splitlines() if part.strip()), "")
    line = re.sub(r"^(\[[\w.]+:\d+\]\s*)+", "", line)  # Mitsuba's [source.cpp:line] prefixes
    for path, name in shown.items():
        line = line.replace(path, name)
    return line


def mitsuba_load(mi, path: Path, shown: dict[str, str]) -> tuple[str, str]:
    """(status, reason): whether Mitsuba 3 loads the file as `mitsuba scene.xml` would, and has a sensor. A file
    whose plugins ask for Mitsuba's polarised mode (the stokes integrator) is tried in scalar_spectral_polarized,
    where Mitsuba renders it: "renders polarised"."""
    try:
        scene = mi.load_file(str(path), parallel=False)
    except Exception as failure:  # Mitsuba's refusals are RuntimeErrors of many kinds
        reason = _first_line(str(failure), shown)
        if "polarized mode" not in reason or POLARISED not in mi.variants():
            return "refuses", reason
        mi.set_variant(POLARISED)
        try:
            scene = mi.load_file(str(path), parallel=False)
        except Exception as polarised_failure:
            return "refuses", f"{reason}; in {POLARISED}: {_first_line(str(polarised_failure), shown)}"
        finally:
            mi.set_variant("scalar_spectral")
        return ("renders polarised", "") if scene.sensors() else ("no sensor", "a scene without a sensor")
    if not isinstance(scene, mi.Scene):
        return "no sensor", f"the root is a {type(scene).__name__}, not a scene"
    return ("renders", "") if scene.sensors() else ("no sensor", "a scene without a sensor (a fragment)")


def _features(path: Path, message: str) -> list[str]:
    """What a refusal says the file lacks: for unsupported plugins, the importer's own record of them (read again by
    importing the file to the point of that error), each as the importer names it without its count and line; else
    the refusal's first words, numbers and quoted values blanked, so that files refused alike group together."""
    if UNSUPPORTED in message:
        from spectrace.interop.mitsuba.importer import MitsubaImporter, run
        from spectrace.interop.mitsuba.tree import read_scene

        importer = MitsubaImporter(path, path.parent, {})
        with suppress(SpectraceError):
            run(importer, read_scene(path, {}))
        if importer.unsupported:
            return list(importer.unsupported)
    text = message.split(": ", 1)[1] if ": " in message else message
    # after the file name, the element path when there is one (`shape[2]/bsdf@type: ...`)
    if re.match(r"^[\w\[\]/@.-]+: ", text) and not text.startswith(UNSUPPORTED):
        text = text.split(": ", 1)[1]
    text = re.sub(r"'[^']*'|\"[^\"]*\"", "'…'", text)
    text = re.sub(r"[-+]?\d[\d.e+-]*", "N", text)
    words = re.split(r"[:;(]", text, maxsplit=1)[0].split()
    return [" ".join(words[:8])]


def spectrace_import(path: Path, shown: dict[str, str]):
    """(scene or None, row fields): spectrace's import of the file, loaded as a scene."""
    from spectrace.interop.mitsuba import load_mitsuba_scene

    try:
        return load_mitsuba_scene(path), {"imported": True}
    except SpectraceError as failure:
        message = str(failure)
        reason = _first_line(message, shown).removeprefix(shown[str(path)] + ": ")  # the row names the file
        reason = re.sub(r" \(spectrace imports [^)]*\)$", "", reason)  # the same list on every such row
        return None, {"reason": reason, "features": _features(path, message)}


def _mitsuba_images(mi, path: Path, width: int, height: int, spp: int, replicas: int) -> tuple[np.ndarray, str]:
    """(replicas, height, width, channels) from Mitsuba, its films set to width x height, and the pixel format of the
    first film. The file is read by Mitsuba's own parser, as load_file reads it, and instantiated after the change."""
    import mitsuba.parser as parser

    config = parser.ParserConfig(mi.variant())
    config.parallel = False
    resolver = mi.file_resolver()
    kept = mi.FileResolver(resolver)
    resolver.prepend(str(path.parent.resolve()))  # as load_file does: the scene's folder first
    try:
        state = parser.parse_file(config, str(path))
        parser.transform_all(config, state)
        films = [node for node in state.nodes if node.type == mi.ObjectType.Film]
        pixel_format = str(films[0].props.get("pixel_format", "rgba")) if films else "rgba"
        for node in films:
            node.props["width"], node.props["height"] = width, height
        scene = parser.instantiate(config, state)
    finally:
        mi.set_file_resolver(kept)
    images = [np.array(mi.render(scene, spp=spp, seed=seed), dtype=np.float64) for seed in range(replicas)]
    return np.stack(images), pixel_format


def compare(mi, path: Path, scene, size: int, spp: int, replicas: int, device, row: Row) -> None:
    """Both renderers' whole-image means, compared (row.compared, row.z, row.power, row.means)."""
    from replica_agreement import difference_and_power, spectrace_replicas
    from spectrace.engine.renderer import Renderer
    from spectrace.engine.scene_features import is_polarized
    from spectrace.spectral import xyz_to_linear_srgb

    width, height = size, max(1, round(size * scene.height / scene.width))
    renderer = Renderer(scene.with_overrides(width=width, height=height), device)
    # Where the import renders polarised (a polariser, a retarder, Mitsuba's stokes integrator), so does Mitsuba:
    # in its other variants its polarisers do not polarise.
    polarised = is_polarized(renderer.scene, renderer.buffers) or row.mitsuba == "renders polarised"
    mi.set_variant(POLARISED if polarised else "scalar_spectral")
    try:
        theirs, pixel_format = _mitsuba_images(mi, path, width, height, spp, replicas)
    finally:
        mi.set_variant("scalar_spectral")
    if pixel_format.startswith("xyz"):
        convert = lambda xyz: xyz  # noqa: E731
    elif pixel_format.startswith("rgb"):
        convert = xyz_to_linear_srgb
    else:
        row.compared = f"not compared: Mitsuba's film gives {pixel_format}"
        return
    ours = convert(spectrace_replicas(renderer, replicas, spp))
    ours_means = ours.mean(axis=(1, 2))
    theirs_means = theirs[..., :3].mean(axis=(1, 2))  # before any channels an integrator adds
    z_channels, _, _ = difference_and_power(ours_means, theirs_means, SIGMAS)
    z_sum, power, _ = difference_and_power(ours_means.sum(-1), theirs_means.sum(-1), SIGMAS)
    row.z = float(max(np.max(z_channels), z_sum))
    row.power = float(power)
    row.means = [*map(float, ours_means.mean(0)), *map(float, theirs_means.mean(0))]
    row.compared = "agrees" if row.z <= SIGMAS else "DIFFERS"


def survey(path: Path, shown: dict[str, str], mi, args, device) -> Row:
    row = Row(shown[str(path)])
    start = time.perf_counter()
    try:
        if mi is not None:
            try:
                with time_limit(args.timeout):
                    row.mitsuba, row.mitsuba_reason = mitsuba_load(mi, path, shown)
            except FileTimeout as late:
                row.mitsuba, row.mitsuba_reason = "timeout", str(late)
            gc.collect()
        try:
            with time_limit(args.timeout):
                scene, found = spectrace_import(path, shown)
        except FileTimeout as late:
            scene, found = None, {"reason": f"timeout: {late}", "features": ["import time limit"]}
        for key, value in found.items():
            setattr(row, key, value)
        if args.render and scene is not None:
            if not row.mitsuba.startswith("renders"):
                row.compared = "not compared: Mitsuba does not render it"
            else:
                try:
                    with time_limit(args.timeout * 4):
                        compare(mi, path, scene, args.size, args.spp, args.replicas, device, row)
                except SpectraceError as failure:
                    row.compared = "not rendered: " + _first_line(str(failure), shown)
                except FileTimeout as late:
                    row.compared = f"not compared: render timeout, {late}"
                except RuntimeError as failure:  # Mitsuba refusing to render what it loaded
                    row.compared = "not compared: Mitsuba: " + _first_line(str(failure), shown)
    except Exception:
        row.crashed = True
        row.reason = "CRASH " + _first_line(traceback.format_exc().strip().splitlines()[-1], shown)
        traceback.print_exc()
    row.seconds = round(time.perf_counter() - start, 2)
    return row


def _cell(text: str) -> str:
    return text.replace("|", "\\|")


def feature_groups(rows: list[Row]) -> list[tuple[str, int, int]]:
    """(feature, files it keeps out, of which Mitsuba renders), the most frequent first."""
    groups: dict[str, list[int]] = {}
    for row in rows:
        if row.imported or row.crashed:
            continue
        for feature in dict.fromkeys(row.features):
            counts = groups.setdefault(feature, [0, 0])
            counts[0] += 1
            counts[1] += row.mitsuba.startswith("renders")
    return sorted(((name, *counts) for name, counts in groups.items()), key=lambda g: (-g[2], -g[1], g[0]))


def summary(rows: list[Row], rendered: bool) -> list[str]:
    renders = [row for row in rows if row.mitsuba.startswith("renders")]
    both = [row for row in renders if row.imported]
    lines = [
        "| files | Mitsuba 3 renders | of which polarised only | loads without a sensor | refuses | "
        + "spectrace imports | of those Mitsuba renders |"
        + (" agree | differ | not compared |" if rendered else ""),
        "|---|---|---|---|---|---|---|" + ("---|---|---|" if rendered else ""),
    ]
    counts = [
        len(rows),
        len(renders),
        sum(row.mitsuba == "renders polarised" for row in rows),
        sum(row.mitsuba == "no sensor" for row in rows),
        sum(row.mitsuba in ("refuses", "timeout") for row in rows),
        sum(row.imported for row in rows),
        len(both),
    ]
    if rendered:
        agree = sum(row.compared == "agrees" for row in both)
        differ = sum(row.compared == "DIFFERS" for row in both)
        counts += [agree, differ, len(both) - agree - differ]
    lines.append("| " + " | ".join(map(str, counts)) + " |")
    return lines


def table(rows: list[Row], rendered: bool) -> str:
    def mark(value: bool) -> str:
        return "yes" if value else "NO"

    head = "| file | Mitsuba 3 | spectrace imports |" + (" compared | z | power |" if rendered else "") + " reason |"
    lines = [head, "|---|---|---|" + ("---|---|---|" if rendered else "") + "---|"]
    for row in rows:
        mitsuba = f"Mitsuba: {row.mitsuba_reason}" if row.mitsuba_reason else ""
        reason = "; ".join(text for text in (mitsuba, row.reason) if text)
        cells = [row.file, row.mitsuba or "-", mark(row.imported)]
        if rendered:
            cells += [
                row.compared or "-",
                "-" if row.z is None else f"{row.z:.2f}",
                "-" if row.power is None else f"{row.power:.1%}" + (" (weak)" if row.power > POWER else ""),
            ]
        lines.append("| " + " | ".join(_cell(cell) for cell in [*cells, reason]) + " |")
    lines += ["", "What the files spectrace refuses lack (a file counts under each feature it lacks):", ""]
    lines += ["| feature | files | of which Mitsuba 3 renders |", "|---|---|---|"]
    lines += [f"| {_cell(name)} | {count} | {renders} |" for name, count, renders in feature_groups(rows)]
    crashed = [row for row in rows if row.crashed]
    if crashed:
        lines += ["", f"Crashes (bugs): {len(crashed)}", *(f"- {row.file}: {row.reason}" for row in crashed)]
    return "\n".join(["", *summary(rows, rendered), "", *lines])


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("roots", nargs="+", type=Path, help="folders (or files) holding Mitsuba 3 XML scenes")
    parser.add_argument("--json", type=Path, help="also write the rows and the feature groups as JSON here")
    parser.add_argument("--render", action="store_true", help="render the files both take and compare them")
    parser.add_argument("--size", type=int, default=16, help="rendered width in pixels")
    parser.add_argument("--spp", type=int, default=4, help="samples per pixel of each replica")
    parser.add_argument("--replicas", type=int, default=8, help="independent images per renderer")
    parser.add_argument("--timeout", type=float, default=60.0, help="seconds per file and step (renders: 4x)")
    parser.add_argument("--device", default=None, help="spectrace's device, as SPECTRACE_DEVICE names one")
    args = parser.parse_args(argv)
    files = sorted(
        {
            path.resolve()
            for root in args.roots
            for path in ([root] if root.is_file() else root.rglob("*.xml"))
            if path.suffix.lower() == ".xml" and path.is_file()
        }
    )
    # Files are named relative to the folder above the roots, so no machine's paths reach the table.
    base = Path(os.path.commonpath([root.resolve().parent for root in args.roots]))
    shown = {str(path): str(path.relative_to(base)) for path in files}
    shown |= {str(path.parent): str(path.parent.relative_to(base)) for path in files}
    shown = dict(sorted(shown.items(), key=lambda item: -len(item[0])))  # the longest first
    mi = _mitsuba()
    if mi is None:
        print("Mitsuba 3 with its scalar_spectral variant is not installed: its column stays empty", file=sys.stderr)
    device = None
    if args.render:
        from spectrace.device import open_device

        device = open_device(args.device)
    rows = []
    for path in files:
        row = survey(path, shown, mi, args, device)
        imported = "yes" if row.imported else "NO"
        print(f"{row.mitsuba or '-':>9} {imported:>3} {row.compared:<8.8} {row.file}  {row.reason}", file=sys.stderr)
        rows.append(row)
    rendered = args.render and mi is not None
    print(table(rows, rendered))
    if args.json:
        groups = [{"feature": name, "files": n, "mitsuba_renders": r} for name, n, r in feature_groups(rows)]
        args.json.write_text(json.dumps({"rows": [asdict(row) for row in rows], "features": groups}, indent=1))
    return 1 if any(row.crashed for row in rows) else 0


if __name__ == "__main__":
    sys.exit(main())
