"""`--display-server` / `display_server=`: the image streamed to the tev viewer as it renders.

The viewer here is a receiver written from tev's description of its IPC packets (a little-endian uint32 length
counting itself, a type byte, then the fields: bools one byte, NUL-terminated strings, int32/int64, float32 data;
CreateImage = 4, UpdateImageV3 = 6, the last with per-channel int64 offsets and strides into its data). It decodes
with `struct` alone, not the client's encoders, so a layout both sides got wrong the same way cannot pass."""

import socket
import struct
import threading
import warnings

import numpy as np
import pytest

from cli_runner import render_cornell_box, run_in_process, run_spectrace
from spectrace.errors import SpectraceError


class Reader:
    def __init__(self, data: bytes):
        self.data, self.at = data, 0

    def take(self, fmt: str):
        values = struct.unpack_from("<" + fmt, self.data, self.at)
        self.at += struct.calcsize("<" + fmt)
        return values if len(values) > 1 else values[0]

    def string(self) -> str:
        end = self.data.index(b"\0", self.at)
        text = self.data[self.at : end].decode("utf-8")
        self.at = end + 1
        return text


def decode(packet: bytes) -> dict:
    reader = Reader(packet)
    length, kind = reader.take("IB")
    assert length == len(packet)
    if kind == 4:
        focus, name = reader.take("B"), reader.string()
        width, height, count = reader.take("iii")
        channels = [reader.string() for _ in range(count)]
        assert reader.at == length
        return {"type": "create", "focus": focus, "name": name, "size": (width, height), "channels": channels}
    assert kind == 6, f"unexpected packet type {kind}"
    focus, name, count = reader.take("B"), reader.string(), reader.take("i")
    channels = [reader.string() for _ in range(count)]
    x, y, width, height = reader.take("iiii")
    offsets = [reader.take("q") for _ in range(count)]
    strides = [reader.take("q") for _ in range(count)]
    data = np.frombuffer(packet, dtype="<f4", offset=reader.at)
    pixels = np.empty((height, width, count), np.float32)
    for c in range(count):
        pixels[..., c] = data[offsets[c] + np.arange(width * height) * strides[c]].reshape(height, width)
    return {"type": "update", "name": name, "channels": channels, "origin": (x, y), "pixels": pixels}


class Receiver:
    """A tev stand-in on 127.0.0.1: takes connections one after the other and decodes what arrives; with
    `hang_up_after` updates it closes the connection and stops listening (a viewer quit mid-render)."""

    def __init__(self, hang_up_after: int | None = None):
        self.server = socket.create_server(("127.0.0.1", 0))
        self.port = self.server.getsockname()[1]
        self.packets: list[dict] = []
        self.hung_up = threading.Event()
        self.stopping = threading.Event()
        self.hang_up_after = hang_up_after
        self.thread = threading.Thread(target=self._serve, daemon=True)
        self.thread.start()

    def _serve(self) -> None:
        self.server.settimeout(0.1)
        while True:
            try:
                connection, _ = self.server.accept()
            except TimeoutError:
                if self.stopping.is_set():
                    return
                continue
            except OSError:
                return
            connection.settimeout(120)
            with connection:
                buffer = b""
                while chunk := connection.recv(1 << 16):
                    buffer += chunk
                    while len(buffer) >= 4 and len(buffer) >= (size := int.from_bytes(buffer[:4], "little")):
                        self.packets.append(decode(buffer[:size]))
                        buffer = buffer[size:]
                    updates = sum(p["type"] == "update" for p in self.packets)
                    if self.hang_up_after is not None and updates >= self.hang_up_after:
                        self.server.close()
                        connection.close()
                        self.hung_up.set()
                        return

    def stop(self) -> None:
        """Wait for the connections made so far to end (the client's last bytes read), then stop listening."""
        self.stopping.set()
        self.thread.join(60)
        self.server.close()


def frame_of(packets: list[dict], width: int, height: int) -> np.ndarray:
    """The image as the viewer holds it after every update."""
    image = np.full((height, width, 3), np.nan, np.float32)
    for packet in packets:
        if packet["type"] == "update":
            x, y = packet["origin"]
            rows, columns = packet["pixels"].shape[:2]
            assert x + columns <= width and y + rows <= height
            image[y : y + rows, x : x + columns] = packet["pixels"]
    return image


def exr_rgb(path) -> np.ndarray:
    import OpenEXR

    with OpenEXR.File(str(path)) as exr:
        return np.array(exr.channels()["RGB"].pixels, dtype=np.float32)


def free_port() -> int:
    """A port nobody listens on (bound, then released)."""
    with socket.create_server(("127.0.0.1", 0)) as probe:
        return probe.getsockname()[1]


@pytest.mark.slow
@pytest.mark.subprocess
def test_render_streams_its_image_and_ends_with_the_file(tmp_path):
    receiver = Receiver()
    out = tmp_path / "box.exr"
    args = [*render_cornell_box(out, 16, 20, 12), "--display-server", f"127.0.0.1:{receiver.port}"]
    result = run_spectrace(*args, "--exposure", "1", "--colour-space", "display-p3")
    receiver.stop()
    assert result.returncode == 0, result.stderr
    assert "\nwarning" not in result.stderr
    create, *updates = receiver.packets
    assert create == {"type": "create", "focus": 1, "name": "box.exr", "size": (20, 12), "channels": ["R", "G", "B"]}
    assert updates and all(p["type"] == "update" and p["name"] == "box.exr" for p in updates)
    assert all(p["channels"] == ["R", "G", "B"] for p in updates)
    written = exr_rgb(out)
    assert written.shape == (12, 20, 3) and written.max() > 0
    np.testing.assert_array_equal(frame_of(receiver.packets, 20, 12), written)
    # the last update covers the whole image: the final frame is the file, not the passes before it
    np.testing.assert_array_equal(updates[-1]["pixels"], written)


@pytest.mark.subprocess
@pytest.mark.slow
def test_no_viewer_is_one_warning_and_the_render_goes_on(tmp_path):
    out = tmp_path / "box.exr"
    result = run_spectrace(*render_cornell_box(out, 4, 8, 8), "--display-server", f"127.0.0.1:{free_port()}")
    assert result.returncode == 0, result.stderr
    warnings_seen = [line for line in result.stderr.splitlines() if line.startswith("warning")]
    assert len(warnings_seen) == 1 and "tev display server" in warnings_seen[0], result.stderr
    assert exr_rgb(out).shape == (8, 8, 3)


def test_viewer_leaving_mid_render_is_one_warning_and_the_render_goes_on():
    """Python API: the viewer quits after the first update; the passes after it and the final frame find it
    gone: one warning, the whole image."""
    import spectrace
    from spectrace.resources import scenes_dir

    receiver = Receiver(hang_up_after=1)
    scene = spectrace.load_scene(scenes_dir() / "cornell_box.toml").with_overrides(width=8, height=6)

    def after_pass(done: int, total: int) -> None:
        if done > 1:  # the first frame has gone out: hold the next passes until the viewer has left
            assert receiver.hung_up.wait(60)

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        image = spectrace.render(
            scene, spp=4, pass_spp=1, progress=after_pass, display_server=f"127.0.0.1:{receiver.port}"
        )
    receiver.stop()
    assert image.spp == 4
    # reading the film for the viewer between passes leaves the render's bits alone
    np.testing.assert_array_equal(image.xyz, spectrace.render(scene, spp=4, pass_spp=1, progress=False).xyz)
    assert [p["type"] for p in receiver.packets] == ["create", "update"]
    messages = [str(w.message) for w in caught if "tev display server" in str(w.message)]
    assert len(messages) == 1 and "closed the connection" in messages[0], messages


@pytest.mark.parametrize(
    "value", ["127.0.0.1", ":14158", "host:", "host:0", "host:65536", "host:1x", "::1:80", "a b:1", "[::1]"]
)
def test_a_bad_host_port_is_one_line_naming_the_option(monkeypatch, capsys, tmp_path, value):
    status, err = run_in_process(
        monkeypatch, capsys, [*render_cornell_box(tmp_path / "x.exr", 1, 8, 8), "--display-server", value]
    )
    assert status != 0
    assert err.strip().count("\n") == 0 and "--display-server: bad host:port" in err, err
    assert not (tmp_path / "x.exr").exists()


@pytest.mark.parametrize(
    ("value", "host", "port"),
    [("127.0.0.1:14158", "127.0.0.1", 14158), ("localhost:1", "localhost", 1), ("[::1]:65535", "::1", 65535)],
)
def test_host_port_forms(value, host, port):
    from spectrace.io.tev import DisplayServer

    assert DisplayServer.parse(value, "--display-server") == DisplayServer(host, port)


def test_python_names_the_argument():
    import spectrace
    from spectrace.resources import scenes_dir

    scene = spectrace.load_scene(scenes_dir() / "cornell_box.toml")
    with pytest.raises(SpectraceError, match="^display_server: bad host:port"):
        spectrace.render(scene, spp=1, display_server="nowhere")


def test_tiles_are_refused_in_one_line(monkeypatch, capsys, tmp_path):
    args = [*render_cornell_box(tmp_path / "x.exr", 1, 8, 8), "--display-server", "127.0.0.1:14158", "--workers", "2"]
    status, err = run_in_process(monkeypatch, capsys, args)
    assert status != 0
    assert err.strip().count("\n") == 0 and "--display-server" in err and "--workers" in err, err


def test_a_frame_larger_than_a_tile_arrives_whole():
    """Frames beyond one packet's tile (128 px a side) arrive as tiles that together are the frame, edge tiles
    included; a later frame replaces an earlier one."""
    from spectrace.io.tev import DisplayServer, TevDisplay

    receiver = Receiver()
    rng = np.random.default_rng(7)
    first, last = (rng.random((140, 300, 3), dtype=np.float32) for _ in range(2))
    seen = []
    display = TevDisplay(DisplayServer("127.0.0.1", receiver.port), "big", 300, 140, ("R", "G", "B"), seen.append)
    display.show(first)
    display.show(last)
    display.close()
    receiver.stop()
    assert seen == []
    updates = [p for p in receiver.packets if p["type"] == "update"]
    assert {p["origin"] for p in updates} >= {(0, 0), (128, 0), (256, 0), (0, 128), (256, 128)}
    assert max(p["pixels"].shape[0] for p in updates) == 128 and max(p["pixels"].shape[1] for p in updates) == 128
    np.testing.assert_array_equal(frame_of(receiver.packets, 300, 140), last)
