"""Nothing already on disk is lost: a closed terminal (SIGHUP) keeps a render's samples as SIGTERM does, outputs
that cannot even be looked at (a symbolic-link loop, a name too long) are one line, a failed import leaves the
earlier import whole, and two renders, imports or sweeps on one output cannot both write it."""

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from cli_runner import render_cornell_box
from spectrace.engine.checkpoint import read_checkpoint
from spectrace.io.exr import read_exr


def _start_render(out: Path, state: Path, *options: str) -> subprocess.Popen:
    """A real render of the Cornell box that would run for hours, checkpointing after every pass."""
    argv = render_cornell_box(out, 1000000, 16, 12)
    return subprocess.Popen(
        # Not -q: the tests read the lines -q keeps quiet (the interrupted render's "wrote" line).
        [sys.executable, "-m", "spectrace", *argv, "--checkpoint", str(state), "--checkpoint-interval", "0"]
        + list(options),
        stderr=subprocess.PIPE,
        text=True,
        env=os.environ.copy(),
    )


def _wait_for_first_pass(process: subprocess.Popen, state: Path) -> None:
    """Returns once the render has checkpointed its first pass (so it holds its outputs and has samples)."""
    deadline = time.monotonic() + 120
    while not state.exists():
        if time.monotonic() > deadline or process.poll() is not None:
            process.kill()
            pytest.fail(f"the render did not checkpoint a pass: {process.communicate()[1]}")
        time.sleep(0.05)


@pytest.mark.subprocess
@pytest.mark.slow
def test_a_closed_terminal_keeps_the_samples_and_the_checkpoint(device, tmp_path):
    """SIGHUP, which a render gets when its terminal closes, stops it after the pass in flight as SIGTERM does:
    the partial image holds as many samples as the checkpoint, and the exit status is 130."""
    out, state = tmp_path / "partial.exr", tmp_path / "state.npz"
    process = _start_render(out, state)
    try:
        _wait_for_first_pass(process, state)
        process.send_signal(signal.SIGHUP)
        _, stderr = process.communicate(timeout=120)
    finally:
        process.kill()
    assert process.returncode == 130, stderr
    assert "interrupted: partial image" in " ".join(stderr.split()) and "Traceback" not in stderr
    _, header = read_exr(out)
    done = int(header["spectrace:spp"])
    assert 0 < done < 1000000 and read_checkpoint(state).state.samples_done == done
    assert sorted(path.name for path in tmp_path.iterdir()) == ["partial.exr", "state.npz"]  # its locks are gone


def test_an_ignored_hangup_stays_ignored():
    """Under nohup (SIGHUP ignored) a render is meant to outlive its terminal: the stop request leaves it alone."""
    from spectrace.engine.stop_signals import StopOnSignals

    previous = signal.signal(signal.SIGHUP, signal.SIG_IGN)
    try:
        with StopOnSignals() as stop:
            assert signal.getsignal(signal.SIGHUP) is signal.SIG_IGN
            os.kill(os.getpid(), signal.SIGHUP)
            assert not stop()
        assert signal.getsignal(signal.SIGHUP) is signal.SIG_IGN
    finally:
        signal.signal(signal.SIGHUP, previous)


PBRT_PLANE = """LookAt 0 0 5  0 0 0  0 1 0
Camera "perspective" "float fov" 30
Film "rgb" "integer xresolution" 8 "integer yresolution" 6
WorldBegin
LightSource "infinite" "rgb L" [1 1 1]
Shape "trianglemesh" "point3 P" [-9 -9 0  9 -9 0  9 9 0  -9 9 0] "integer indices" [0 1 2 0 2 3]
"""
MITSUBA_CUBE = """<scene version="3.0.0">
<sensor type="perspective"><float name="fov" value="45"/>
<film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="6"/></film></sensor>
<shape type="cube"/>
</scene>
"""


def _every_output_option(tmp_path: Path) -> dict[str, tuple[list[str], str, str]]:
    """name -> (argv before the output's path, the option, the output's suffix): every file a command writes by a
    name the user gives."""
    (tmp_path / "scene.pbrt").write_text(PBRT_PLANE)
    (tmp_path / "scene.xml").write_text(MITSUBA_CUBE)
    from spectrace.resources import scenes_dir

    render = ["render", str(scenes_dir() / "cornell_box.toml"), "--spp", "1", "--width", "8", "--height", "6"]
    good = str(tmp_path / "good.exr")
    return {
        "render -o": ([*render, "-o"], "--output", ".exr"),
        "render --checkpoint": ([*render, "-o", good, "--checkpoint"], "--checkpoint", ".npz"),
        "render --false-color": ([*render, "-o", good, "--false-color"], "--false-color", ".png"),
        "view -o": (["view", str(scenes_dir() / "cornell_box.toml"), "--no-browser", "-o"], "--output", ".exr"),
        "spectra plot -o": (["spectra", "plot", "cie:D65", "-o"], "--output", ".png"),
        "display compare --plot": (
            ["display", "compare", "--rgb", "0.5", "0.5", "0.5", "-d", "CRT-Dell", "--plot"],
            "--plot",
            ".png",
        ),
        "display model --plot": (["display", "model", "LCD-Dell_CCFL", "--plot"], "--plot", ".png"),
        "import-pbrt -o": (["import-pbrt", str(tmp_path / "scene.pbrt"), "-o"], "--output", ".toml"),
        "import-mitsuba -o": (["import-mitsuba", str(tmp_path / "scene.xml"), "-o"], "--output", ".toml"),
        "import-gltf -o": (
            [*_importing("import-gltf"), str(_gltf_quad(tmp_path / "scene.glb")), "-o"],
            "--output",
            ".toml",
        ),
    }


def _importing(command: str) -> list[str]:
    """The command's words before its input: glTF files import their materials as the base colour, diffuse (these
    tests are about the files an import writes, not about materials)."""
    return [command, "--materials", "diffuse"] if command == "import-gltf" else [command]


def _gltf_quad(path: Path, size: float = 1.0, aspect: float = 1.0) -> Path:
    """A glTF file of one quad seen by a camera of aspect ratio `aspect` (the film 640 pixels wide, its height
    640 / aspect)."""
    from tests.interop.gltf_builder import Gltf

    gltf = Gltf()
    gltf.node(mesh=gltf.quad(size=size))
    gltf.node(camera=gltf.camera(type="perspective", perspective={"yfov": 0.8, "aspectRatio": aspect}))
    return gltf.write(path)


@pytest.mark.slow
def test_outputs_through_a_symlink_loop_or_too_long_are_one_line(tmp_path, monkeypatch, capsys):
    """A folder that is a loop of symbolic links, a name over 255 bytes, a path over 4096: for every output option of
    every command, one line naming the option and the path, status 2, and nothing written."""
    from cli_runner import run_in_process

    (tmp_path / "loop").symlink_to("loop")
    commands = _every_output_option(tmp_path)
    before = sorted(path.name for path in tmp_path.iterdir())
    for name, (argv, option, suffix) in commands.items():
        for target, says in [
            (tmp_path / "loop" / f"out{suffix}", "a path that leads through a loop of symbolic links"),
            (tmp_path / ("n" * 300 + suffix), "a path too long for the file system"),
            (tmp_path.joinpath(*["d" * 200] * 25, f"out{suffix}"), "a path too long for the file system"),
        ]:
            status, stderr = run_in_process(monkeypatch, capsys, [*argv, str(target)])
            assert status == 2 and stderr.count("\n") == 1, (name, stderr)
            assert stderr.startswith(f"error: {target}: {option} names {says}"), (name, stderr)
    assert sorted(path.name for path in tmp_path.iterdir()) == before


@pytest.mark.subprocess
@pytest.mark.slow
def test_an_output_in_a_symlink_loop_is_one_line_from_a_real_process(tmp_path):
    from cli_runner import run_spectrace

    (tmp_path / "loop").symlink_to("loop")
    target = tmp_path / "loop" / "out.png"
    result = run_spectrace(*render_cornell_box(target, 1, 8, 6))
    assert result.returncode == 2 and "Traceback" not in result.stderr, result.stderr
    assert result.stderr == f"error: {target}: --output names a path that leads through a loop of symbolic links\n"


def test_a_long_name_the_file_system_takes_is_written(tmp_path, monkeypatch, capsys):
    """A 250-character name is a valid file name, so it must be written: the hidden temporary files beside it are
    cut short, not 250 characters plus their own."""
    from cli_runner import run_in_process

    argv, _, _ = _every_output_option(tmp_path)["spectra plot -o"]
    target = tmp_path / ("n" * 246 + ".png")
    status, stderr = run_in_process(monkeypatch, capsys, [*argv, str(target)])
    assert status == 0 and target.stat().st_size > 0, stderr


def _tree(folder: Path) -> dict[str, bytes]:
    """Every file under `folder` (hidden ones too) by relative name, with its bytes."""
    return {path.relative_to(folder).as_posix(): path.read_bytes() for path in folder.rglob("*") if path.is_file()}


MITSUBA_SPECFILM = """<scene version="3.0.0">
  <sensor type="perspective"><float name="fov" value="30"/>
    <film type="specfilm"><integer name="width" value="WIDTH"/><integer name="height" value="4"/>
      <spectrum name="band" value="500:0, 550:RESPONSE, 600:0"/></film></sensor>
  <shape type="rectangle"><emitter type="area"><rgb name="radiance" value="1"/></emitter></shape>
</scene>
"""


def _importer_cases(tmp_path: Path) -> dict[str, tuple[Path, Path, Path, str]]:
    """importer -> (a scene, another that imports with other files, one whose TOML does not load, where the files
    go beside out.toml)."""
    pbrt = {
        "good": PBRT_PLANE,
        "other": PBRT_PLANE.replace("9 9 0  -9 9 0", "8 8 0  -9 9 0") + PBRT_PLANE.splitlines()[-1] + "\n",
        "bad": PBRT_PLANE.replace('xresolution" 8', 'xresolution" 100000').replace("9 9 0  -9 9 0", "7 7 0  -9 9 0"),
    }
    mitsuba = {
        "good": MITSUBA_SPECFILM.replace("WIDTH", "4").replace("RESPONSE", "1"),
        "other": MITSUBA_SPECFILM.replace("WIDTH", "4").replace("RESPONSE", "0.5"),
        "bad": MITSUBA_SPECFILM.replace("WIDTH", "100000").replace("RESPONSE", "0.25"),
    }
    cases = {}
    for command, suffix, texts, files in [
        ("import-pbrt", ".pbrt", pbrt, "out_assets"),
        ("import-mitsuba", ".xml", mitsuba, "out.sensor.csv"),
    ]:
        sources = tmp_path / "sources" / command
        sources.mkdir(parents=True)
        for name, text in texts.items():
            (sources / f"{name}{suffix}").write_text(text)
        cases[command] = (sources / f"good{suffix}", sources / f"other{suffix}", sources / f"bad{suffix}", files)
    sources = tmp_path / "sources" / "import-gltf"
    sources.mkdir(parents=True)
    cases["import-gltf"] = (
        _gltf_quad(sources / "good.glb"),
        _gltf_quad(sources / "other.glb", size=2.0),
        _gltf_quad(sources / "bad.glb", size=3.0, aspect=0.0064),  # a film 100000 pixels high
        "out_assets",
    )
    return cases


@pytest.mark.parametrize("command", ["import-pbrt", "import-mitsuba", "import-gltf"])
def test_a_failed_import_leaves_the_earlier_import_whole(command, tmp_path, monkeypatch, capsys):
    """An import whose TOML does not load, over an earlier import: one line, status 2, and the earlier TOML and
    the files it refers to (pbrt's meshes folder, Mitsuba's sensor table) byte for byte as they were, with no
    temporary file left. A good import then replaces the TOML and those files together."""
    from cli_runner import run_in_process

    good, other, bad, files = _importer_cases(tmp_path)[command]
    out_folder = tmp_path / "out"
    out_folder.mkdir()
    out = out_folder / "out.toml"
    status, stderr = run_in_process(monkeypatch, capsys, [*_importing(command), str(good), "-o", str(out)])
    assert status == 0 and (out_folder / files).exists(), stderr
    earlier = _tree(out_folder)

    status, stderr = run_in_process(monkeypatch, capsys, [*_importing(command), str(bad), "-o", str(out)])
    assert status == 2 and stderr.count("\n") == 1 and "100000" in stderr, stderr
    assert _tree(out_folder) == earlier
    assert sorted(path.name for path in out_folder.iterdir()) == sorted(["out.toml", files])

    fresh = tmp_path / "fresh" / "out.toml"
    for target in (out, fresh):
        status, stderr = run_in_process(monkeypatch, capsys, [*_importing(command), str(other), "-o", str(target)])
        assert status == 0, stderr
    replaced = _tree(out_folder)
    assert replaced == _tree(fresh.parent)  # nothing of the earlier import's files is left
    assert {n: b for n, b in replaced.items() if n != "out.toml"} != {
        n: b for n, b in earlier.items() if n != "out.toml"
    }


@pytest.mark.parametrize("command", ["import-pbrt", "import-mitsuba", "import-gltf"])
def test_an_import_failing_at_its_last_rename_puts_the_earlier_files_back(command, tmp_path, monkeypatch, capsys):
    """The files are swapped in before the TOML is renamed over the earlier one; if that rename fails (a full
    disk cannot, but a file system can), the earlier files come back."""
    from cli_runner import run_in_process

    good, other, _, files = _importer_cases(tmp_path)[command]
    out = tmp_path / "out" / "out.toml"
    status, stderr = run_in_process(monkeypatch, capsys, [*_importing(command), str(good), "-o", str(out)])
    assert status == 0, stderr
    earlier = _tree(out.parent)

    def failing_replace(source, target):
        raise OSError(5, "Input/output error", str(target))

    monkeypatch.setattr(os, "replace", failing_replace)
    status, stderr = run_in_process(monkeypatch, capsys, [*_importing(command), str(other), "-o", str(out)])
    assert status == 2 and stderr == f"error: {out}: cannot write the TOML or its files (Input/output error)\n"
    assert _tree(out.parent) == earlier
    assert sorted(path.name for path in out.parent.iterdir()) == sorted(["out.toml", files])


def _locks(folder: Path) -> list[str]:
    return sorted(path.name for path in folder.rglob("*.lock"))


@pytest.mark.subprocess
@pytest.mark.slow
def test_a_second_render_on_an_output_in_use_is_refused_naming_the_holder(device, tmp_path):
    """While a render writes out.exr and state.npz, a second render naming either (-o, however spelled;
    --resume of the checkpoint) stops at once: one line naming the option, the file and the first render's pid,
    status 2; the first render goes on, and once it has stopped the lock files are gone and the output is free.
    The first is a real process, as its lock and its SIGTERM must be; the others run here, held off by its lock."""
    from cli_runner import run_here

    out, state = tmp_path / "out.exr", tmp_path / "state.npz"
    (tmp_path / "link").symlink_to(tmp_path, target_is_directory=True)
    first = _start_render(out, state)
    try:
        _wait_for_first_pass(first, state)
        for option, named, argv in [
            ("--output", out, render_cornell_box(out, 1, 8, 6)),
            ("--output", tmp_path / "link" / "out.exr", render_cornell_box(tmp_path / "link" / "out.exr", 1, 8, 6)),
            ("--resume", state, [*render_cornell_box(tmp_path / "other.exr", 1, 8, 6), "--resume", str(state)]),
        ]:
            second = run_here(*argv)
            assert second.returncode == 2 and "Traceback" not in second.stderr, second.stderr
            assert second.stderr.count("\n") == 1, second.stderr
            line = second.stderr
            assert line.startswith(f"error: {named}: {option} is being written by another command"), line
            assert f"pid {first.pid} on " in line, line
            assert first.poll() is None
        assert not (tmp_path / "other.exr").exists()
        first.send_signal(signal.SIGTERM)
        _, stderr = first.communicate(timeout=120)
    finally:
        first.kill()
    assert first.returncode == 130, stderr
    assert _locks(tmp_path) == []
    again = run_here(*render_cornell_box(out, 1, 8, 6))
    assert again.returncode == 0, again.stderr
    assert _locks(tmp_path) == []


def test_a_lock_left_by_a_dead_render_does_not_stop_the_next(tmp_path, monkeypatch, capsys):
    """A render killed outright (kill -9) leaves its lock file, but the kernel has dropped its lock: the next
    render on that output takes it and goes on; an error after the locks are taken releases them too."""
    from cli_runner import run_in_process
    from spectrace.io.output_lock import lock_path_for

    out = tmp_path / "out.png"
    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True, text=True)
    lock_path_for(out).write_text(f"spectrace render, pid {dead.stdout.strip()} on this host, since long ago\n")
    status, stderr = run_in_process(monkeypatch, capsys, render_cornell_box(out, 1, 8, 6) + ["-q"])
    assert status == 0 and out.is_file(), stderr
    assert _locks(tmp_path) == []

    state = tmp_path / "state.npz"
    state.write_bytes(b"not a checkpoint")
    status, stderr = run_in_process(
        monkeypatch, capsys, render_cornell_box(out, 1, 8, 6) + ["--resume", str(state), "-q"]
    )
    assert status == 2 and _locks(tmp_path) == [], stderr


@pytest.mark.parametrize("suffix", [".exr", ".png"])
def test_denoise_replaces_its_own_noisy_image_and_no_other_file(suffix, tmp_path, monkeypatch, capsys):
    """`--denoise -o out.X` keeps the noisy image in out.noisy.X, a file the user did not name: a file there that
    is not the noisy image of an earlier --denoise render of out.X (a photo, another output's noisy image) is
    refused before any work, one line naming --denoise and the file, and left as it was; the render's own noisy
    image is replaced like -o. (The denoiser is a stand-in: only which files are written is tested here.)"""
    import dataclasses

    from cli_runner import run_in_process
    from spectrace import denoising

    monkeypatch.setattr(denoising, "denoise_available", lambda: True)
    monkeypatch.setattr(
        denoising,
        "denoise_with_emission_pass",
        lambda scene, image, device=None, log=print: dataclasses.replace(image, extra={**image.extra, "denoised": "x"}),
    )

    def render(out: Path) -> tuple[int, str]:
        return run_in_process(monkeypatch, capsys, render_cornell_box(out, 1, 8, 6) + ["--denoise", "-q"])

    out, noisy = tmp_path / f"out{suffix}", tmp_path / f"out.noisy{suffix}"
    noisy.write_bytes(b"a photo the user keeps here")
    status, stderr = render(out)
    assert status == 2 and stderr.count("\n") == 1, stderr
    assert stderr.startswith(f"error: {noisy}: --denoise keeps the noisy image in {noisy.name}, which exists"), stderr
    assert noisy.read_bytes() == b"a photo the user keeps here" and not out.exists()

    noisy.unlink()
    for _ in range(2):  # the second render replaces the first one's noisy image
        status, stderr = render(out)
        assert status == 0 and out.is_file() and noisy.is_file(), stderr
    other, others_noisy = tmp_path / f"other{suffix}", tmp_path / f"other.noisy{suffix}"
    others_noisy.write_bytes(noisy.read_bytes())  # out's noisy image, not other's
    status, stderr = render(other)
    assert status == 2 and stderr.startswith(f"error: {others_noisy}: --denoise keeps"), stderr
    assert others_noisy.read_bytes() == noisy.read_bytes() and not other.exists()


@pytest.mark.subprocess
@pytest.mark.parametrize("command", ["import-pbrt", "import-mitsuba", "import-gltf"])
@pytest.mark.slow
def test_an_import_onto_an_output_in_use_is_refused_naming_the_holder(command, tmp_path, monkeypatch, capsys):
    """While another command writes the import's TOML, or the entry beside it that the import swaps in (pbrt's
    `out_assets`, Mitsuba's `out.sensor.csv`, which `-o out` and `-o out.toml` share), a real import process
    stops: one line naming the file, the option and the holder's pid, status 2, the earlier import untouched.
    Once the holder lets go the import goes on and leaves no lock file."""
    from cli_runner import run_in_process, run_spectrace
    from spectrace.io.output_lock import OutputLocks

    good, other, _, files = _importer_cases(tmp_path)[command]
    out = tmp_path / "out" / "out.toml"
    status, stderr = run_in_process(monkeypatch, capsys, [*_importing(command), str(good), "-o", str(out)])
    assert status == 0, stderr
    earlier = _tree(out.parent)
    for held, says in [(out, "--output"), (out.parent / files, f"{files} beside --output")]:
        with OutputLocks({"held": held}, command="another import"):
            result = run_spectrace(*_importing(command), str(other), "-o", str(out), timeout=120)
        assert result.returncode == 2 and result.stderr.count("\n") == 1, result.stderr
        assert result.stderr.startswith(
            f"error: {held}: {says} is being written by another command (another import, pid {os.getpid()} on "
        ), result.stderr
        assert _tree(out.parent) == earlier
    status, stderr = run_in_process(monkeypatch, capsys, [*_importing(command), str(other), "-o", str(out)])
    assert status == 0 and _tree(out.parent) != earlier, stderr
    assert _locks(tmp_path) == []


@pytest.mark.subprocess
@pytest.mark.slow
def test_a_sweep_into_a_folder_in_use_is_refused_naming_the_holder(tmp_path, monkeypatch, capsys):
    """A second sweep into a results folder another sweep is writing would rewrite its table without the first
    one's rows: a real sweep process stops at once, one line naming the folder and the holder's pid, status 2,
    the folder as it was; once the holder lets go the sweep runs and leaves no lock file."""
    from cli_runner import run_in_process, run_spectrace
    from spectrace.io.output_lock import OutputLocks

    spec = tmp_path / "sweep.toml"
    spec.write_text('[sweep]\nkind = "display"\n[grid]\ndisplay = ["CRT-Dell"]\nrgb = [[0.5, 0.5, 0.5]]\n')
    out = tmp_path / "results"
    status, stderr = run_in_process(monkeypatch, capsys, ["sweep", str(spec), "-o", str(out), "-q"])
    assert status == 0, stderr
    earlier = _tree(out)
    spec.write_text('[sweep]\nkind = "display"\n[grid]\ndisplay = ["CRT-Dell"]\nrgb = [[0.5, 0.5, 0.5], [1, 0, 0]]\n')
    with OutputLocks({"held": out}, command="spectrace sweep"):
        result = run_spectrace("sweep", str(spec), "-o", str(tmp_path / "." / "results"), "-q", timeout=120)
    assert result.returncode == 2 and result.stderr.count("\n") == 1, result.stderr
    assert result.stderr.startswith(
        f"error: {tmp_path / '.' / 'results'}: --output is being written by another command (spectrace sweep, "
        f"pid {os.getpid()} on "
    ), result.stderr
    assert _tree(out) == earlier
    status, stderr = run_in_process(monkeypatch, capsys, ["sweep", str(spec), "-o", str(out)])
    assert status == 0 and "2/2 items (1 computed now" in stderr + capsys.readouterr().out, stderr
    assert _locks(tmp_path) == []
