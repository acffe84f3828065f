"""The live view of a render: `spectrace view SCENE` in the browser, `spectrace.view(scene)` in a notebook
(docs/viewer.md). Both run a `spectrace.session.Session` on a thread of its own (spectrace.viewer.live) behind a
small HTTP server on the loopback address (spectrace.viewer.server) whose page shows the image pass by pass."""

from __future__ import annotations

import html
import time
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

from spectrace.errors import SpectraceError
from spectrace.session import Session
from spectrace.viewer.live import LiveView
from spectrace.viewer.server import ViewerServer

BAND_NM = 10.0  # the width of the spectral bins the viewer asks of the session


def spectral_bins_for(scene: Any) -> int:
    """Bands of about BAND_NM over the film's wavelengths (a pixel's spectrum in the page)."""
    from spectrace.film.state import spectral_range

    low, high = spectral_range(scene)
    return max(1, round((high - low) / BAND_NM))


def start_view(
    scene: Any,
    *,
    save_folder: Path = Path("."),
    port: int = 0,
    pass_spp: int = 1,
    device: Any = None,
    log: Callable[[str], None] | None = None,
) -> tuple[LiveView, ViewerServer]:
    """Open a session on `scene` (its spp is where the render stops), start its render thread and a server; the
    caller stops both (`server.stop()`, `live.close()`, `live.session.close()`)."""
    session = Session(scene, device=device, spectral_bins=spectral_bins_for(scene), pass_spp=pass_spp)
    live = LiveView(session, scene.spp, pass_spp=pass_spp, scene_exposure=float(scene.exposure))
    try:
        server = ViewerServer(live, save_folder, scene.source, port=port, log=log)
    except BaseException:
        session.close()
        raise
    live.start()
    server.serve_in_thread()
    return live, server


class _SharedSession:
    """The view's session for code beside the page: each call waits for the pass in flight, and an update wakes
    the render thread (and is kept for the saved scene) as the page's own edits are."""

    def __init__(self, live: LiveView):
        self._live = live

    def update(self, changes: Mapping[str, object]) -> None:
        self._live.update(changes)

    def __getattr__(self, name: str) -> Any:
        value = getattr(self._live.session, name)
        if not callable(value):
            with self._live.session_lock:
                return getattr(self._live.session, name)

        def locked(*args: Any, **kwargs: Any) -> Any:
            with self._live.session_lock:
                return value(*args, **kwargs)

        return locked


class ViewerWidget:
    """What `spectrace.view` returns: shown in a notebook as the viewer's page in a frame, updating each pass;
    `session` edits the scene while it renders (`widget.session.update({"camera.fov": 30})`)."""

    def __init__(self, live: LiveView, server: ViewerServer, height: int):
        self._live = live
        self._server = server
        self._height = height
        self.session = _SharedSession(live)

    @property
    def url(self) -> str:
        return self._server.url

    @property
    def samples_done(self) -> int:
        image = self._live.image()
        return image.spp if image is not None else 0

    def image(self):
        """The image of the samples so far (None before the first pass)."""
        return self._live.image()

    def wait(self, spp: int | None = None, timeout: float = 600.0) -> int:
        """Wait until `spp` samples per pixel (default: the scene's) are done or `timeout` seconds pass; the spp."""
        wanted = self._live.spp if spp is None else spp
        end = time.monotonic() + timeout
        seen: tuple[int, int] | None = None
        while self.samples_done < wanted and time.monotonic() < end and not self._live.closed:
            seen = self._live.wait_for_change(seen, min(1.0, max(0.0, end - time.monotonic())))
        return self.samples_done

    def close(self) -> None:
        self._server.stop()
        self._live.close()
        self._live.session.close()

    def _repr_html_(self) -> str:
        return (
            f'<iframe src="{html.escape(self.url)}" width="100%" height="{self._height}" '
            'style="border: 0" title="spectrace view"></iframe>'
        )

    def __enter__(self) -> ViewerWidget:
        return self

    def __exit__(self, *_: object) -> None:
        self.close()


def view(
    scene: Any,
    *,
    save_folder: str | Path = ".",
    port: int = 0,
    pass_spp: int = 1,
    device: Any = None,
    height: int = 720,
) -> ViewerWidget:
    """The live view of `scene` (a spectrace.Scene) for a notebook: the same page as `spectrace view`, served on
    127.0.0.1 and shown in a frame, rendering pass by pass up to the scene's spp. Saves go to `save_folder`."""
    from spectrace.scene.model import Scene

    if not isinstance(scene, Scene):
        raise SpectraceError(f"view() needs a spectrace.Scene, got {type(scene).__name__} (load_scene reads a file)")
    folder = Path(save_folder)
    if not folder.is_dir():
        raise SpectraceError("is no folder", where=str(folder))
    live, server = start_view(scene, save_folder=folder, port=port, pass_spp=pass_spp, device=device)
    return ViewerWidget(live, server, height)
