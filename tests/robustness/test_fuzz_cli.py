"""Fuzzing the command line: random option values (huge and negative integers, NaN, infinities and huge floats,
strings with odd characters, paths that are folders, missing, read-only or the same file twice) for `render` and
the numeric and file options of `bench`, `display` and `spectra`. Every run must end with status 0 or 2, never a
traceback, and a refusal is exactly one `error: ...` line; a render that succeeds must have been within the
limits (seed, depth, exposure) and have written its image.

Commands run in this process through `spectrace.cli.main` (fast); renders use a 4x4 film and 1 sample, and most
bad values are refused before any device work. `bench` runs with its measurements replaced by stubs that record
what they were asked, so only the checking of its options is exercised. CI runs a fixed set of examples
(derandomised); a longer random search:

    SPECTRACE_FUZZ_EXAMPLES=5000 python -m pytest tests/robustness/test_fuzz_cli.py -s
"""

import contextlib
import importlib
import io
import math
import sys
import tempfile
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given
from hypothesis import strategies as st

from fuzz_settings import LONG_RUN_EXAMPLES, fuzz_settings
from scene_text import glowing_rectangle
from spectrace import cli

pytestmark = pytest.mark.slow  # about a minute: the other fuzzers are marked so too


def _settings(examples: int):
    return fuzz_settings(examples, [HealthCheck.function_scoped_fixture, HealthCheck.too_slow])


SCENE = glowing_rectangle(width="4", height="4")

# ---------------------------------------------------------------- value strategies

ODD_INTS = st.sampled_from([0, -1, 1, 2, 3, -5, 2**31 - 1, 2**31, 2**32, 2**63, -(2**63), 10**30, 99999999999])
INTEGERS = st.one_of(ODD_INTS, st.integers(-(2**70), 2**70)).map(str)
JUNK = st.sampled_from(["", " ", "1.5", "abc", "0x10", "1e3", "1_000", "-", "--", "٣", "nan", "None"])
FLOATS = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True).map(repr),
    st.sampled_from(["nan", "-nan", "inf", "-inf", "1e308", "-1e308", "1e-320", "-0", "64", "-64", "64.0000001"]),
)
TEXT = st.text(st.characters(blacklist_categories=("Cs",), blacklist_characters="\x00"), max_size=16)
SUFFIXES = st.sampled_from([".png", ".exr", ".tiff", "", ".npz", ".pdf", ".svg", ".PNG"])
FILE_NAMES = st.one_of(
    st.sampled_from(
        [
            "out.png",
            "out.exr",
            "a-folder.png",
            "missing/out.png",
            "existing.png",
            "read-only.png",
            "scene.toml",
            "garbage.npz",
            "",
            ".",
            "..",
            "existing.png/x.png",
            "link-to-out.png",
        ]
    ),
    st.tuples(
        st.text(st.characters(blacklist_categories=("Cs",), blacklist_characters="\x00/"), min_size=1, max_size=12),
        SUFFIXES,
    ).map("".join),
)


def small(valid: list[int]):
    """Valid values that keep a render tiny, or anything."""
    return st.one_of(st.sampled_from(valid).map(str), INTEGERS, JUNK)


PATH = object()  # a file name, made absolute under the example's folder

RENDER_OPTIONS = {
    "--width": small([1, 2, 4]),
    "--height": small([1, 3, 4]),
    "--spp": small([1, 2]),
    "--seed": st.one_of(INTEGERS, JUNK),
    "--max-depth": st.one_of(INTEGERS, JUNK),
    "--exposure": st.one_of(FLOATS, JUNK),
    "--checkpoint-interval": st.one_of(FLOATS, JUNK),
    "--spectral-bins": st.one_of(st.sampled_from(["0", "3", "-1", "471", "472"]), INTEGERS, JUNK),
    "--sampler": st.one_of(st.sampled_from(["sobol", "independent"]), TEXT),
    "--kernel": st.one_of(st.sampled_from(["megakernel", "wavefront"]), TEXT),
    "--colour-space": st.one_of(st.sampled_from(["srgb", "display-p3", "rec2020", "xyz"]), TEXT),
    "--white-balance": st.one_of(st.sampled_from(["A", "D50", "3200K", "0.3,0.3", "-5K", "nan,0.3"]), TEXT),
    "--adaptation": st.one_of(st.sampled_from(["bradford", "von-kries"]), TEXT),
    "--false-color-scale": st.one_of(st.sampled_from(["log", "linear"]), TEXT),
    "--device": TEXT,
    "-o": PATH,
    "--false-color": PATH,
    "--checkpoint": PATH,
    "--resume": PATH,
}
RENDER_FLAGS = ["--no-xyz", "--overwrite", "--xyz"]

BENCH_OPTIONS = {
    "--size": small([1, 4, 16]),
    "--spp": small([1]),
    "--max-depth": st.one_of(INTEGERS, JUNK),
    "--triangles": st.one_of(INTEGERS, JUNK),
    "--ray-count": st.one_of(INTEGERS, JUNK),
    "--seconds": st.one_of(FLOATS, JUNK),
    "--peer-sampler": TEXT,
    "--rounds": st.one_of(INTEGERS, JUNK),
}
# Each mode's own options and flags ("" is the plain render bench); the others are click's usage errors.
BENCH_MODES = {
    "": (["--size", "--spp", "--max-depth"], ["--all"]),
    "peer": (["--size", "--spp", "--max-depth", "--peer-sampler", "--rounds"], ["--all", "--per-core"]),
    "quality": (["--size", "--seconds", "--max-depth", "--peer-sampler"], []),
    "rays": (["--triangles", "--ray-count"], ["--all"]),
    "scaling": (["--size", "--spp", "--max-depth", "--triangles"], []),
    "cold": (["--size", "--spp", "--max-depth"], []),
    "samplers": (["--size"], []),
    "kernel-shapes": (["--size", "--spp", "--max-depth"], []),
}

DISPLAYS = st.one_of(st.sampled_from(["CRT-Dell", "OLED-SamsungNote3"]), st.sampled_from(["LCD-Apple_WLED"]), TEXT)
RGB = st.one_of(
    st.tuples(*[st.sampled_from(["0", "0.25", "1"])] * 3),
    st.tuples(*[st.one_of(st.sampled_from(["0", "0.5", "1"]), FLOATS, JUNK)] * 3),
)
DISPLAY_OPTIONS = {
    "--white-luminance": st.one_of(st.sampled_from(["100", "0.01"]), FLOATS, JUNK),
    "--encoding": st.one_of(st.sampled_from(["linear", "srgb", "gamma2.2"]), TEXT),
}


def _options(table: dict, flags: list[str], max_size: int):
    choices = [
        st.tuples(st.just(name), value) if value is not PATH else st.tuples(st.just(name), FILE_NAMES)
        for name, value in table.items()
    ]
    choices += [st.just((flag,)) for flag in flags]
    return st.lists(st.one_of(choices), max_size=max_size)


# ---------------------------------------------------------------- running one example

COUNTS: dict[str, dict[int, int]] = {}  # command -> exit status -> runs
EXAMPLES = {"render": 300, "bench": 150, "display": 100, "spectra plot": 40}  # each command's fuzz test's examples


def _example_folder(workspace: Path) -> Path:
    folder = Path(tempfile.mkdtemp(dir=workspace))
    (folder / "scene.toml").write_text(SCENE)
    (folder / "a-folder.png").mkdir()
    (folder / "existing.png").write_bytes(b"kept")
    (folder / "garbage.npz").write_bytes(b"not a checkpoint")
    (folder / "read-only.png").write_bytes(b"kept")
    (folder / "read-only.png").chmod(0o444)
    (folder / "link-to-out.png").symlink_to(folder / "out.png")
    return folder


def _absolute(folder: Path, items) -> list[str]:
    argv = []
    for item in items:
        if len(item) == 2 and item[0] in ("-o", "--false-color", "--checkpoint", "--resume", "--plot"):
            argv += [item[0], str(folder / item[1])]
        elif len(item) == 2 and isinstance(item[1], tuple):
            argv += [item[0], *item[1]]
        else:
            argv += list(item)
    return argv


def _run(command: str, argv: list[str]) -> tuple[int, str]:
    """`spectrace ARGV` in this process; its status, with the one-line rule checked on its stderr."""
    stderr, stdout = io.StringIO(), io.StringIO()
    saved = sys.argv
    sys.argv = ["spectrace", *argv]
    try:
        with contextlib.redirect_stderr(stderr), contextlib.redirect_stdout(stdout):
            try:
                cli.main()
                status = 0
            except SystemExit as exit_info:
                status = exit_info.code
    finally:
        sys.argv = saved
    text = stderr.getvalue()
    COUNTS.setdefault(command, {}).setdefault(status, 0)
    COUNTS[command][status] += 1
    assert status in (0, 2), (argv, status, text)
    assert "Traceback" not in text, (argv, text)
    messages = [
        line
        for line in text.splitlines()
        if line.strip() and not line.startswith(("device: ", "scene: ", "resumed ", "warning: ", "wrote "))
    ]
    errors = [line for line in messages if line.startswith("error: ")]
    if status == 2:
        assert len(errors) == 1 and errors == [line for line in messages if "Warning" not in line], (argv, text)
    else:
        assert not errors, (argv, text)
    return status, text


def _last(argv: list[str], option: str) -> str | None:
    values = [argv[i + 1] for i, token in enumerate(argv[:-1]) if token == option]
    return values[-1] if values else None


def _report(command: str) -> None:
    counts = COUNTS.get(command, {})
    print(f"\n{command}: {sum(counts.values())} cases, by exit status {dict(sorted(counts.items()))}")


@pytest.fixture(scope="module")
def workspace(tmp_path_factory):
    return tmp_path_factory.mktemp("cli-fuzz")


# ---------------------------------------------------------------- the commands


@_settings(EXAMPLES["render"])
@given(options=_options(RENDER_OPTIONS, RENDER_FLAGS, max_size=4))
def test_render_options(workspace, options):
    folder = _example_folder(workspace)
    argv = [
        "render",
        str(folder / "scene.toml"),
        "-o",
        str(folder / "out.png"),
        "--width",
        "4",
        "--height",
        "4",
        "--spp",
        "1",
        "-q",
        *_absolute(folder, options),
    ]
    status, _ = _run("render", argv)
    if status == 0:  # whatever got through is within the limits, and the image is there
        if (seed := _last(argv, "--seed")) is not None:
            assert 0 <= int(seed) < 2**31, argv
        if (depth := _last(argv, "--max-depth")) is not None:
            assert int(depth) == -1 or 1 <= int(depth) < 2**31, argv
        if (exposure := _last(argv, "--exposure")) is not None:
            assert math.isfinite(float(exposure)) and abs(float(exposure)) <= 64, argv
        assert Path(_last(argv, "-o")).is_file(), argv
    assert (folder / "existing.png").read_bytes() == b"kept" or "existing.png" in " ".join(argv)
    assert (folder / "read-only.png").read_bytes() == b"kept"


@pytest.fixture
def stubbed_bench(monkeypatch):
    """The measurements replaced by recorders: only the command's own checks run."""
    asked = []

    def record(name, result):
        def stub(*args, **kwargs):
            asked.append((name, args, kwargs))
            return result

        return stub

    stubs = {
        "render": {"run_render_bench": []},
        "peer_mitsuba": {"run_peer_bench": {}, "peer_tables": [], "device_keys": [None]},
        "quality": {"run_quality_bench": {}, "quality_tables": []},
        "rays": {"run_rays_bench": {}, "rays_tables": []},
        "scaling": {"run_scaling_bench": {}, "scaling_tables": []},
        "cold_start": {"run_cold_bench": ([], []), "cold_tables": []},
        "kernel_shapes": {"run_kernel_shape_bench": []},
        "samplers": {"sampler_bench_command": None},
    }
    for module, functions in stubs.items():
        loaded = importlib.import_module(f"spectrace.benchmarks.{module}")
        for function, result in functions.items():
            monkeypatch.setattr(loaded, function, record(function, result))
    return asked


def _bench_argv(mode: str):
    names, flags = BENCH_MODES[mode]
    table = {name: BENCH_OPTIONS[name] for name in names}
    return _options(table, [*flags, "--json"], max_size=4).map(lambda options: [*([(mode,)] if mode else []), *options])


@_settings(EXAMPLES["bench"])
@given(argv=st.sampled_from(list(BENCH_MODES)).flatmap(_bench_argv))
def test_bench_options(stubbed_bench, argv):
    argv = ["bench", *_absolute(Path("."), argv)]
    stubbed_bench.clear()
    status, _ = _run("bench", argv)
    if status == 0:
        assert stubbed_bench, argv
        if (depth := _last(argv, "--max-depth")) is not None:
            assert int(depth) == -1 or 1 <= int(depth) < 2**31, argv
        sizes = [argv[i + 1] for i, token in enumerate(argv[:-1]) if token == "--size"]
        if argv[1:2] and argv[1] in ("peer", "quality", "cold", "samplers"):  # one size: the last --size given
            sizes = sizes[-1:]
        sizes = [int(size) for size in sizes]
        assert all(1 <= size <= 16384 for size in sizes), argv
        if (seconds := _last(argv, "--seconds")) is not None:
            assert math.isfinite(float(seconds)), argv


@_settings(EXAMPLES["display"])
@given(
    command=st.sampled_from(["compare", "match", "metamerism"]),
    rgb=RGB,
    source=DISPLAYS,
    target=DISPLAYS,
    options=_options(DISPLAY_OPTIONS, ["--measured-radiance", "--json"], max_size=3),
    plot=st.one_of(st.none(), FILE_NAMES),
)
def test_display_options(workspace, command, rgb, source, target, options, plot):
    folder = _example_folder(workspace)
    argv = ["display", command, "--rgb", *rgb, *_absolute(folder, options)]
    if command == "compare":
        argv += ["-d", source, "-d", target]
        if plot is not None:
            argv += ["--plot", str(folder / plot)]
    else:
        argv += ["--from", source, "--to", target]
    if command == "metamerism":
        argv = [token for token in argv if token != "--measured-radiance"]
    _run("display", argv)


@pytest.mark.filterwarnings("ignore:Glyph .* missing from font")  # odd characters in titles draw as boxes
@_settings(EXAMPLES["spectra plot"])
@given(
    names=st.lists(st.one_of(st.sampled_from(["cie:D65", "cie:A", "cornell_box/light"]), TEXT), min_size=1, max_size=3),
    output=FILE_NAMES,
    title=st.one_of(st.none(), TEXT, st.sampled_from(["$", "$x^$", r"\frac", "a$b$c"])),
    normalise=st.booleans(),
)
def test_spectra_plot_options(workspace, names, output, title, normalise):
    folder = _example_folder(workspace)
    argv = ["spectra", "plot", *names, "-o", str(folder / output)]
    argv += ["--title", title] if title is not None else []
    argv += ["--normalise"] if normalise else []
    _run("spectra plot", argv)


def test_fuzz_counts():
    """Each fuzz test that ran in this session ran every one of its examples, and its command both accepted some
    values (exit 0) and refused others (exit 2), so neither path went untried. The counts are printed with -s."""
    ran = [command for command in EXAMPLES if command in COUNTS]
    if not ran:
        pytest.skip("counts what the fuzz tests above ran, and none ran in this session")
    for command in ran:
        _report(command)
        counts = COUNTS[command]
        assert sum(counts.values()) == (LONG_RUN_EXAMPLES or EXAMPLES[command]), (command, counts)
        assert set(counts) == {0, 2}, (command, counts)
