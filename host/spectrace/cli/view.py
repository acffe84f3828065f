"""`spectrace view`: the render in the browser as it converges, with display controls, camera moves, light
switches, saves and a pixel's spectrum (spectrace.viewer; docs/viewer.md). Ctrl-C, SIGTERM or SIGHUP ends it after
the pass in flight and writes the image of the samples done, as `spectrace render` does."""

from __future__ import annotations

import time
from pathlib import Path
from typing import Annotated

import typer

from spectrace.cli.common import DeviceOption, console
from spectrace.errors import SpectraceError


def _say(text: str) -> None:
    console.print(text, highlight=False, markup=False, soft_wrap=True)


def view_command(
    scene: Annotated[
        Path, typer.Argument(help="Scene file (TOML), glTF 2.0 file (.gltf, .glb) or Blender file (.blend).")
    ],
    folder: Annotated[
        Path, typer.Option("--folder", "-f", help="Folder the page saves images and scenes into (names checked).")
    ] = Path("."),
    output: Annotated[
        Path | None,
        typer.Option(
            "--output",
            "-o",
            help="Image written when the viewer is stopped (Ctrl-C): .exr or .png (default: FOLDER/<scene>.exr).",
        ),
    ] = None,
    port: Annotated[int, typer.Option(help="Port on 127.0.0.1 (0: a free one).", min=0, max=65535)] = 0,
    browser: Annotated[bool, typer.Option("--browser/--no-browser", help="Open the page in the browser.")] = True,
    spp: Annotated[int | None, typer.Option(help="Samples per pixel to stop at (default: the scene's).", min=1)] = None,
    pass_spp: Annotated[int, typer.Option(help="Samples per pixel of each pass shown.", min=1)] = 1,
    width: Annotated[int | None, typer.Option(help="Film width in pixels.", min=1)] = None,
    height: Annotated[int | None, typer.Option(help="Film height in pixels.", min=1)] = None,
    seed: Annotated[int | None, typer.Option(help="Sampler seed.", min=0)] = None,
    device: DeviceOption = None,
) -> None:
    """Show SCENE rendering in the browser: a page served on 127.0.0.1 with a random token in its address. Ctrl-C
    stops after the pass in flight and writes the samples done to --output."""
    from spectrace.engine.job import COMMAND_LINE, RenderJob
    from spectrace.engine.stop_signals import StopOnSignals
    from spectrace.interop.scene_files import load_any_scene
    from spectrace.io.output_files import check_output_file
    from spectrace.viewer import start_view

    if not folder.is_dir():
        raise SpectraceError("is no folder", where="--folder")
    image_path = output if output is not None else folder / f"{scene.stem}.exr"
    if image_path.suffix.lower() not in (".exr", ".png"):
        raise SpectraceError(f"unknown image format '{image_path.suffix}' (use .exr or .png)", where=str(image_path))
    check_output_file(image_path, "--output")
    job = RenderJob.make(
        lambda: load_any_scene(scene, report=_say),
        COMMAND_LINE,
        spp=spp,
        width=width,
        height=height,
        seed=seed,
        pass_spp=pass_spp,
        device=device,
    )
    live, server = start_view(job.scene, save_folder=folder, port=port, pass_spp=pass_spp, device=device, log=_say)
    try:
        with StopOnSignals() as stop:
            _say(f"spectrace view: {server.url} (Ctrl-C stops and writes the image)")
            if browser:
                import webbrowser

                webbrowser.open(server.url)
            while not stop.requested:
                time.sleep(0.1)
            live.close()  # after the pass in flight
    finally:
        server.stop()
        live.close()
    image = live.image()
    live.session.close()
    if image is None:
        raise SpectraceError("stopped before the first pass finished; nothing written")
    from spectrace.cli.render_output import write_image

    write_image(image, image_path, include_xyz=True, state_file=None)
    _say(f"wrote {image_path}: {image.width}x{image.height}, {image.spp} spp (stopped)")
    raise typer.Exit(130)
