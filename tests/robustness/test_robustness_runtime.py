"""Faults at run time: a render too large for the device is refused before anything is allocated, with the
amount; OpenCL errors become one actionable line; non-finite samples are dropped, counted and reported; a stop
request ends the render between passes with the true sample count."""

import errno
import json
import os
import signal
import subprocess
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
import pyopencl as cl
import pytest

from cli_runner import run_in_process
from spectrace import cli
from spectrace.core.limits import format_bytes
from spectrace.engine import memory
from spectrace.engine import renderer as renderer_module
from spectrace.engine.checkpoint import read_checkpoint
from spectrace.engine.memory import device_memory_need
from spectrace.engine.opencl_errors import describe_opencl_error
from spectrace.engine.renderer import Renderer
from spectrace.engine.stop_signals import StopOnSignals
from spectrace.errors import SpectraceError
from spectrace.geometry import primitives
from spectrace.geometry.transforms import apply_transform
from spectrace.resources import scenes_dir
from spectrace.scene import load_scene
from spectrace.scene.model import AreaEmitter, Camera, DiffuseMaterial, Scene, Shape
from spectrace.spectral.spectrum import Spectrum


@pytest.fixture(scope="module")
def cornell():
    return load_scene(scenes_dir() / "cornell_box.toml").with_overrides(width=12, height=10, spp=4)


def _allocated_bytes(renderer) -> int:
    """Bytes of the device buffers the renderer holds, its film's included."""
    total = 0
    for value in [*vars(renderer).values(), *vars(renderer.film).values()]:
        for item in value if isinstance(value, list) else [value]:
            if isinstance(item, cl.Buffer):
                total += item.size
    return total


@pytest.mark.parametrize("spectral_bins", [0, 5])
def test_the_memory_estimate_is_what_the_renderer_allocates(cornell, device, spectral_bins):
    renderer = Renderer(cornell, device, spectral_bins=spectral_bins)
    need = device_memory_need(renderer.buffers, 12 * 10, spectral_bins)
    assert need.total_bytes == _allocated_bytes(renderer)
    assert need.buffers["film"] == 12 * 10 * 16 and need.buffers["ray counts"] == 12 * 10 * 4


class _PyopenclWith:
    """pyopencl as the renderer module sees it, with some functions replaced (the probe that opens devices keeps
    the real ones, so its per-process cache of results is not spoiled)."""

    def __init__(self, **replaced):
        self.__dict__.update(replaced)

    def __getattr__(self, name):
        return getattr(cl, name)


def _refuse_allocations(monkeypatch):
    def no_allocation(*args, **kwargs):
        raise AssertionError("a device buffer was allocated before the memory check")

    monkeypatch.setattr(renderer_module, "cl", _PyopenclWith(Buffer=no_allocation))


def test_a_render_larger_than_the_device_is_refused_before_allocating(cornell, device, monkeypatch):
    big = cornell.with_overrides(width=4000, height=3000)
    expected = Renderer(cornell, device)  # the scene part of the need, measured on a render that fits
    scene_bytes = _allocated_bytes(expected) - 12 * 10 * (16 + 4) - 4  # less film, ray counts, 1-float band buffer
    need_bytes = 4000 * 3000 * (16 + 4) + 4 + scene_bytes
    monkeypatch.setattr(memory, "device_memory_limits", lambda device: (need_bytes - 1, need_bytes))
    _refuse_allocations(monkeypatch)
    with pytest.raises(SpectraceError) as caught:
        Renderer(big, device)
    message = str(caught.value)
    amounts = "film 183.1 MiB, ray counts 45.8 MiB"  # 4000 x 3000 x 16 and x 4 bytes
    assert f"the render needs {format_bytes(need_bytes)} of device memory ({amounts}" in message
    assert f"but {device.report.key} has {format_bytes(need_bytes - 1)}" in message and "\n" not in message


def test_a_buffer_above_the_per_allocation_limit_is_refused(cornell, device, monkeypatch):
    monkeypatch.setattr(memory, "device_memory_limits", lambda device: (1 << 40, 100_000))
    _refuse_allocations(monkeypatch)
    refusal = r"film buffer needs 156\.2 KiB but .* allows at most 97\.7 KiB per buffer"  # 100 x 100 x 16 bytes
    with pytest.raises(SpectraceError, match=refusal):
        Renderer(cornell.with_overrides(width=100, height=100), device)


def test_absurd_sizes_from_python_are_refused_with_their_memory(cornell, device):
    with pytest.raises(SpectraceError, match=r"16384x16384 film .* would need 5\.0 GiB of device memory"):
        Renderer(cornell.with_overrides(width=16384, height=16384), device)
    with pytest.raises(SpectraceError, match="spp 2000000 exceeds the limit of 1048576"):
        Renderer(cornell, device).render(spp=2_000_000)


def _opencl_error(kind, status: str):
    return kind(cl._cl._ErrorRecord("clEnqueueNDRangeKernel", getattr(cl.status_code, status), ""))  # noqa: SLF001


@pytest.mark.parametrize(
    "kind, status, advice",
    [
        (cl.RuntimeError, "OUT_OF_RESOURCES", "lower --width/--height, or choose another device"),
        (cl.MemoryError, "MEM_OBJECT_ALLOCATION_FAILURE", "lower --width/--height"),
        (cl.LogicError, "DEVICE_NOT_AVAILABLE", "resume from the last checkpoint with --resume"),
        (cl.LogicError, "INVALID_KERNEL_ARGS", "see `spectrace devices`"),
    ],
)
def test_enqueue_errors_become_one_actionable_line(cornell, device, monkeypatch, kind, status, advice):
    renderer = Renderer(cornell, device)

    def failing_enqueue(*args, **kwargs):
        raise _opencl_error(kind, status)

    monkeypatch.setattr(renderer_module, "cl", _PyopenclWith(enqueue_nd_range_kernel=failing_enqueue))
    with pytest.raises(SpectraceError) as caught:
        renderer.run_pass(1)
    message = str(caught.value)
    assert message.startswith(
        f"OpenCL error while running a render pass on {device.report.key}: clEnqueueNDRangeKernel failed: {status}"
    )
    assert advice in message and "\n" not in message


def test_an_opencl_error_in_the_command_line_is_one_line(tmp_path, monkeypatch, capsys):
    def failing_enqueue(*args, **kwargs):
        raise _opencl_error(cl.RuntimeError, "OUT_OF_RESOURCES")

    monkeypatch.setattr(renderer_module, "cl", _PyopenclWith(enqueue_nd_range_kernel=failing_enqueue))
    status, stderr = _render_cornell(
        monkeypatch, capsys, "-o", str(tmp_path / "x.png"), "--width", "8", "--height", "8", "-q"
    )
    assert status == 2 and "Traceback" not in stderr
    error_lines = [line for line in stderr.splitlines() if line.startswith("error: ")]
    assert len(error_lines) == 1 and "OUT_OF_RESOURCES" in error_lines[0]
    assert not (tmp_path / "x.png").exists()


def test_host_memory_exhaustion_is_described():
    text = describe_opencl_error(MemoryError(), "reading the film", "some-device")
    assert text == "out of host memory while reading the film on some-device: lower --width/--height"


def _overflowing_light_scene() -> Scene:
    """A camera looking straight at an emitter so bright (3e38 W/(m² sr nm), the float32 limit) that every
    sample's XYZ estimate, L·cmf/p(λ), overflows to infinity."""
    wall = apply_transform(primitives.rectangle(), np.diag([10.0, 10.0, 1.0, 1.0]))
    light = Shape(
        wall, DiffuseMaterial(Spectrum.constant(0.5)), emitter=AreaEmitter(Spectrum.constant(3e38)), name="too bright"
    )
    return Scene(
        camera=Camera(origin=(0, 0, 5), target=(0, 0, 0), fov_degrees=30),
        width=6,
        height=5,
        shapes=[light],
        spp=3,
        max_depth=1,
    )


def test_a_render_of_dropped_samples_fails_naming_the_emitter(device, tmp_path, monkeypatch, capsys):
    """Every sample overflows: the render refuses to give a black image, in the API and on the command line (one
    line naming the emitter, exit 2, nothing written)."""
    scene = _overflowing_light_scene()
    with pytest.raises(SpectraceError) as failure:
        Renderer(scene, device).render()
    message = str(failure.value)
    assert "every one of the render's 90 samples" in message and "shape 'too bright'" in message

    monkeypatch.setattr("spectrace.interop.scene_files.load_any_scene", lambda path, overrides=None, report=None: scene)
    monkeypatch.setattr(sys, "argv", ["spectrace", "render", "ignored.toml", "-o", str(tmp_path / "cli.png"), "-q"])
    with pytest.raises(SystemExit) as exit_info:
        cli.main()
    assert exit_info.value.code == 2
    errors = [line for line in capsys.readouterr().err.splitlines() if line.startswith("error: ")]
    assert len(errors) == 1 and "NaN or infinite" in errors[0] and "too bright" in errors[0]
    assert not (tmp_path / "cli.png").exists()


def test_a_few_dropped_samples_are_counted_and_reported(device, tmp_path, monkeypatch, capsys):
    """Below spectrace.film.state.DROPPED_FAIL_FRACTION the image is written, the count in its metadata and a warning:
    here the overflowing emitter covers the left eighth of the view (x from -3 to -1 where the view spans ±1.34),
    in front of a plain one."""
    from spectrace.film.state import DROPPED_FAIL_FRACTION

    scene = _overflowing_light_scene()
    edge = np.diag([1.0, 10.0, 1.0, 1.0])
    edge[0, 3] = -2.0  # x from -3 to -1 of a 30 degree view 2 * 5 tan 15° (about 2.7) wide
    bright = replace(scene.shapes[0], mesh=apply_transform(primitives.rectangle(), edge))
    grey = Shape(
        apply_transform(primitives.rectangle(), np.diag([10.0, 10.0, 1.0, 1.0]) @ _translation(0, 0, -1)),
        DiffuseMaterial(Spectrum.constant(0.5)),
        emitter=AreaEmitter(Spectrum.constant(1.0)),
        name="plain",
    )
    scene = replace(scene, shapes=[bright, grey])
    image = Renderer(scene, device).render()
    assert 0 < image.dropped_samples < DROPPED_FAIL_FRACTION * 6 * 5 * 3
    image.write(tmp_path / "dropped.png")
    from PIL import Image as PILImage

    with PILImage.open(tmp_path / "dropped.png") as written:
        assert written.text["spectrace:dropped_samples"] == str(image.dropped_samples)

    monkeypatch.setattr("spectrace.interop.scene_files.load_any_scene", lambda path, overrides=None, report=None: scene)
    monkeypatch.setattr(sys, "argv", ["spectrace", "render", "ignored.toml", "-o", str(tmp_path / "cli.png"), "-q"])
    with pytest.raises(SystemExit) as exit_info:
        cli.main()
    assert exit_info.value.code == 0
    expected = f"warning: {image.dropped_samples} non-finite samples were dropped"
    assert expected in " ".join(capsys.readouterr().err.split())


def _translation(x: float, y: float, z: float) -> np.ndarray:
    matrix = np.eye(4)
    matrix[:3, 3] = (x, y, z)
    return matrix


def test_a_stop_request_ends_the_render_between_passes_with_the_true_count(cornell, device):
    asked = []

    def stop_after_two_passes() -> bool:
        asked.append(1)
        return len(asked) > 2

    stopped = Renderer(cornell, device).render(spp=100, pass_spp=3, should_stop=stop_after_two_passes)
    assert stopped.spp == 6
    assert np.array_equal(stopped.xyz, Renderer(cornell, device).render(spp=6).xyz)


def test_the_first_signal_asks_to_stop_and_the_second_interrupts():
    previous = signal.getsignal(signal.SIGTERM)
    # raise_signal delivers to this (the main) thread, so the handler runs before the next line; os.kill may be taken
    # by another thread of a test worker, and the main thread then sees it a few lines later (it failed so, loaded).
    with StopOnSignals() as stop:
        assert not stop()
        signal.raise_signal(signal.SIGTERM)
        assert stop() and stop.signal_name == "SIGTERM"
        with pytest.raises(KeyboardInterrupt):
            signal.raise_signal(signal.SIGINT)
    assert signal.getsignal(signal.SIGTERM) is previous


def test_an_opencl_error_mid_render_points_at_the_last_checkpoint(tmp_path, monkeypatch, capsys):
    calls = []

    def enqueue_then_fail(*args, **kwargs):
        calls.append(1)
        if len(calls) > 2:
            raise _opencl_error(cl.LogicError, "DEVICE_NOT_AVAILABLE")
        return cl.enqueue_nd_range_kernel(*args, **kwargs)

    monkeypatch.setattr(renderer_module, "cl", _PyopenclWith(enqueue_nd_range_kernel=enqueue_then_fail))
    state = tmp_path / "state.npz"
    status, stderr = _render_cornell(
        monkeypatch,
        capsys,
        "-o",
        str(tmp_path / "x.png"),
        "--width",
        "8",
        "--height",
        "8",
        "--spp",
        "1000",
        "--checkpoint",
        str(state),
        "--checkpoint-interval",
        "0",
        "-q",
    )
    error_lines = [line for line in stderr.splitlines() if line.startswith("error: ")]
    assert status == 2 and len(error_lines) == 1
    saved = read_checkpoint(state).state.samples_done
    assert saved > 0 and "DEVICE_NOT_AVAILABLE" in error_lines[0]
    assert error_lines[0].endswith(f"{state} holds the last {saved} spp (continue with --resume)")


# ---------------------------------------------------------------- every writer, when the disk fills up

_ENOSPC = os.strerror(errno.ENOSPC)


def _fill_the_disk_in(monkeypatch, kind: str) -> None:
    """Make one writer fail as on a full disk, after writing part of its temporary file: OpenEXR with its own
    RuntimeError (which names the system's reason), the display-image writer (PNG, through its atomic write) and
    matplotlib with OSError."""

    def partial_then_full(path):
        Path(path).write_bytes(b"partial")
        return OSError(errno.ENOSPC, _ENOSPC)

    if kind == "exr":
        from spectrace.io import exr

        class FullFile:
            def __init__(self, header, channels):
                pass

            def __enter__(self):
                return self

            def __exit__(self, *exc):
                return False

            def write(self, path):
                partial_then_full(path)
                raise RuntimeError(f'Failed to write pixel data to image file "{path}". {_ENOSPC}.')

        monkeypatch.setattr(exr, "OpenEXR", _Namespace(exr.OpenEXR, File=FullFile))
    elif kind == "png":
        from spectrace.io import raster

        atomic_write = raster.write_atomically

        def full_disk(path, write):
            def write_part(temp):
                raise partial_then_full(temp)

            return atomic_write(path, write_part)

        monkeypatch.setattr(raster, "write_atomically", full_disk)
    else:
        from matplotlib.figure import Figure

        def savefig(self, path, **kwargs):
            raise partial_then_full(path)

        monkeypatch.setattr(Figure, "savefig", savefig)


class _Namespace:
    """A module with some attributes replaced."""

    def __init__(self, module, **replaced):
        self._module = module
        self.__dict__.update(replaced)

    def __getattr__(self, name):
        return getattr(self._module, name)


def _render_cornell(monkeypatch, capsys, *argv) -> tuple[int, str]:
    """`spectrace render` of the bundled Cornell box with ARGV, in this process: exit status and stderr."""
    return run_in_process(monkeypatch, capsys, ["render", str(scenes_dir() / "cornell_box.toml"), *argv])


def _render_cli(monkeypatch, capsys, *argv) -> tuple[int, str]:
    return _render_cornell(monkeypatch, capsys, "--width", "8", "--height", "6", "--spp", "1", "-q", *argv)


@pytest.mark.parametrize("suffix", ["exr", "png"])
def test_a_full_disk_is_one_line_and_the_old_image_survives(suffix, tmp_path, monkeypatch, capsys):
    out, state = tmp_path / f"out.{suffix}", tmp_path / "state.npz"
    out.write_bytes(b"the previous image")
    _fill_the_disk_in(monkeypatch, suffix)
    status, stderr = _render_cli(monkeypatch, capsys, "-o", str(out), "--checkpoint", str(state))
    errors = [line for line in stderr.splitlines() if not line.startswith(("device: ", "scene: "))]
    assert status == 2 and "Traceback" not in stderr, stderr
    assert errors == [
        f"error: {out}: cannot write the image ({_ENOSPC}); the render's state is in {state} (continue with --resume)"
    ]
    assert out.read_bytes() == b"the previous image"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out." + suffix, "state.npz"]  # no temporary file left


def test_a_full_disk_for_the_false_colour_map_is_one_line(tmp_path, monkeypatch, capsys):
    out, figure = tmp_path / "out.png", tmp_path / "map.png"
    figure.write_bytes(b"the previous map")
    _fill_the_disk_in(monkeypatch, "figure")
    status, stderr = _render_cli(monkeypatch, capsys, "-o", str(out), "--false-color", str(figure))
    errors = [line for line in stderr.splitlines() if not line.startswith(("device: ", "scene: "))]
    assert status == 2 and errors == [f"error: {figure}: cannot write the figure ({_ENOSPC})"], stderr
    assert figure.read_bytes() == b"the previous map" and out.is_file()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["map.png", "out.png"]


def test_figure_commands_refuse_unwritable_outputs_and_survive_a_full_disk(tmp_path, monkeypatch, capsys):
    (tmp_path / "folder.png").mkdir()
    commands = {
        "spectra plot": (["spectra", "plot", "cie:D65", "-o"], "--output"),
        "display compare": (["display", "compare", "--rgb", "0.5", "0.5", "0.5", "-d", "CRT-Dell", "--plot"], "--plot"),
    }
    for name, (argv, option) in commands.items():
        for target, says in [
            (tmp_path / "folder.png", f"{option} names a folder; name a file in it"),
            (tmp_path / "nope" / "x.png", f"the folder {tmp_path / 'nope'} for {option} does not exist"),
        ]:
            status, stderr = run_in_process(monkeypatch, capsys, [*argv, str(target)])
            assert status == 2 and stderr == f"error: {target}: {says}\n", (name, stderr)

    _fill_the_disk_in(monkeypatch, "figure")
    for name, (argv, _option) in commands.items():
        target = tmp_path / "kept.png"
        target.write_bytes(b"the previous figure")
        status, stderr = run_in_process(monkeypatch, capsys, [*argv, str(target)])
        assert status == 2 and stderr.count("\n") == 1, (name, stderr)
        assert stderr.startswith(f"error: {target}: cannot write the ") and f"({_ENOSPC})" in stderr, stderr
        assert target.read_bytes() == b"the previous figure"
        assert sorted(p.name for p in tmp_path.iterdir()) == ["folder.png", "kept.png"]


# A real write failure, not an imitation: the file size limit makes the operating system refuse the write (EFBIG),
# as a full disk refuses it (ENOSPC), and OpenEXR reports it in its own words.
_SIZE_LIMITED_WRITE = r"""
import json, resource, signal, sys
import numpy as np
from pathlib import Path
signal.signal(signal.SIGXFSZ, signal.SIG_IGN)  # a write beyond the limit then fails instead of killing
resource.setrlimit(resource.RLIMIT_FSIZE, (16384, 16384))
from spectrace.io.exr import write_exr
from spectrace.io.raster import write_display_image as write_png
out = Path(sys.argv[1])
pixels = np.random.default_rng(1).random((128, 128, 3), dtype=np.float32)
try:
    if out.suffix == ".exr":
        write_exr(out, pixels, pixels, {})
    else:
        write_png(out, pixels, {})
except OSError as error:
    print(json.dumps([error.errno, error.strerror]))
"""


@pytest.mark.skipif(not hasattr(signal, "SIGXFSZ"), reason="needs a file size limit (POSIX)")
@pytest.mark.parametrize("suffix", ["exr", "png"])
def test_a_real_failed_write_is_an_os_error_and_leaves_the_old_file(suffix, tmp_path):
    out = tmp_path / f"image.{suffix}"
    out.write_bytes(b"the previous image")
    result = subprocess.run(
        [sys.executable, "-c", _SIZE_LIMITED_WRITE, str(out)],
        capture_output=True,
        text=True,
        env=os.environ.copy(),
        timeout=120,
    )
    assert result.returncode == 0, result.stderr
    assert json.loads(result.stdout) == [errno.EFBIG, os.strerror(errno.EFBIG)]
    assert out.read_bytes() == b"the previous image" and [p.name for p in tmp_path.iterdir()] == [out.name]


@pytest.mark.skipif(not hasattr(signal, "SIGXFSZ"), reason="needs a file size limit (POSIX)")
@pytest.mark.slow
def test_a_real_process_whose_figure_cannot_be_written_prints_one_line(tmp_path):
    import resource

    def limit_file_size():
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
        resource.setrlimit(resource.RLIMIT_FSIZE, (4096, 4096))

    out = tmp_path / "spectra.png"
    out.write_bytes(b"the previous figure")
    result = subprocess.run(
        [sys.executable, "-m", "spectrace", "spectra", "plot", "cie:D65", "cie:A", "-o", str(out)],
        capture_output=True,
        text=True,
        env=os.environ.copy(),
        preexec_fn=limit_file_size,
        timeout=300,
    )
    assert result.returncode == 2 and "Traceback" not in result.stderr
    assert result.stderr == f"error: {out}: cannot write the figure ({os.strerror(errno.EFBIG)})\n"
    assert out.read_bytes() == b"the previous figure" and [p.name for p in tmp_path.iterdir()] == [out.name]
