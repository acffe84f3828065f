"""Ctrl-C (SIGINT), SIGTERM and SIGHUP as a request to stop a render after the pass in flight, so no work is lost.

SIGHUP is what a render gets when its terminal closes (an ssh session dropped, a window shut): its default action
ends the process at once, losing the samples done and the checkpoint, where the user meant no more than SIGTERM.

A signal that raised KeyboardInterrupt wherever Python happened to be could land after a pass has been added to
the film but before the sample count was updated, and the partial image would then be divided by the wrong
count. Here the handler only records the request; the render loop asks between passes. A second signal raises
KeyboardInterrupt at once, for a user who does not want to wait for the pass to end.
"""

import signal
import threading
from collections.abc import Callable
from types import FrameType
from typing import Any

# SIGHUP exists on POSIX systems only.
_STOP_SIGNALS = tuple(getattr(signal, name) for name in ("SIGINT", "SIGTERM", "SIGHUP") if hasattr(signal, name))
# What signal.signal returns and takes back: a handler, SIG_DFL/SIG_IGN, or None (installed outside Python).
_Handler = Callable[[int, FrameType | None], Any] | int | signal.Handlers | None


class StopOnSignals:
    """Context manager: while active, the first SIGINT, SIGTERM or SIGHUP sets `requested`; calling the object
    returns it (usable as Renderer.render's `should_stop`). Previous handlers come back on exit. Outside the main
    thread (where Python cannot install handlers) it installs nothing and never requests a stop."""

    def __init__(self) -> None:
        self.requested = False
        self.signal_name: str | None = None
        self._previous: dict[int, _Handler] = {}

    def __call__(self) -> bool:
        return self.requested

    def _handle(self, signum: int, frame: FrameType | None) -> None:
        if self.requested:
            raise KeyboardInterrupt
        self.requested = True
        self.signal_name = signal.Signals(signum).name

    def __enter__(self) -> "StopOnSignals":
        if threading.current_thread() is threading.main_thread():
            for signum in _STOP_SIGNALS:
                # An ignored signal stays ignored: `nohup spectrace render ...` is meant to outlive its terminal.
                if signal.getsignal(signum) is not signal.SIG_IGN:
                    self._previous[signum] = signal.signal(signum, self._handle)
        return self

    def __exit__(self, *exc_info) -> None:
        for signum, handler in self._previous.items():
            signal.signal(signum, handler)
        self._previous.clear()
