"""What a newcomer meets first: install hints printed whole, help readable when piped, a progress bar in a bare
Jupyter, the bundled scenes by name from any folder, a short repr of an image."""

import ast
import os
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

import spectrace
from cli_runner import run_here
from spectrace import progress
from spectrace.resources import bundled_scene_names

PACKAGE = Path(spectrace.__file__).parent


def _spectrace(*args, cwd=None) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "spectrace", *args],
        capture_output=True,
        text=True,
        cwd=cwd,
        env=os.environ.copy(),
        timeout=300,
    )


@pytest.mark.slow
def test_every_rich_console_prints_text_as_it_is():
    """rich reads '[bench]' in "pip install 'spectrace[bench]'" as a style and drops it: every Console the package
    makes has markup off (messages, tables and notes are plain text)."""
    consoles = []
    for path in PACKAGE.rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Call) and getattr(node.func, "id", None) == "Console":
                markup = [k.value for k in node.keywords if k.arg == "markup"]
                consoles.append((f"{path.relative_to(PACKAGE)}:{node.lineno}", markup))
    assert consoles
    assert [
        where
        for where, markup in consoles
        if not (len(markup) == 1 and isinstance(markup[0], ast.Constant) and markup[0].value is False)
    ] == []


def test_a_note_with_brackets_prints_whole():
    from spectrace.cli import console

    with console.capture() as captured:
        console.print("mitsuba is not installed (pip install 'spectrace[bench]')", highlight=False)
    assert "spectrace[bench]" in captured.get()


@pytest.mark.subprocess
def test_piped_help_names_every_option_whole():
    import typer

    from spectrace.cli import app

    render = typer.main.get_command(app).commands["render"]
    names = [name for param in render.params for name in (*param.opts, *param.secondary_opts) if name.startswith("-")]
    env = {k: v for k, v in os.environ.items() if k not in ("COLUMNS", "TERMINAL_WIDTH")}
    result = subprocess.run(
        [sys.executable, "-m", "spectrace", "render", "--help"], capture_output=True, text=True, env=env, timeout=120
    )
    assert result.returncode == 0, result.stderr
    assert "…" not in result.stdout
    words = set(result.stdout.replace(",", " ").split())
    assert [name for name in names if name not in words] == []


def test_progress_auto_in_jupyter_without_ipywidgets_is_a_text_bar(device, monkeypatch, capsys):
    monkeypatch.setattr(progress, "in_notebook", lambda: True)
    monkeypatch.setattr(progress, "has_ipywidgets", lambda: False)
    scene = spectrace.load_scene("cornell_box").with_overrides(width=8, height=8, spp=2)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # tqdm's and rich's notebook bars warn without ipywidgets
        image = spectrace.render(scene, device=device, progress="auto", pass_spp=1)
    assert image.spp == 2
    err = capsys.readouterr().err
    assert "rendering |" in err and "2/2 spp" in err and err.endswith("\n")


def test_bundled_scenes_load_by_name_from_any_folder(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    by_name = spectrace.load_scene("cornell_box")
    assert by_name.width > 0 and spectrace.load_scene("cornell_box.toml").width == by_name.width
    with pytest.raises(spectrace.SpectraceError) as error:
        spectrace.load_scene("cornel_box")
    assert "cornell_box" in str(error.value) and "material_showcase" in str(error.value)


def test_a_local_file_comes_before_the_bundled_scene(tmp_path, monkeypatch):
    from spectrace.resources import resolve_scene_path, scenes_dir

    monkeypatch.chdir(tmp_path)
    assert resolve_scene_path("cornell_box") == scenes_dir() / "cornell_box.toml"
    (tmp_path / "cornell_box.toml").write_text("# mine\n")
    assert resolve_scene_path("cornell_box") == Path("cornell_box.toml")


def test_a_folder_named_like_a_bundled_scene_does_not_hide_it(tmp_path, monkeypatch):
    # Working in scenes/ (or beside a copy of a scene's folder), `cornell_box` is also the folder of its meshes.
    from spectrace.resources import resolve_scene_path, scenes_dir

    monkeypatch.chdir(tmp_path)
    (tmp_path / "teapot").mkdir()
    (tmp_path / "no_such_scene").mkdir()
    assert resolve_scene_path("teapot") == scenes_dir() / "teapot.toml"
    assert resolve_scene_path("no_such_scene") == Path("no_such_scene")  # the loader says it is a folder


@pytest.mark.subprocess
@pytest.mark.slow
def test_render_a_bundled_scene_by_name_from_another_folder(tmp_path, monkeypatch):
    """The render through the entry point in this process; the unknown name's refusal in a real one."""
    monkeypatch.chdir(tmp_path)
    result = run_here("render", "cornell_box", "-o", "x.png", "--width", "8", "--height", "8", "--spp", "1", "-q")
    assert result.returncode == 0, result.stderr
    assert (tmp_path / "x.png").is_file()
    unknown = _spectrace("render", "no_such_scene", "-o", "x.png", cwd=tmp_path)
    assert unknown.returncode != 0 and "Traceback" not in unknown.stderr
    lines = unknown.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: no_such_scene:")
    assert all(name in lines[0] for name in bundled_scene_names())


def test_image_repr_is_short():
    image = spectrace.Image(
        xyz=np.zeros((64, 64, 3), np.float32), spp=16, seed=7, device="pocl:cpu:0", render_seconds=0.25
    )
    text = repr(image)
    assert len(text) < 200
    assert "64x64" in text and "spp=16" in text and "seed=7" in text
