"""The render behind the Blender add-on, in a process of its own (Blender's libraries and the OpenCL runtime never
share one): `python -m spectrace.interop.blender.render_worker SCENE.toml OUT.npy SPP` renders the exported scene and
tells the add-on how far it is, one line on stdout after each pass:

    progress DONE TOTAL          samples per pixel done, of TOTAL
    partial DONE                 the image of DONE samples per pixel written to OUT.partial.npy (as OUT below), for
                                 the add-on to show while the render goes on: after the first pass, then at most
                                 once a second, never after the last pass
    done SPP SECONDS             the image written: OUT.npy, linear Rec.709 RGB as float32 (height, width, 3), rows
                                 top-down

SIGINT or SIGTERM (the add-on's answer to Esc in Blender) ends the render after the pass in flight, and the image of
the samples done is written as at the end. An error is one line on stderr and a non-zero exit."""

from __future__ import annotations

import sys
import time
from pathlib import Path

PARTIAL_SECONDS = 1.0  # the least time between two partial images: reading the film back costs a pass's share


def _say(line: str) -> None:
    print(line, flush=True)


def partial_path(out: Path) -> Path:
    """Where the worker writing `out` leaves its partial images."""
    return out.with_name(out.name.removesuffix(".npy") + ".partial.npy")


def _write_rgb(image, job, path: Path) -> None:
    import numpy as np

    from spectrace.io.atomic import write_atomically

    rgb = np.ascontiguousarray(job.finish(image).to_rgb(), dtype=np.float32)

    def write(target: Path) -> None:
        with open(target, "wb") as handle:
            np.save(handle, rgb)

    write_atomically(path, write)


def render(toml: Path, out: Path, spp: int) -> None:
    from spectrace.api import render_passes
    from spectrace.engine.job import RenderJob
    from spectrace.engine.stop_signals import StopOnSignals
    from spectrace.scene import load_scene

    job = RenderJob.make(lambda: load_scene(toml), spp=spp)
    renderer = job.renderer()
    shown: list[float] = []  # when the last partial image was written

    def progress(done: int, total: int) -> None:
        _say(f"progress {done} {total}")
        if done < total and (not shown or time.monotonic() - shown[-1] >= PARTIAL_SECONDS):
            _write_rgb(renderer.image(), job, partial_path(out))
            shown.append(time.monotonic())
            _say(f"partial {done}")

    with StopOnSignals() as stop:
        image = render_passes(renderer, pass_spp=job.pass_spp, progress=progress, stop=stop)
    if image.spp == 0:
        raise SystemExit("spectrace: stopped before the first pass finished")
    _write_rgb(image, job, out)
    _say(f"done {image.spp} {image.render_seconds:.3f}")


def main(argv: list[str]) -> int:
    from spectrace.errors import SpectraceError

    if len(argv) != 3:
        print("usage: python -m spectrace.interop.blender.render_worker SCENE.toml OUT.npy SPP", file=sys.stderr)
        return 2
    try:
        render(Path(argv[0]), Path(argv[1]), int(argv[2]))
    except SpectraceError as error:
        print(f"spectrace: {error}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
