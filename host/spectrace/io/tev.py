"""Streaming an image to the tev HDR viewer while it renders (`--display-server HOST:PORT`).

The protocol is tev's IPC over TCP, as its sources describe it (Tom94/tev, include/tev/Ipc.h and src/Ipc.cpp):
every packet is a little-endian uint32 holding the packet's whole length (these four bytes included), one byte
naming its type, then the type's fields: a bool is one byte (0 or 1), a string its UTF-8 bytes and a NUL, integers
and floats little-endian. tev never answers, so a client only writes. Used here:

- CreateImage (4): grab_focus bool, name string, width int32, height int32, channel count int32, channel names.
  tev replaces an open image of the same name, so a render started again starts a fresh image.
- UpdateImageV3 (6): grab_focus bool, name string, channel count int32, channel names, x, y, width, height int32
  (a tile of the image), per channel an int64 offset then per channel an int64 stride (in floats), then float32
  data: channel c of the tile's pixel i (row-major) is data[offset[c] + i * stride[c]]; interleaved RGB is offsets
  0, 1, 2 and strides 3.

A viewer is a convenience: `TevDisplay` sends from a thread of its own, so a slow or stalled viewer never slows
the render; a viewer that is absent or goes away costs one warning line and the render goes on (it is looked for
again, quietly, every RETRY_SECONDS).
"""

from __future__ import annotations

import select
import socket
import struct
import threading
import time
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass

import numpy as np

from spectrace.errors import SpectraceError

DEFAULT_PORT = 14158  # tev's own default
CREATE_IMAGE = 4
UPDATE_IMAGE_V3 = 6
TILE = 128  # pixels a side: a tile of three float32 channels is 192 KiB, well inside what tev buffers per packet
RETRY_SECONDS = 5.0
CONNECT_SECONDS = 2.0  # a viewer on another machine may take a moment
SEND_SECONDS = 10.0


@dataclass(frozen=True)
class DisplayServer:
    """Where tev listens: a host name or address and a TCP port."""

    host: str
    port: int

    def __str__(self) -> str:
        return f"[{self.host}]:{self.port}" if ":" in self.host else f"{self.host}:{self.port}"

    @classmethod
    def parse(cls, text: object, where: str | None = None) -> DisplayServer:
        """HOST:PORT ("127.0.0.1:14158", "localhost:14158", "[::1]:14158"); anything else is one SpectraceError
        under `where` (the option or argument)."""
        bad = f"bad host:port {text!r} (use HOST:PORT, e.g. 127.0.0.1:{DEFAULT_PORT})"
        if not isinstance(text, str):
            raise SpectraceError(bad, where=where)
        host, colon, port = text.rpartition(":")
        if host.startswith("[") and host.endswith("]"):
            host = host[1:-1]
        elif ":" in host:  # an IPv6 address needs its brackets, or the port cannot be told from it
            colon = ""
        if not colon or not host or not port.isascii() or not port.isdigit() or not 0 < int(port) < 65536:
            raise SpectraceError(bad, where=where)
        if any(c.isspace() or c in "[]/@" or not c.isprintable() for c in host):
            raise SpectraceError(bad, where=where)
        return cls(host, int(port))


def _string(text: str) -> bytes:
    encoded = text.encode("utf-8")
    if b"\0" in encoded:
        raise ValueError(f"a tev string cannot hold a NUL character: {text!r}")
    return encoded + b"\0"


def _packet(kind: int, body: bytes) -> bytes:
    return struct.pack("<IB", 5 + len(body), kind) + body


def create_image_packet(name: str, width: int, height: int, channels: Sequence[str], grab_focus: bool) -> bytes:
    """The CreateImage packet: an empty image of `channels` (names) in tev."""
    body = struct.pack("<?", grab_focus) + _string(name) + struct.pack("<iii", width, height, len(channels))
    return _packet(CREATE_IMAGE, body + b"".join(_string(c) for c in channels))


def update_image_packet(name: str, channels: Sequence[str], x: int, y: int, pixels: np.ndarray) -> bytes:
    """The UpdateImageV3 packet setting the tile of `pixels` ((rows, columns, channels), interleaved) whose
    top-left pixel is (x, y)."""
    rows, columns, count = pixels.shape
    if count != len(channels):
        raise ValueError(f"{count} channels of pixels for {len(channels)} channel names")
    body = b"".join(
        (
            struct.pack("<?", False),
            _string(name),
            struct.pack("<i", count),
            *(_string(c) for c in channels),
            struct.pack("<iiii", x, y, columns, rows),
            struct.pack(f"<{count}q", *range(count)),
            struct.pack(f"<{count}q", *([count] * count)),
            np.ascontiguousarray(pixels, dtype="<f4").tobytes(),
        )
    )
    return _packet(UPDATE_IMAGE_V3, body)


def image_packets(name: str, channels: Sequence[str], pixels: np.ndarray, tile: int = TILE) -> Iterator[bytes]:
    """The whole of `pixels` ((height, width, channels)) as UpdateImage packets of tiles at most `tile` a side, made
    as they are sent (a large image's packets are not all held at once)."""
    height, width = pixels.shape[:2]
    for y in range(0, height, tile):
        for x in range(0, width, tile):
            yield update_image_packet(name, channels, x, y, pixels[y : y + tile, x : x + tile])


class TevDisplay:
    """One image shown in tev while it renders: `show` hands over the latest pixels and returns at once; a thread
    of its own connects (once, again after RETRY_SECONDS when the viewer was absent or went away), creates the
    image and sends each frame it finds, skipping frames that came while it was sending. `close` sends the last
    frame shown, waiting at most `wait` seconds; `abandon` does not. Every failure is one `warn` line for the whole
    render."""

    def __init__(
        self,
        server: DisplayServer,
        name: str,
        width: int,
        height: int,
        channels: Sequence[str],
        warn: Callable[[str], None],
    ) -> None:
        self.server = server
        self.name = name
        self.size = (width, height)
        self.channels = tuple(channels)
        self._warn = warn
        self._warned = False
        self._socket: socket.socket | None = None
        self._retry_at = 0.0
        self._frame: np.ndarray | None = None
        self._closing = False
        self._ready = threading.Condition()
        # The first connection is tried here, before the render draws its progress bar: a viewer that is not there
        # is then one warning on a line of its own, not one printed by the thread into the bar's line. A viewer
        # that is slow to answer delays the start by CONNECT_SECONDS at most.
        self._connect()
        self._thread = threading.Thread(target=self._run, name="tev display", daemon=True)
        self._thread.start()

    def show(self, pixels: np.ndarray) -> None:
        """Send `pixels` ((height, width, channels)) when the thread is free (a copy: the caller may reuse its
        array)."""
        frame = np.array(pixels, dtype=np.float32)
        with self._ready:
            self._frame = frame
            self._ready.notify()

    def close(self, wait: float = CONNECT_SECONDS + SEND_SECONDS) -> None:
        """Send what `show` left and stop; the image stays open in tev."""
        with self._ready:
            self._closing = True
            self._ready.notify()
        self._thread.join(wait)
        if not self._thread.is_alive() and self._socket is not None:
            self._socket.close()
            self._socket = None

    def abandon(self) -> None:
        """Stop without sending what is left and without waiting (the render was stopped at once)."""
        with self._ready:
            self._frame = None
            self._closing = True
            self._ready.notify()

    def _run(self) -> None:
        while True:
            with self._ready:
                while self._frame is None and not self._closing:
                    self._ready.wait()
                frame, self._frame = self._frame, None
            if frame is None:
                return
            self._send(frame)

    def _send(self, frame: np.ndarray) -> None:
        if self._socket is None or self._peer_closed(self._socket):
            if self._socket is not None:
                self._lost(f"the tev display server at {self.server} closed the connection")
            if time.monotonic() < self._retry_at or not self._connect():
                return
        assert self._socket is not None
        try:
            for packet in image_packets(self.name, self.channels, frame):
                self._socket.sendall(packet)
        except OSError as error:
            self._lost(f"the tev display server at {self.server} stopped taking the image ({_reason(error)})")

    def _connect(self) -> bool:
        try:
            connection = socket.create_connection((self.server.host, self.server.port), timeout=CONNECT_SECONDS)
        except OSError as error:
            self._lost(f"no tev display server at {self.server} ({_reason(error)})")
            return False
        connection.settimeout(SEND_SECONDS)
        connection.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self._socket = connection
        width, height = self.size
        try:
            connection.sendall(create_image_packet(self.name, width, height, self.channels, grab_focus=True))
        except OSError as error:
            self._lost(f"the tev display server at {self.server} stopped taking the image ({_reason(error)})")
            return False
        return True

    @staticmethod
    def _peer_closed(connection: socket.socket) -> bool:
        """Whether the viewer has closed its end: it never writes, so a readable socket is its end of stream (seen
        here before a send, which the system may otherwise buffer without complaint)."""
        try:
            readable, _, _ = select.select([connection], [], [], 0)
            return bool(readable) and connection.recv(1, socket.MSG_PEEK) == b""
        except OSError:
            return True

    def _lost(self, message: str) -> None:
        if self._socket is not None:
            self._socket.close()
            self._socket = None
        self._retry_at = time.monotonic() + RETRY_SECONDS
        if not self._warned:
            self._warned = True
            self._warn(f"{message}; the render goes on without it")


def _reason(error: OSError) -> str:
    if isinstance(error, socket.gaierror):
        return f"unknown host: {error.strerror or error}"
    if isinstance(error, TimeoutError | socket.timeout):
        return "timed out"
    return error.strerror or str(error)
