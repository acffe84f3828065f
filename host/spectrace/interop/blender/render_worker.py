"""The render behind the Blender add-on, in a process of its own (Blender's libraries and the OpenCL runtime never
share one): `python -m spectrace.interop.blender.render_worker SCENE.toml OUT.npy SPP` renders the exported scene and
tells the add-on how far it is, one line on stdout after each pass:

    progress DONE TOTAL          samples per pixel done, of TOTAL
    done SPP SECONDS             the image written: OUT.npy, linear Rec.709 RGB as float32 (height, width, 3), rows
                                 top-down

SIGINT or SIGTERM (the add-on's answer to Esc in Blender) ends the render after the pass in flight, and the image of
the samples done is written as at the end. An error is one line on stderr and a non-zero exit."""

from __future__ import annotations

import sys
from pathlib import Path


def _say(line: str) -> None:
    print(line, flush=True)


def render(toml: Path, out: Path, spp: int) -> None:
    import numpy as np

    from spectrace.api import render_passes
    from spectrace.engine.job import RenderJob
    from spectrace.engine.stop_signals import StopOnSignals
    from spectrace.io.atomic import write_atomically
    from spectrace.scene import load_scene

    job = RenderJob.make(lambda: load_scene(toml), spp=spp)
    renderer = job.renderer()
    with StopOnSignals() as stop:
        image = render_passes(
            renderer, pass_spp=job.pass_spp, progress=lambda done, total: _say(f"progress {done} {total}"), stop=stop
        )
    if image.spp == 0:
        raise SystemExit("spectrace: stopped before the first pass finished")
    rgb = np.ascontiguousarray(job.finish(image).to_rgb(), dtype=np.float32)

    def write(path: Path) -> None:
        with open(path, "wb") as handle:
            np.save(handle, rgb)

    write_atomically(out, write)
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
