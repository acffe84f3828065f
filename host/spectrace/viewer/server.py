"""The viewer's HTTP server: the standard library's ThreadingHTTPServer on the loopback address, the page's three
files from the package, a JSON API and a Server-Sent Events stream of the render's progress.

Safe by default: it listens on 127.0.0.1 only; every request needs the random token of the printed URL (403
without); a request whose Origin, Host or Sec-Fetch-Site says it comes from another site is refused (403), which
also refuses another site's page opening the event stream; the files served are a fixed table read from the
package when the server starts, so no path from a request reaches the file system; every value a request sends is
checked (spectrace.viewer.live) and a refusal is one line in the page while the render goes on; a client that goes
away mid-stream ends its own thread only."""

from __future__ import annotations

import hmac
import json
import secrets
import threading
from collections.abc import Callable
from dataclasses import replace
from http import HTTPStatus
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from importlib import resources
from pathlib import Path
from typing import Any
from urllib.parse import parse_qs, urlsplit

from spectrace.errors import SpectraceError
from spectrace.viewer.live import LiveView

LOOPBACK = "127.0.0.1"
MAX_BODY_BYTES = 64 * 1024
EVENT_HEARTBEAT_S = 10.0
_STATIC = {  # request path -> (package file, content type)
    "/": ("index.html", "text/html; charset=utf-8"),
    "/viewer.js": ("viewer.js", "text/javascript; charset=utf-8"),
    "/viewer.css": ("viewer.css", "text/css; charset=utf-8"),
}
NO_TOKEN = "403: this page needs the token of the address that spectrace view printed"
OTHER_ORIGIN = "403: requests from another site are refused"


def _static_files(token: str) -> dict[str, tuple[bytes, str]]:
    """The page's files by route, the page's own links carrying the token (every request needs it)."""
    folder = resources.files("spectrace.viewer") / "static"
    return {
        route: ((folder / name).read_bytes().replace(b"__TOKEN__", token.encode()), kind)
        for route, (name, kind) in _STATIC.items()
    }


class ViewerServer(ThreadingHTTPServer):
    """Serves one LiveView at http://127.0.0.1:PORT/?token=TOKEN (`url`) until `shutdown()`."""

    daemon_threads = True  # a stream still open does not hold up the end
    allow_reuse_address = True

    def __init__(
        self,
        live: LiveView,
        save_folder: Path,
        scene_source: Path | None,
        port: int = 0,
        title: str = "spectrace",
        log: Callable[[str], None] | None = None,
    ):
        self.live = live
        self.save_folder = save_folder
        self.scene_source = scene_source
        self.title = title
        self.token = secrets.token_urlsafe(24)
        self.files = _static_files(self.token)
        self.log = log
        self.stopping = threading.Event()
        try:
            super().__init__((LOOPBACK, port), _Handler)
        except OSError as error:
            raise SpectraceError(f"cannot listen on {LOOPBACK}:{port} ({error.strerror or error})", "--port") from None

    @property
    def port(self) -> int:
        return int(self.server_address[1])

    @property
    def url(self) -> str:
        return f"http://{LOOPBACK}:{self.port}/?token={self.token}"

    def serve_in_thread(self) -> threading.Thread:
        thread = threading.Thread(target=self.serve_forever, name="spectrace-view-http", daemon=True)
        thread.start()
        return thread

    def stop(self) -> None:
        self.stopping.set()
        self.shutdown()
        self.server_close()

    def handle_error(self, request, client_address) -> None:
        # A client gone mid-reply (a closed tab) is no error of the server's; anything else is one line.
        import sys

        error = sys.exc_info()[1]
        if not isinstance(error, (ConnectionError, TimeoutError)) and self.log is not None:
            self.log(f"viewer request failed: {type(error).__name__}: {error}")


class _Handler(BaseHTTPRequestHandler):
    server: ViewerServer
    protocol_version = "HTTP/1.1"
    timeout = 30  # a client that sends nothing lets its thread go

    def log_message(self, format: str, *args: Any) -> None:  # noqa: A002 - the base class's name
        pass  # the terminal shows the render, not every request

    # ------------------------------------------------------------ checks every request passes

    def _own_origins(self) -> set[str]:
        port = self.server.port
        return {f"http://{LOOPBACK}:{port}", f"http://localhost:{port}"}

    def _refusal(self) -> tuple[HTTPStatus, str] | None:
        own = self._own_origins()
        host = self.headers.get("Host", "")
        if f"http://{host}" not in own:  # another name for this address (DNS rebinding) is another site
            return HTTPStatus.FORBIDDEN, OTHER_ORIGIN
        origin = self.headers.get("Origin")
        if origin is not None and origin not in own:
            return HTTPStatus.FORBIDDEN, OTHER_ORIGIN
        # The page itself may be opened from another page (the notebook's frame, at Jupyter's address): a
        # navigation, with the token. Anything else a browser marks as sent from another site is refused.
        navigation = self.command == "GET" and urlsplit(self.path).path == "/"
        navigation = navigation and self.headers.get("Sec-Fetch-Mode", "navigate") == "navigate"
        if not navigation and self.headers.get("Sec-Fetch-Site", "same-origin") not in ("same-origin", "none"):
            return HTTPStatus.FORBIDDEN, OTHER_ORIGIN
        token = parse_qs(urlsplit(self.path).query).get("token", [""])[0] or self.headers.get("X-Spectrace-Token", "")
        if not hmac.compare_digest(token.encode(), self.server.token.encode()):
            return HTTPStatus.FORBIDDEN, NO_TOKEN
        return None

    def _send(self, status: HTTPStatus, body: bytes, kind: str, extra: dict[str, str] | None = None) -> None:
        self.send_response(status)
        self.send_header("Content-Type", kind)
        self.send_header("Content-Length", str(len(body)))
        self.send_header("Cache-Control", "no-store")
        self.send_header("X-Content-Type-Options", "nosniff")
        self.send_header("Referrer-Policy", "no-referrer")  # the token stays out of other sites' logs
        self.send_header(
            "Content-Security-Policy",
            # Framed only by pages of this machine (a notebook), never by another site's.
            "default-src 'self'; img-src 'self'; style-src 'self'; script-src 'self'; "
            "frame-ancestors 'self' http://127.0.0.1:* http://localhost:*",
        )
        for name, value in (extra or {}).items():
            self.send_header(name, value)
        self.end_headers()
        if self.command != "HEAD":
            self.wfile.write(body)

    def _text(self, status: HTTPStatus, line: str) -> None:
        self._send(status, (line + "\n").encode(), "text/plain; charset=utf-8")

    def _json(self, value: object, status: HTTPStatus = HTTPStatus.OK) -> None:
        self._send(status, json.dumps(value).encode(), "application/json")

    def _checked(self) -> bool:
        refusal = self._refusal()
        if refusal is not None:
            self._text(*refusal)
            return False
        return True

    # ------------------------------------------------------------ routes

    def do_GET(self) -> None:  # noqa: N802 - http.server's name
        if not self._checked():
            return
        route, query = urlsplit(self.path).path, parse_qs(urlsplit(self.path).query)
        live = self.server.live
        if route in self.server.files:
            body, kind = self.server.files[route]
            self._send(HTTPStatus.OK, body, kind)
        elif route == "/api/state":
            self._json(live.state())
        elif route == "/api/image.png":
            data = live.png()
            if data is None:
                self._send(HTTPStatus.NO_CONTENT, b"", "image/png")
            else:
                self._send(HTTPStatus.OK, data, "image/png")
        elif route == "/api/pixel":
            try:
                x, y = (int(query.get(axis, [""])[0]) for axis in "xy")
            except ValueError:
                self._json({"error": "pixel: x and y must be whole numbers"}, HTTPStatus.BAD_REQUEST)
                return
            try:
                size = int(query.get("size", ["1"])[0])
            except ValueError:
                self._json({"error": "size: must be a whole number"}, HTTPStatus.BAD_REQUEST)
                return
            self._answer(lambda: live.pixel(x, y, size))
        elif route == "/api/events":
            self._events()
        else:
            self._text(HTTPStatus.NOT_FOUND, "404: not a page of this viewer")

    def do_POST(self) -> None:  # noqa: N802 - http.server's name
        if not self._checked():
            return
        route = urlsplit(self.path).path
        if self.headers.get("Content-Type", "").split(";")[0].strip() != "application/json":
            # A form another site posts cannot set this type without asking first (CORS), which is refused.
            self._json({"error": "requests must send JSON (Content-Type: application/json)"}, HTTPStatus.BAD_REQUEST)
            return
        try:
            length = int(self.headers.get("Content-Length", "0"))
        except ValueError:
            length = -1
        if not 0 < length <= MAX_BODY_BYTES:
            self._json({"error": f"a request body must be 1 to {MAX_BODY_BYTES} bytes"}, HTTPStatus.BAD_REQUEST)
            self.close_connection = True
            return
        try:
            data = json.loads(self.rfile.read(length), parse_constant=_no_constant)
        except (ValueError, UnicodeDecodeError) as error:
            self._json({"error": f"the request is not JSON ({error})"}, HTTPStatus.BAD_REQUEST)
            return
        if not isinstance(data, dict):
            self._json({"error": "the request must be a JSON object"}, HTTPStatus.BAD_REQUEST)
            return
        live, server = self.server.live, self.server
        actions: dict[str, Callable[[], object]] = {
            "/api/display": lambda: live.set_display(data),
            "/api/pause": lambda: live.set_paused(data.get("paused")),
            "/api/update": lambda: live.update(data.get("changes")),  # type: ignore[arg-type]
            "/api/camera": lambda: live.move_camera(data.get("action"), data.get("dx", 0), data.get("dy", 0)),
            "/api/reference": lambda: live.set_reference(data.get("x"), data.get("y"), data.get("size", 1)),
            "/api/save": lambda: _save(server, data),
        }
        if route not in actions:
            self._text(HTTPStatus.NOT_FOUND, "404: not a page of this viewer")
            return
        self._answer(actions[route])

    def _answer(self, action: Callable[[], object]) -> None:
        try:
            result = action()
        except SpectraceError as error:
            self._json({"error": str(error)}, HTTPStatus.BAD_REQUEST)
            return
        self._json(result if isinstance(result, dict) else {"ok": True})

    def _events(self) -> None:
        """Server-Sent Events: a `state` event after every pass, restart or setting change, until the client or the
        server goes."""
        self.send_response(HTTPStatus.OK)
        self.send_header("Content-Type", "text/event-stream")
        self.send_header("Cache-Control", "no-store")
        self.end_headers()
        self.close_connection = True
        live: LiveView = self.server.live
        seen: tuple[int, int] | None = None
        while not self.server.stopping.is_set():
            version = live.wait_for_change(seen, EVENT_HEARTBEAT_S)
            if version != seen:
                message = f"event: state\ndata: {json.dumps(live.state())}\n\n"
                seen = version
            else:
                message = ": still here\n\n"
            try:
                self.wfile.write(message.encode())
                self.wfile.flush()
            except (ConnectionError, TimeoutError, OSError):
                return
            if live.closed:
                return


def _no_constant(name: str) -> object:
    raise ValueError(f"{name} is not a number JSON allows")


def _save(server: ViewerServer, data: dict) -> dict[str, object]:
    from spectrace.viewer.saving import save_built_scene, save_image, save_scene

    kind = data.get("kind")
    if kind == "image":
        image = server.live.image()
        if image is None:
            raise SpectraceError("no pass has finished yet", where="save")
        display = server.live.display
        from spectrace.film.colour_output import parse_colour_space, parse_white_balance

        labelled = replace(
            image,
            exposure=display.exposure,
            colour_space=parse_colour_space(display.colour_space),
            white_balance=parse_white_balance(display.white_balance) if display.white_balance else None,
        )
        path = save_image(labelled, server.save_folder, data.get("name"))
    elif kind == "scene":
        # The settings a front end may have changed from the file's (spectrace view's --width, --spp, ...) first.
        scene = server.live.session.scene
        edits: dict[str, object] = {
            "film.width": scene.width,
            "film.height": scene.height,
            "sampler.spp": server.live.spp,
            "sampler.seed": scene.seed,
            **server.live.edits,
        }
        if server.live.display.exposure != server.live.scene_exposure:
            edits["film.exposure"] = server.live.display.exposure
        if server.scene_source is None:  # built in Python: written from its objects, with the page's edits in them
            exposure = server.live.display.exposure
            built = replace(scene, spp=server.live.spp, exposure=exposure)
            path = save_built_scene(built, server.save_folder, data.get("name"))
        else:
            path = save_scene(server.scene_source, edits, server.save_folder, data.get("name"))
    else:
        raise SpectraceError(f"unknown kind {kind!r} (use image or scene)", where="kind")
    return {"ok": True, "saved": path.name}
