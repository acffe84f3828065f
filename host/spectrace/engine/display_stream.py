"""A render shown in the tev viewer as it converges, for `spectrace render --display-server` and
`spectrace.render(display_server=...)`.

tev gets the values the EXR output holds in its R, G, B channels: linear, in the job's colour space (X, Y, Z for
"xyz"), white-balanced and scaled by 2**exposure as asked (`Image.to_rgb`), so what tev shows, its readouts
included, is the file. tev applies its own display curve. The last frame sent is the image written.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import TYPE_CHECKING

from spectrace.errors import SpectraceError
from spectrace.io.tev import TevDisplay

if TYPE_CHECKING:
    from spectrace.engine.job import RenderJob
    from spectrace.engine.renderer import Renderer
    from spectrace.film.image import Image

CHANNELS = ("R", "G", "B")
# A frame reads the film back and converts it on the render's own thread: frames of a small film every few
# milliseconds would cost as much as its passes, and a large film's take long enough to count, so frames are at
# least FRAME_SECONDS apart and the time spent on them at most about 1/FRAME_SHARE of the render's.
FRAME_SECONDS = 0.2
FRAME_SHARE = 10


class RenderDisplay:
    """The job's image in tev: `after_pass` (between passes) sends the samples so far, at most every
    FRAME_SECONDS and in about 1/FRAME_SHARE of the render's time; `finish` sends the image written and waits for
    it to leave; `close` stops at once (a failed or abandoned render), leaving what tev has."""

    def __init__(self, job: RenderJob, name: str, warn: Callable[[str], None]) -> None:
        assert job.display_server is not None
        self.job = job
        self._display = TevDisplay(job.display_server, name, job.scene.width, job.scene.height, CHANNELS, warn)
        self._next_at = -float("inf")

    def after_pass(self, renderer: Renderer) -> None:
        start = time.monotonic()
        if start < self._next_at:
            return
        try:
            image = renderer.image()
        except SpectraceError:
            pass  # mostly dropped samples so far: the render itself says so at its end
        else:
            self._display.show(self.job.finish(image).to_rgb())
        cost = time.monotonic() - start
        self._next_at = start + max(FRAME_SECONDS, FRAME_SHARE * cost)

    def finish(self, image: Image) -> None:
        self._display.show(self.job.finish(image).to_rgb())
        self._display.close()

    def close(self) -> None:
        self._display.abandon()
