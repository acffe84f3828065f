"""`spectrace view`'s server over HTTP, without a browser: safe by default (loopback, token, origin, a fixed table
of files, every value checked, many clients), and what the page shows checked against independent references
(colour-science's sRGB and CIEDE2000, the CIE 1931 functions, the exact darkness of a booth whose only light is
off)."""

import contextlib
import io
import json
import socket
import sys
import threading
import time

import numpy as np
import pytest
from tests.viewer.viewer_client import Client

import spectrace

colour = pytest.importorskip("colour")


def _png(client: Client) -> np.ndarray:
    from PIL import Image

    status, body, _ = client.request("GET", "/api/image.png")
    assert status == 200
    return np.asarray(Image.open(io.BytesIO(body)).convert("RGB"))


# ------------------------------------------------------------------ safe by default


def test_listens_on_the_loopback_address(viewer):
    _, server, client = viewer
    assert server.server_address[0] == "127.0.0.1" and server.socket.getsockname()[0] == "127.0.0.1"
    assert client.host == "127.0.0.1"


def test_cannot_be_reached_on_another_address(viewer):
    _, server, _ = viewer
    addresses: set[str] = set()
    with contextlib.suppress(OSError):
        addresses = {str(info[4][0]) for info in socket.getaddrinfo(socket.gethostname(), None, socket.AF_INET)}
    outside = [a for a in addresses if not a.startswith("127.")]
    if not outside:
        pytest.skip("this machine has no address but the loopback one to try")
    with pytest.raises(OSError):
        socket.create_connection((outside[0], server.port), timeout=2).close()


@pytest.mark.parametrize(
    "path", ["/", "/viewer.js", "/api/state", "/api/image.png", "/api/events", "/api/pixel?x=1&y=1"]
)
def test_every_request_needs_the_token(viewer, path):
    _, _, client = viewer
    for token in (None, "wrong", client.token[:-1]):
        query = "" if token is None else ("&" if "?" in path else "?") + f"token={token}"
        status, body, _ = client.request("GET", path + query, token=False)
        assert status == 403
        assert body.decode().strip().count("\n") == 0 and "token" in body.decode()
    status, body, _ = client.request("POST", "/api/pause", {"paused": True}, token=False)
    assert status == 403 and not viewer[0].paused


@pytest.mark.parametrize(
    "headers",
    [
        {"Origin": "http://evil.example"},
        {"Origin": "null"},
        {"Sec-Fetch-Site": "cross-site"},
        {"Host": "evil.example"},  # another name for this address: DNS rebinding
    ],
)
def test_other_sites_are_refused(viewer, headers):
    live, server, client = viewer
    for method, path, body in (
        ("GET", "/api/state", None),
        ("GET", "/api/events", None),  # the event stream: another site's page cannot open it
        ("POST", "/api/pause", {"paused": True}),
        ("POST", "/api/camera", {"action": "orbit", "dx": 30, "dy": 0}),
    ):
        status, reply, _ = client.request(method, path, body, headers=headers)
        assert status == 403, (method, path)
        assert "another site" in reply.decode()
    assert not live.paused and live.session.samples_done == live.spp  # nothing was applied


def test_own_origin_is_served(viewer):
    _, server, client = viewer
    status, _, _ = client.request("GET", "/api/state", headers={"Origin": f"http://127.0.0.1:{server.port}"})
    assert status == 200


def test_no_path_from_a_request_reaches_the_file_system(viewer):
    _, _, client = viewer
    opened: list[str] = []
    watching = threading.Event()

    def audit(event: str, args: tuple) -> None:
        # The event first: the hook stays for the rest of the process, so it must cost next to nothing.
        if event == "open" and watching.is_set() and "process_request" in threading.current_thread().name:
            opened.append(str(args[0]))

    sys.addaudithook(audit)  # hooks cannot be removed: this one is idle once the test ends
    paths = [
        "/../../../../etc/passwd",
        "/%2e%2e/%2e%2e/%2e%2e/etc/passwd",
        "//etc/passwd",
        "/viewer.js/../../pyproject.toml",
        "/static/viewer.js",
        "/index.html",
        "/__init__.py",
        "/server.py",
        "/api/../server.py",
        "/C:%5cWindows%5cwin.ini",
    ]
    watching.set()
    try:
        for path in paths:
            status, body, _ = client.request("GET", path)
            assert status == 404, path
            assert b"root:" not in body and b"import" not in body
        assert client.request("GET", "/viewer.js")[0] == 200
    finally:
        watching.clear()
    assert opened == []


@pytest.mark.parametrize(
    "route, body, where",
    [
        ("/api/display", {"exposure": "bright"}, "exposure"),
        ("/api/display", {"exposure": 1e9}, "exposure"),
        ("/api/display", {"colour_space": "cmyk"}, "colour_space"),
        ("/api/display", {"white_balance": "not a white"}, "white_balance"),
        ("/api/display", {"false_colour": "yes"}, "false_colour"),
        ("/api/display", {"channel": "sensor.nothing"}, "channel"),
        ("/api/display", {"gamma": 2}, "gamma"),
        ("/api/pause", {"paused": "no"}, "paused"),
        ("/api/camera", {"action": "fly", "dx": 1, "dy": 1}, "action"),
        ("/api/camera", {"action": "orbit", "dx": "10", "dy": 0}, "dx"),
        ("/api/camera", {"action": "orbit", "dx": 1e300, "dy": 0}, "dx"),
        ("/api/camera", {"action": "zoom", "dy": 0}, "dy"),
        ("/api/update", {"changes": {"camera.fov": -5}}, "camera.fov"),
        ("/api/update", {"changes": {"camera.origin": [0, "a", 0]}}, "camera.origin"),
        ("/api/update", {"changes": {"no.such.key": 1}}, "no.such.key"),
        ("/api/update", {"changes": []}, "changes"),
        ("/api/pixel-less", {}, None),
        ("/api/reference", {"x": -1, "y": 0}, "x"),
        ("/api/save", {"kind": "image", "name": "../escape.png"}, "name"),
        ("/api/save", {"kind": "image", "name": "picture.bmp"}, "name"),
        ("/api/save", {"kind": "everything", "name": "x.exr"}, "kind"),
    ],
)
def test_a_bad_value_is_one_line_and_changes_nothing(viewer, route, body, where):
    live, _, client = viewer
    before = (live.state()["parameters"], live.display, live.paused, live.session.samples_done)
    status, reply, _ = client.request("POST", route, body)
    assert status in (400, 404)
    if where is not None:
        message = json.loads(reply)["error"]
        assert where in message and "\n" not in message and "Traceback" not in message
    assert (live.state()["parameters"], live.display, live.paused, live.session.samples_done) == before


@pytest.mark.parametrize(
    "body, headers",
    [
        (b"{not json", {}),
        (b'{"exposure": NaN}', {}),  # JSON has no NaN
        (b"[1, 2]", {}),
        (b'{"exposure": 1}', {"Content-Type": "text/plain"}),  # a form another site could post without asking
        (b"x" * (65 * 1024), {}),
    ],
)
def test_malformed_requests_are_refused(viewer, body, headers):
    live, _, client = viewer
    status, reply, _ = client.request("POST", "/api/display", body, headers=headers)
    assert status == 400
    assert "\n" not in json.loads(reply)["error"]
    assert live.display.exposure == 0.0


@pytest.mark.slow
def test_twenty_clients_and_disconnects_mid_pass_leave_it_working(fresh_viewer):
    live, server, client = fresh_viewer
    live.spp = 400  # passes keep coming while the clients come and go
    client.post("/api/pause", {"paused": False})
    failures: list[BaseException] = []

    def one_client(index: int) -> None:
        try:
            connection = socket.create_connection((client.host, client.port), timeout=30)
            request = f"GET /api/events?token={client.token} HTTP/1.1\r\nHost: 127.0.0.1:{client.port}\r\n\r\n"
            connection.sendall(request.encode())
            received = b""
            while b"event: state" not in received:
                received += connection.recv(4096)
            if index % 2:  # half of them leave in the middle of the stream, without a word
                connection.close()
            else:
                for _ in range(3):
                    assert client.state()["target_spp"] == 400
                    client.request("GET", "/api/image.png")
                connection.close()
        except BaseException as error:  # reported below, in the test's thread
            failures.append(error)

    threads = [threading.Thread(target=one_client, args=(i,)) for i in range(20)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join(120)
    assert not failures
    done = client.wait_done(timeout=300)
    assert done["spp"] == 400 and done["error"] == ""
    assert client.request("GET", "/")[0] == 200


# ------------------------------------------------------------------ what the page shows


def test_exposure_changes_the_pixels_without_a_pass(viewer):
    live, _, client = viewer
    before = client.state()
    try:
        status, _ = client.post("/api/display", {"exposure": 1.5})
        assert status == 200
        shown = _png(client)
        after = client.state()
    finally:
        client.post("/api/display", {"exposure": 0.0})
    assert after["spp"] == before["spp"] and live.session.samples_done == before["spp"]  # no new pass
    # colour-science's sRGB of the film XYZ x 2^1.5, 8 bits: the page's pixels to within a code.
    xyz = live.image().xyz.astype(np.float64) * 2.0**1.5
    expected = colour.XYZ_to_sRGB(xyz, apply_cctf_encoding=False, chromatic_adaptation_transform=None)
    expected = np.rint(colour.cctf_encoding(np.clip(expected, 0, 1), function="sRGB") * 255)
    assert np.abs(shown.astype(float) - expected).max() <= 1
    assert np.abs(_png(client).astype(float) - shown).max() > 10  # back at 0 stops: other pixels


def test_orbit_restarts_the_accumulation_and_keeps_the_distance(fresh_viewer):
    live, _, client = fresh_viewer
    before = client.state()["parameters"]
    assert client.post("/api/pause", {"paused": True})[0] == 200  # so that the restart can be seen at 0 spp
    status, _ = client.post("/api/camera", {"action": "orbit", "dx": 20, "dy": 5})
    assert status == 200
    restarted = client.state()
    assert restarted["spp"] == 0 and live.session.samples_done == 0  # the accumulation began again
    assert client.post("/api/pause", {"paused": False})[0] == 200
    after = restarted["parameters"]
    distance = [np.linalg.norm(np.subtract(p["camera.origin"], p["camera.target"])) for p in (before, after)]
    assert distance[1] == pytest.approx(distance[0], rel=1e-9)
    assert after["camera.target"] == before["camera.target"] and after["camera.origin"] != before["camera.origin"]
    assert client.wait_done()["spp"] == live.spp


def _pixel(client: Client, x: int, y: int) -> dict:
    return client.get_json(f"/api/pixel?x={x}&y={y}")


def test_a_red_wall_pixel_shows_a_spectrum_peaking_in_the_red(viewer):
    _, _, client = viewer
    red = _pixel(client, 2, 12)  # the Cornell box's red wall is on the image's left
    wavelengths, radiance = np.array(red["wavelengths_nm"]), np.array(red["radiance"])
    assert wavelengths[np.argmax(radiance)] > 600
    assert red["xy"][0] > 0.45  # a red chromaticity
    # The bands integrated with colour-science's CIE 1931 functions give the pixel's film XYZ (same samples, so the
    # difference is only the 10 nm bands' width).
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
    curves = np.stack([np.interp(wavelengths, cmfs.wavelengths, cmfs.values[:, i]) for i in range(3)])
    step = wavelengths[1] - wavelengths[0]
    ybar_integral = np.trapezoid(cmfs.values[:, 1], cmfs.wavelengths)
    from_bands = curves @ radiance * step / ybar_integral
    assert from_bands == pytest.approx(red["xyz"], rel=0.03)
    assert np.array(red["observer"]["curves"]).shape == (3, wavelengths.size)


def test_a_red_walls_spectrum_averaged_over_its_neighbours_is_nearer_the_converged_one(viewer):
    from tests.viewer.viewer_client import small_scene

    _, _, client = viewer
    one = _pixel(client, 3, 12)
    mean = client.get_json("/api/pixel?x=3&y=12&size=5")  # rows 10-14, columns 1-5: all on the red wall
    assert mean["pixels"] == 25 and "radiance_error" not in one
    wavelengths = np.array(mean["wavelengths_nm"])
    radiance, error = np.array(mean["radiance"]), np.array(mean["radiance_error"])
    # The same bands converged: 64 times the viewer's samples.
    converged = spectrace.render(small_scene(spp=256), spectral_bins=wavelengths.size, progress=False).spectral
    assert np.allclose(converged.centres_nm, wavelengths)
    window = converged.radiance[10:15, 1:6].reshape(25, -1).astype(np.float64)
    truth, truth_error = window.mean(axis=0), window.std(axis=0, ddof=1) / 5
    # Where the wall reflects and the film's wavelengths are dense enough: at 4 spp, 25 pixels draw 400 wavelengths,
    # and beyond 750 nm some 10 nm bands get none (their mean and spread both 0, no estimate of an error).
    red = (wavelengths > 600) & (wavelengths < 750)
    # The mean of 25 pixels is nearer its converged value than one pixel is to its own, by far.
    one_off = np.abs(np.array(one["radiance"]) - converged.radiance[12, 3])[red]
    assert np.sqrt(np.mean((radiance - truth)[red] ** 2)) < 0.5 * np.sqrt(np.mean(one_off**2))
    # Its band is a standard error: the converged mean lies within it as a standard error should (the mean of z²
    # over those bands about 1; the spread between neighbours also holds the wall's shading, which widens it).
    z = (radiance - truth) / np.hypot(error, truth_error)
    assert np.mean(z[red] ** 2) < 4.0
    assert np.all(error[red] < one_off.max())
    # The averaged bands integrated with colour-science's CIE 1931 functions give the averaged XYZ (the 10 nm bands'
    # width apart).
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
    curves = np.stack([np.interp(wavelengths, cmfs.wavelengths, cmfs.values[:, i]) for i in range(3)])
    step = wavelengths[1] - wavelengths[0]
    from_bands = curves @ radiance * step / np.trapezoid(cmfs.values[:, 1], cmfs.wavelengths)
    assert from_bands == pytest.approx(mean["xyz"], rel=0.03)


@pytest.mark.parametrize("size", ["2", "7", "0", "three"])
def test_a_bad_average_size_is_one_line(viewer, size):
    _, _, client = viewer
    status, body, _ = client.request("GET", f"/api/pixel?x=3&y=12&size={size}")
    assert status == 400 and "size" in json.loads(body)["error"]


def test_delta_e_to_the_chosen_reference(viewer):
    live, _, client = viewer
    try:
        assert client.post("/api/reference", {"x": 29, "y": 12})[0] == 200  # the green wall
        green = _pixel(client, 29, 12)
        red = _pixel(client, 2, 12)
    finally:
        live.reference = None
    assert green["delta_e"] == pytest.approx(0.0, abs=1e-9)
    white = colour.xy_to_XYZ(colour.CCS_ILLUMINANTS["CIE 1931 2 Degree Standard Observer"]["D65"])
    lab = [colour.XYZ_to_Lab(np.array(p["xyz"]), colour.XYZ_to_xy(white)) for p in (red, green)]
    # rel: the white's chromaticity here is the tabulated one, the viewer's is D65's spectrum integrated (5th digit).
    assert red["delta_e"] == pytest.approx(float(colour.delta_E(*lab, method="CIE 2000")), rel=1e-4)
    assert red["reference"] == [29, 12]


@pytest.mark.slow  # 25 s on PoCL with its program not yet in the cache
def test_a_light_switched_off_leaves_its_booth_exactly_black(tmp_path):
    from tests.viewer.conftest import _close, _open
    from tests.viewer.viewer_client import small_scene

    live, server, client = _open(small_scene("display_lcd_vs_led.toml", 48, 24, 2), tmp_path)
    try:
        state = client.wait_done()
        keys = sorted(state["lights"])
        assert len(keys) == 2 and all("screen" in key for key in keys)
        left_key = next(key for key in keys if "left" in key)
        lit = live.image().xyz[..., 1]
        assert client.post("/api/update", {"changes": {left_key: 0}})[0] == 200
        client.wait_done()
        dark = live.image().xyz[..., 1]
    finally:
        _close(live, server)
    # The booths face the camera side by side; light that leaves one cannot enter the other.
    assert lit[:, :24].max() > 0 and dark[:, :24].max() == 0.0
    assert dark[:, 24:].max() > 0


def test_save_writes_the_image_and_the_edited_scene(fresh_viewer):
    from spectrace.io.exr import read_exr
    from spectrace.scene import load_scene

    live, server, client = fresh_viewer
    folder = server.save_folder
    assert client.post("/api/camera", {"action": "orbit", "dx": 15, "dy": 0})[0] == 200
    assert client.post("/api/update", {"changes": {"shapes.light.emitter.scale": 0.5}})[0] == 200
    assert client.post("/api/display", {"exposure": 1.0})[0] == 200
    client.wait_done()
    for name in ("view.exr", "view.png"):
        status, reply = client.post("/api/save", {"kind": "image", "name": name})
        assert status == 200 and reply["saved"] == name
    channels, header = read_exr(folder / "view.exr")
    assert np.array_equal(np.stack([channels[c] for c in "XYZ"], axis=-1), live.image().xyz)
    status, reply = client.post("/api/save", {"kind": "scene", "name": "edited.toml"})
    assert status == 200, reply
    saved = load_scene(folder / "edited.toml")
    parameters = client.state()["parameters"]
    assert list(saved.camera.origin) == pytest.approx(parameters["camera.origin"], rel=1e-12)
    assert saved.exposure == 1.0
    light = next(s for s in saved.shapes if s.name == "light")
    original = next(s for s in live.session.scene.shapes if s.name == "light")
    assert np.array_equal(light.emitter.radiance.values, original.emitter.radiance.values)
    assert sorted(p.name for p in folder.iterdir()) == ["edited.toml", "view.exr", "view.png"]
    # The saved scene, read back by the loader, renders the bits the view shows (same seed, size and spp).
    assert (saved.width, saved.height, saved.spp) == (32, 24, 4)
    fresh = spectrace.render(saved, device=live.session.image().device, progress=False)
    assert np.array_equal(fresh.xyz, live.image().xyz)


def test_a_websocket_upgrade_from_another_site_is_refused(viewer):
    _, server, client = viewer
    upgrade = {"Connection": "Upgrade", "Upgrade": "websocket", "Sec-WebSocket-Version": "13"}
    upgrade["Sec-WebSocket-Key"] = "dGhlIHNhbXBsZSBub25jZQ=="
    for path in ("/api/events", "/"):
        status, body, _ = client.request("GET", path, headers={**upgrade, "Origin": "http://evil.example"})
        assert status == 403 and b"another site" in body


@pytest.mark.parametrize("query, where", [("x=abc&y=1", "x and y"), ("x=999&y=1", "x"), ("x=1&y=-1", "y"), ("", "x")])
def test_a_bad_pixel_is_one_line(viewer, query, where):
    _, _, client = viewer
    status, body, _ = client.request("GET", f"/api/pixel?{query}")
    assert status == 400 and where in json.loads(body)["error"]


@pytest.mark.slow
def test_pause_holds_the_samples_and_resume_goes_on(fresh_viewer):
    live, _, client = fresh_viewer
    live.spp = 100_000
    assert client.post("/api/pause", {"paused": False})[0] == 200
    client.wait_for(lambda s: s["spp"] > 4)
    assert client.post("/api/pause", {"paused": True})[0] == 200
    client.wait_for(lambda s: s["paused"])
    time.sleep(0.5)  # the pass in flight (milliseconds here) ends, and the page is shown it
    held = client.state()["spp"]
    time.sleep(0.5)
    assert client.state()["spp"] == held == live.session.samples_done
    assert client.post("/api/pause", {"paused": False})[0] == 200
    client.wait_for(lambda s: s["spp"] > held)
    client.post("/api/pause", {"paused": True})


def test_pan_moves_origin_and_target_alike_and_zoom_scales_the_distance(fresh_viewer):
    _, _, client = fresh_viewer
    before = client.state()["parameters"]
    assert client.post("/api/camera", {"action": "pan", "dx": 0.1, "dy": -0.05})[0] == 200
    panned = client.state()["parameters"]
    shift = np.subtract(panned["camera.origin"], before["camera.origin"])
    assert np.allclose(np.subtract(panned["camera.target"], before["camera.target"]), shift, atol=1e-12)
    view = np.subtract(before["camera.target"], before["camera.origin"])
    assert abs(np.dot(shift, view)) < 1e-9 * np.linalg.norm(view) ** 2  # across the view, not along it
    assert np.linalg.norm(shift) == pytest.approx(np.hypot(0.1, 0.05) * np.linalg.norm(view), rel=1e-9)
    assert client.post("/api/camera", {"action": "zoom", "dy": 0.5})[0] == 200
    zoomed = client.state()["parameters"]
    assert zoomed["camera.target"] == panned["camera.target"]
    assert np.subtract(zoomed["camera.origin"], zoomed["camera.target"]) == pytest.approx(
        0.5 * np.subtract(panned["camera.origin"], panned["camera.target"]), rel=1e-12
    )


@pytest.mark.slow  # the film's observers need a program of their own (40 s to build, once)
def test_another_observer_is_shown_without_a_pass(tmp_path):
    from tests.viewer.conftest import _close, _open
    from tests.viewer.viewer_client import small_scene

    from spectrace.film.response import FilmResponse

    scene = small_scene().with_overrides(film_response=FilmResponse(observers=("CIE 1964 10°",)))
    live, server, client = _open(scene, tmp_path)
    try:
        state = client.wait_done()
        assert state["channels"] == ["CIE 1964 10°"]
        assert client.post("/api/display", {"channel": "CIE 1964 10°"})[0] == 200
        shown = _png(client)
        image = live.image()
        assert client.state()["version"] == state["version"]  # no new pass
    finally:
        _close(live, server)
    xyz = np.stack([image.channels[f"cie1964_10.{axis}"] for axis in "XYZ"], axis=-1).astype(np.float64)
    expected = colour.XYZ_to_sRGB(xyz, apply_cctf_encoding=False, chromatic_adaptation_transform=None)
    expected = np.rint(colour.cctf_encoding(np.clip(expected, 0, 1), function="sRGB") * 255)
    assert np.abs(shown.astype(float) - expected).max() <= 1
    assert not np.array_equal(image.channels["cie1964_10.X"], image.xyz[..., 0])


def test_false_colour_orders_pixels_by_luminance(viewer):
    matplotlib = pytest.importorskip("matplotlib", reason="false colour uses matplotlib's colour maps")
    from spectrace.plots import FALSE_COLOUR_MAP

    live, _, client = viewer
    try:
        assert client.post("/api/display", {"false_colour": True})[0] == 200
        shown = _png(client).reshape(-1, 3).astype(float)
    finally:
        client.post("/api/display", {"false_colour": False})
    luminance = live.image().xyz[..., 1].reshape(-1)
    # Each pixel's position along the colour map (its nearest of 256 entries) rises with its luminance.
    table = matplotlib.colormaps[FALSE_COLOUR_MAP](np.linspace(0, 1, 256))[:, :3] * 255
    position = np.argmin(((shown[:, None, :] - table[None]) ** 2).sum(-1), axis=1)
    lit = luminance > 0
    order = np.argsort(luminance[lit])
    assert np.all(np.diff(position[lit][order]) >= -2)  # 8-bit rounding may swap neighbours
    assert position[lit][order][-1] > position[lit][order][0]


def test_switching_the_observer_renders_again_and_the_spectrum_integrates_with_its_functions(fresh_viewer):
    live, _, client = fresh_viewer
    assert client.state()["observer"] == "CIE 1931 2°" and "CIE 1964 10°" in client.state()["observers"]
    assert client.post("/api/update", {"changes": {"film.observer": "CIE 1964 10°"}})[0] == 200
    state = client.wait_done()
    assert state["observer"] == "CIE 1964 10°" and live.session.scene.film_response.observer == "CIE 1964 10°"
    red = client.get_json("/api/pixel?x=3&y=12&size=3")
    assert red["observer"]["label"] == "CIE 1964 10°"
    # The bands integrated with colour-science's CIE 1964 10° functions give the film's XYZ, now that observer's.
    wavelengths, radiance = np.array(red["wavelengths_nm"]), np.array(red["radiance"])
    cmfs = colour.MSDS_CMFS["CIE 1964 10 Degree Standard Observer"]
    curves = np.stack([np.interp(wavelengths, cmfs.wavelengths, cmfs.values[:, i]) for i in range(3)])
    from_bands = (
        curves @ radiance * (wavelengths[1] - wavelengths[0]) / np.trapezoid(cmfs.values[:, 1], cmfs.wavelengths)
    )
    assert from_bands == pytest.approx(red["xyz"], rel=0.03)
    np.testing.assert_allclose(np.array(red["observer"]["curves"]), curves, rtol=1e-6, atol=1e-9)
    status, body, _ = client.request("POST", "/api/update", {"changes": {"film.observer": "CIE 1999 3°"}})
    assert status == 400 and "film.observer" in json.loads(body)["error"]
