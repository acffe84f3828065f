"""`spectrace sweep` and spectrace.sweep without a cluster: an item is keyed by everything that determines it, so a
rerun after an edit of the scene, of a file it names or of the program computes those items again (and the numbers
follow the edit as the physics says), while a rerun of the same inputs computes nothing; a spec of the wrong shape
is one line naming the spec file and key path; a results table that cannot be written is one line and keeps the
table already there."""

import errno
import json
import math
import os
import signal
import subprocess
import sys
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given
from hypothesis import strategies as st

from cli_runner import run_in_process
from fuzz_settings import fuzz_settings
from scene_text import emitting_screen
from spectrace.errors import SpectraceError
from spectrace.resources import spectra_dir
from spectrace.scene import Scene

_ENOSPC = os.strerror(errno.ENOSPC)


def _sweep(monkeypatch, capsys, spec: Path, out: Path, quiet: bool = False) -> tuple[int, str]:
    """The sweep's status and stderr; without -q, for its summary line (-q keeps only warnings and errors)."""
    return run_in_process(monkeypatch, capsys, ["sweep", str(spec), "-o", str(out), *(["-q"] if quiet else [])])


def _counts(err: str) -> str:
    """'(C computed now, D already done)' of the command's last line."""
    last = err.strip().splitlines()[-1]
    return last[last.index("(") :].strip()


def _display_spec(path: Path, displays: list[str]) -> Path:
    path.write_text(
        f'[sweep]\nkind = "display"\n[grid]\ndisplay = {json.dumps(displays)}\n'
        'rgb = [[0.2, 0.7, 0.4], [1.0, 1.0, 1.0]]\nobserver = ["cie1964_10"]\n'
    )
    return path


def _glow(path: Path, radiance: float) -> None:
    """A spectrum file that is `radiance` (W/(m² sr nm)) at every wavelength."""
    path.write_text(f"wavelength_nm,glow\n300,{radiance}\n900,{radiance}\n")


# ---------------------------------------------------------------- what an item's key covers


def test_a_render_sweep_rerun_after_an_edit_recomputes_and_follows_it(tmp_path, monkeypatch, capsys):
    """The camera sees only an emitter of spectral radiance L (one bounce), so the film's mean XYZ is linear in L:
    with the same seeds, scaling L scales every sample, and the mean, by the same factor (rounding aside). Each edit
    (the spectrum file the scene names, the scene file itself, `scene =` pointing at another file) must compute
    every item again and report the scaled numbers; a rerun without an edit computes nothing."""
    _glow(tmp_path / "glow.csv", 1.0)
    (tmp_path / "screen.toml").write_text(emitting_screen(radiance='file = "glow.csv"'))
    (tmp_path / "brighter.toml").write_text(emitting_screen(radiance="value = 4.0"))
    spec = tmp_path / "sweep.toml"
    spec_text = '[sweep]\nkind = "render"\nscene = "{}"\n[grid]\n"sampler.seed" = [1, 2]\n"sampler.spp" = [4]\n'
    spec.write_text(spec_text.format("screen.toml"))
    out = tmp_path / "results"

    def means(expected_counts: str) -> list[float]:
        status, err = _sweep(monkeypatch, capsys, spec, out)
        assert status == 0 and _counts(err) == expected_counts, err
        rows = json.loads((out / "results.json").read_text())
        assert [row["sampler.seed"] for row in rows] == [1, 2]
        assert all((out / row["image"]).is_file() for row in rows)
        return [row["Y_mean"] for row in rows]

    first = means("(2 computed now, 0 already done)")
    assert all(y > 0 for y in first)
    assert means("(0 computed now, 2 already done)") == first

    _glow(tmp_path / "glow.csv", 2.0)  # the asset the scene names
    assert means("(2 computed now, 0 already done)") == pytest.approx([2 * y for y in first], rel=1e-6)

    scene_text = (tmp_path / "screen.toml").read_text().replace('file = "glow.csv"', 'file = "glow.csv", scale = 1.5')
    (tmp_path / "screen.toml").write_text(scene_text)  # the scene file itself
    assert means("(2 computed now, 0 already done)") == pytest.approx([3 * y for y in first], rel=1e-6)
    assert means("(0 computed now, 2 already done)") == pytest.approx([3 * y for y in first], rel=1e-6)

    spec.write_text(spec_text.format("brighter.toml"))  # another scene file
    assert means("(2 computed now, 0 already done)") == pytest.approx([4 * y for y in first], rel=1e-6)


def test_a_display_sweep_rerun_after_its_display_file_changes_recomputes(tmp_path, monkeypatch, capsys):
    """A display given as a CSV file is an input of its items: other primaries in the same file, other numbers,
    which are those of the display the new primaries come from."""
    from spectrace.sweep import display_colour_item

    shipped = spectra_dir() / "displays"
    monkeypatch.chdir(tmp_path)  # a display file is found as `spectrace display` finds it
    (tmp_path / "mine.csv").write_bytes((shipped / "CRT-Dell.csv").read_bytes())
    spec = _display_spec(tmp_path / "sweep.toml", ["mine.csv"])
    out = tmp_path / "results"
    status, err = _sweep(monkeypatch, capsys, spec, out)
    assert status == 0 and _counts(err) == "(2 computed now, 0 already done)", err
    (tmp_path / "mine.csv").write_bytes((shipped / "LCD-Apple_WLED.csv").read_bytes())
    status, err = _sweep(monkeypatch, capsys, spec, out)
    assert status == 0 and _counts(err) == "(2 computed now, 0 already done)", err
    for row in json.loads((out / "results.json").read_text()):
        expected = display_colour_item("LCD-Apple_WLED", row["rgb"], "cie1964_10")
        assert {name: row[name] for name in expected} == expected


def test_item_files_without_the_key_or_from_another_program_are_not_trusted(tmp_path, monkeypatch, capsys):
    from spectrace import sweep as sweeping

    spec = _display_spec(tmp_path / "sweep.toml", ["CRT-Dell"])
    out = tmp_path / "results"
    status, err = _sweep(monkeypatch, capsys, spec, out)
    assert status == 0 and _counts(err) == "(2 computed now, 0 already done)", err
    expected = json.loads((out / "results.json").read_text())
    item_files = sorted((out / "items").iterdir())
    assert len(item_files) == 2
    # An older spectrace's file, with its parameters but no key, and numbers that are not these items' own.
    for path in item_files:
        saved = json.loads(path.read_text())
        path.write_text(json.dumps({"params": saved["params"], "row": {**saved["row"], "Y": -1.0}}))
    status, err = _sweep(monkeypatch, capsys, spec, out)
    assert status == 0 and _counts(err) == "(2 computed now, 0 already done)", err
    assert json.loads((out / "results.json").read_text()) == expected

    monkeypatch.setattr(sweeping, "program_version", lambda: {"version": "other", "kernels": "other"})
    status, err = _sweep(monkeypatch, capsys, spec, out)
    assert status == 0 and _counts(err) == "(2 computed now, 0 already done)", err
    assert json.loads((out / "results.json").read_text()) == expected


def _brightness(level, gain=1.0):
    return {"Y": level * gain}


def _dimness(level, gain=1.0):
    return {"Y": -level * gain}


def test_the_python_sweep_keys_items_by_function_and_inputs(tmp_path):
    from spectrace.sweep import SweepItem, grid_items, run_items, sweep

    grid = {"level": [1.0, 2.0]}
    assert sweep(_brightness, grid, tmp_path) == [{"level": 1.0, "Y": 1.0}, {"level": 2.0, "Y": 2.0}]
    again = [SweepItem(params, _brightness, params) for params in grid_items(grid)]
    assert run_items(again, tmp_path)[1] == 0
    assert sweep(_dimness, grid, tmp_path) == [{"level": 1.0, "Y": -1.0}, {"level": 2.0, "Y": -2.0}]
    # Inputs the grid does not show (here the digest of a calibration the function would read) are part of the key.
    changed = [SweepItem(params, _brightness, params, {"calibration": "v2"}) for params in grid_items(grid)]
    assert run_items(changed, tmp_path)[1] == 2
    assert sweep(_brightness, grid, tmp_path, inputs={"calibration": "v2"}) == [
        {"level": 1.0, "Y": 1.0},
        {"level": 2.0, "Y": 2.0},
    ]


# ---------------------------------------------------------------- specs of the wrong shape

_SCENE = emitting_screen()
_SPECS_ARE_FROM = ("display", "render")

_SCALARS = st.one_of(
    st.integers(min_value=-(2**70), max_value=2**70),
    st.floats(allow_nan=True, allow_infinity=True),
    st.booleans(),
    st.text(max_size=8),
    st.sampled_from(
        [
            "display",
            "render",
            "screen.toml",
            "glow.csv",
            "missing.toml",
            "CRT-Dell",
            "OLED-SonyPVM2541",
            "cie1931_2",
            "cie2012_2",
            "film.width",
            "sampler.spp",
            "materials.black.reflectance",
            "shapes.0.material",
            "",
            "d" * 300,
            0,
            1,
            -1,
            0.5,
            1e400,
            math.nan,
            math.inf,
        ]
    ),
)
_VALUES = st.recursive(
    _SCALARS,
    lambda children: st.one_of(
        st.lists(children, max_size=4),
        st.dictionaries(st.sampled_from(["kind", "scene", "value", "display", "rgb", "x", "film.width"]), children),
    ),
    max_leaves=8,
)
_KEYS = st.sampled_from(
    [
        "sweep",
        "grid",
        "kind",
        "scene",
        "display",
        "rgb",
        "observer",
        "white_luminance",
        "film.width",
        "film.height",
        "sampler.spp",
        "sampler.seed",
        "materials.black.reflectance",
        "shapes.0.material",
        "film",
        "nosuch",
        "",
    ]
)


def _valid_spec(kind: str) -> dict:
    if kind == "display":
        grid = {"display": ["CRT-Dell", "OLED-SonyPVM2541"], "rgb": [[1.0, 0.0, 0.0], [0.5, 0.5, 0.5]]}
        return {"sweep": {"kind": "display"}, "grid": {**grid, "observer": ["cie2012_2"], "white_luminance": [80]}}
    grid = {"film.width": [4, 6], "sampler.spp": [2], "materials.black.reflectance": [{"value": 0.1}]}
    return {"sweep": {"kind": "render", "scene": "screen.toml"}, "grid": grid}


@st.composite
def _mutated_specs(draw) -> dict:
    """A valid spec with a few of its values replaced, keys added or removed, values wrapped in lists or tables."""
    spec = _valid_spec(draw(st.sampled_from(_SPECS_ARE_FROM)))
    for _ in range(draw(st.integers(1, 3))):
        tables = [spec, *(value for value in spec.values() if isinstance(value, dict))]
        table = draw(st.sampled_from(tables))
        keys = list(table)
        action = draw(st.sampled_from(["replace", "replace", "add", "remove", "wrap", "empty", "element"]))
        if not keys or action == "add":
            table[draw(_KEYS)] = draw(_VALUES)
            continue
        key = draw(st.sampled_from(keys))
        if action == "replace":
            table[key] = draw(_VALUES)
        elif action == "remove":
            del table[key]
        elif action == "wrap":
            table[key] = draw(st.sampled_from([[table[key]], {"x": table[key]}]))
        elif action == "empty":
            table[key] = draw(st.sampled_from([[], {}, [[]]]))
        elif isinstance(table[key], list) and table[key]:  # one grid value replaced
            table[key][draw(st.integers(0, len(table[key]) - 1))] = draw(_VALUES)
    return spec


def _toml_value(value) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float) and not math.isfinite(value):
        return "nan" if math.isnan(value) else ("inf" if value > 0 else "-inf")
    if isinstance(value, int | float):
        return repr(value)
    if isinstance(value, str):
        return json.dumps(value, ensure_ascii=False).replace("\x7f", "\\u007f")
    if isinstance(value, list):
        return "[" + ", ".join(map(_toml_value, value)) + "]"
    return "{ " + ", ".join(f"{_toml_value(k)} = {_toml_value(v)}" for k, v in value.items()) + " }"


def _toml(spec: dict) -> str:
    """Every top-level key as one line; inline tables read back as the same tables a [table] would."""
    return "".join(f"{_toml_value(key)} = {_toml_value(value)}\n" for key, value in spec.items())


@pytest.mark.slow
@given(spec=_mutated_specs())
@fuzz_settings(300, [HealthCheck.too_slow, HealthCheck.function_scoped_fixture], database=None)
def test_a_spec_of_any_shape_gives_items_or_one_line_naming_the_spec_file(spec, tmp_path):
    """Whatever the spec holds, reading it gives items ready to compute, or a SpectraceError of one line that
    names the spec file (and, after it, the key path); never another exception."""
    from spectrace.cli.sweep import sweep_items
    from spectrace.sweep import display_colour_item

    (tmp_path / "screen.toml").write_text(_SCENE)
    _glow(tmp_path / "glow.csv", 1.0)
    path = tmp_path / "sweep.toml"
    path.write_text(_toml(spec))
    try:
        items = sweep_items(path, None)
    except SpectraceError as error:
        assert str(error).startswith(f"{path}: ") and str(error).isprintable(), str(error)
        return
    assert items
    first = items[0]
    if first.function is display_colour_item:  # the item's own checks agree with the spec's
        assert set(display_colour_item(**first.arguments)) == {"X", "Y", "Z", "x", "y", "L", "a", "b"}
    else:
        assert isinstance(first.arguments["scene"], Scene)


@pytest.mark.parametrize(
    ("text", "where", "says"),
    [
        ('sweep = [1]\n[grid]\ndisplay = ["CRT-Dell"]\n', "sweep", "expected a table ([sweep]), got an array"),
        ('[sweep]\nkind = "display"\nscene = "x.toml"\n[grid]\nrgb = [[1, 1, 1]]\n', "sweep.scene", "unknown key"),
        ('[sweep]\nkind = "display"\n[grid]\ndisplay = []\nrgb = [[1, 1, 1]]\n', "grid.display", "non-empty list"),
        ('[sweep]\nkind = "display"\n[grid]\ndisplay = ["CRT-Dell"]\nrgb = [[1, nan, 1]]\n', "grid.rgb[0]", "[0, 1]"),
        (
            '[sweep]\nkind = "display"\n[grid]\ndisplay = ["CRT-Dell"]\nrgb = [[1, true, 1]]\n',
            "grid.rgb[0]",
            "an RGB triple is a list of 3 numbers",
        ),
        (
            '[sweep]\nkind = "display"\n[grid]\ndisplay = ["CRT-Dell"]\nrgb = [[1, 1, 1]]\nwhite_luminance = ["9"]\n',
            "grid.white_luminance[0]",
            "a white luminance is a number",
        ),
        (
            '[sweep]\nkind = "render"\nscene = "screen.toml"\n[grid]\nfilm.width = [4]\n',
            "grid.film",
            'quote a dotted key path: "film.width" = [...]',
        ),
        (
            '[sweep]\nkind = "render"\nscene = "screen.toml"\n[grid]\n"film.width" = [4, "wide"]\n',
            'grid."film.width"[1]',
            "expected a whole number",
        ),
    ],
)
def test_a_malformed_spec_is_one_line_naming_its_key_path(text, where, says, tmp_path, monkeypatch, capsys):
    (tmp_path / "screen.toml").write_text(_SCENE)
    spec = tmp_path / "sweep.toml"
    spec.write_text(text)
    status, err = _sweep(monkeypatch, capsys, spec, tmp_path / "out", quiet=True)
    assert status == 2 and err.count("\n") == 1, err
    assert err.startswith(f"error: {spec}: {where}: ") and says in err, err
    assert not (tmp_path / "out").exists()


@pytest.mark.subprocess
@pytest.mark.slow
def test_malformed_specs_in_a_real_process_are_one_line_and_exit_2(tmp_path):
    from cli_runner import run_spectrace

    cases = {
        "tables.toml": ('[[sweep]]\nkind = "display"\n[grid]\ndisplay = ["CRT-Dell"]\n', "sweep"),
        "observer.toml": (
            '[sweep]\nkind = "display"\n[grid]\ndisplay = ["CRT-Dell"]\nrgb = [[1, 1, 1]]\nobserver = [[1]]\n',
            "grid.observer[0]",
        ),
    }
    for name, (text, where) in cases.items():
        spec = tmp_path / name
        spec.write_text(text)
        result = run_spectrace("sweep", str(spec), "-o", str(tmp_path / "out"), timeout=300)
        assert result.returncode == 2 and result.stderr.count("\n") == 1, result.stderr
        assert result.stderr.startswith(f"error: {spec}: {where}: "), result.stderr
        assert "Traceback" not in result.stderr and not (tmp_path / "out").exists()


# ---------------------------------------------------------------- a full disk


def test_a_full_disk_while_saving_items_is_one_line_and_a_rerun_resumes(tmp_path, monkeypatch, capsys):
    """The disk fills up after the first item is saved: one line naming the item's file, the table already there
    is kept, no temporary file is left; with space again, a rerun computes only the items not saved."""
    spec = _display_spec(tmp_path / "sweep.toml", ["CRT-Dell", "LCD-Apple_WLED"])
    out = tmp_path / "results"
    out.mkdir()
    (out / "results.json").write_text("the previous table")
    real_write_text = Path.write_text
    writes = []

    def fills_up(self, text, *args, **kwargs):
        writes.append(self)
        if len(writes) > 1:
            real_write_text(self, text[:10], *args, **kwargs)
            raise OSError(errno.ENOSPC, _ENOSPC)
        return real_write_text(self, text, *args, **kwargs)

    monkeypatch.setattr(Path, "write_text", fills_up)
    status, err = _sweep(monkeypatch, capsys, spec, out, quiet=True)
    monkeypatch.setattr(Path, "write_text", real_write_text)
    assert status == 2 and err.count("\n") == 1 and "Traceback" not in err, err
    assert err.startswith(f"error: {out / 'items'}/") and f"cannot save the sweep item ({_ENOSPC})" in err, err
    assert (out / "results.json").read_text() == "the previous table"
    assert len(list((out / "items").iterdir())) == 1
    assert not [path for path in out.rglob(".*") if path.is_file()]  # no temporary file left

    status, err = _sweep(monkeypatch, capsys, spec, out)
    assert status == 0 and _counts(err) == "(3 computed now, 1 already done)", err
    assert len(json.loads((out / "results.json").read_text())) == 4


_LIMITED_SWEEP = """
import resource, runpy, signal, sys
signal.signal(signal.SIGXFSZ, signal.SIG_IGN)  # a write beyond the limit then fails instead of killing
resource.setrlimit(resource.RLIMIT_FSIZE, (64, 64))
sys.argv = ["spectrace", *sys.argv[1:]]
runpy.run_module("spectrace", run_name="__main__")
"""


@pytest.mark.subprocess
@pytest.mark.slow
@pytest.mark.skipif(not hasattr(signal, "SIGXFSZ"), reason="needs a file size limit (POSIX)")
def test_a_results_table_that_cannot_be_written_is_one_line_and_keeps_the_old_table(tmp_path, monkeypatch, capsys):
    """A real failed write (the file size limit refuses it, as a full disk would): every item is saved already, so
    the rerun writes only the table, which fails as one line; the previous table is kept whole."""
    spec = _display_spec(tmp_path / "sweep.toml", ["CRT-Dell"])
    out = tmp_path / "results"
    status, err = _sweep(monkeypatch, capsys, spec, out)
    assert status == 0, err
    (out / "results.json").write_text("the previous table")
    result = subprocess.run(
        [sys.executable, "-c", _LIMITED_SWEEP, "sweep", str(spec), "-o", str(out), "-q"],
        capture_output=True,
        text=True,
        env=os.environ.copy(),
        timeout=300,
    )
    assert result.returncode == 2 and result.stderr.count("\n") == 1, result.stderr
    assert result.stderr.startswith(f"error: {out / 'results.json'}: cannot write the results table ("), result.stderr
    assert os.strerror(errno.EFBIG) in result.stderr
    assert (out / "results.json").read_text() == "the previous table"
    assert sorted(path.name for path in out.iterdir()) == ["items", "results.csv", "results.json"]
