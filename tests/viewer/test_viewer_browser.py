"""The viewer's page in a real browser: Debian's chromium, headless, driven by Playwright (no browser download:
`executable_path`). Skips, saying why, where either is missing; .ci/run installs both."""

import os
import shutil

import numpy as np
import pytest
from tests.viewer.conftest import _close, _open
from tests.viewer.viewer_client import small_scene

sync_api = pytest.importorskip(
    "playwright.sync_api", reason="the browser tests need playwright (the viewer-test extra)"
)
CHROMIUM = os.environ.get("SPECTRACE_CHROMIUM") or shutil.which("chromium") or shutil.which("chromium-browser")
if CHROMIUM is None:
    pytest.skip("the browser tests need Debian's chromium (apt-get install chromium)", allow_module_level=True)

pytestmark = [pytest.mark.subprocess, pytest.mark.slow]


@pytest.fixture(scope="module")
def browser():
    with sync_api.sync_playwright() as playwright:
        # --no-sandbox: chromium's sandbox refuses to start as root, which CI's container is.
        launched = playwright.chromium.launch(executable_path=CHROMIUM, headless=True, args=["--no-sandbox"])
        yield launched
        launched.close()


@pytest.fixture
def page_on(browser, tmp_path):
    opened = []

    def open_page(scene):
        live, server, client = _open(scene, tmp_path)
        page = browser.new_page(viewport={"width": 1280, "height": 900})
        opened.append((live, server, page))
        page.goto(server.url)
        return live, server, client, page

    yield open_page
    for live, server, page in opened:
        page.close()
        _close(live, server)


def _status_spp(page) -> int:
    return int(page.get_attribute("#status", "data-spp") or -1)


def _wait_done(page, spp: int) -> None:
    page.wait_for_function(
        "spp => document.getElementById('image').dataset.spp === String(spp) && "
        "document.getElementById('image').complete",
        arg=spp,
        timeout=120_000,
    )


def _shown_pixels(page, space: str = "srgb") -> np.ndarray:
    """The pixels the page's <img> shows, read back through a canvas of colour space `space` (the browser converts
    the image's colours into it)."""
    data = page.evaluate(
        """space => {
            const image = document.getElementById('image');
            const canvas = document.createElement('canvas');
            canvas.width = image.naturalWidth; canvas.height = image.naturalHeight;
            const context = canvas.getContext('2d', { colorSpace: space });
            context.drawImage(image, 0, 0);
            return Array.from(context.getImageData(0, 0, canvas.width, canvas.height).data);
        }""",
        space,
    )
    return np.array(data, np.uint8)


def _click_pixel(page, x: int, y: int, width: int, height: int) -> None:
    box = page.locator("#image").bounding_box()
    page.mouse.click(box["x"] + (x + 0.5) * box["width"] / width, box["y"] + (y + 0.5) * box["height"] / height)


def _wait_shown(page, version: int) -> None:
    """Until the page shows (loaded) the image of state `version`."""
    page.wait_for_function(
        "v => { const i = document.getElementById('image'); return i.src.includes('v=' + v + '%3A') && i.complete; }",
        arg=version,
        timeout=120_000,
    )


def test_the_image_converges_pass_by_pass(page_on):
    live, _, client, page = page_on(small_scene(spp=24))
    _wait_done(page, 24)
    page.evaluate(
        """() => {
            window.seen = new Set();
            new MutationObserver(() => window.seen.add(document.getElementById('image').src))
                .observe(document.getElementById('image'), { attributes: true });
        }"""
    )
    fov = client.state()["parameters"]["camera.fov"]
    assert client.post("/api/update", {"changes": {"camera.fov": fov}})[0] == 200  # the same view, from 0 spp
    _wait_shown(page, client.wait_done()["version"])
    assert page.evaluate("window.seen.size") >= 2  # the image changed between passes
    assert "24/24 spp" in page.inner_text("#status") and "ETA" in page.inner_text("#status")


def test_exposure_changes_pixels_without_a_new_pass(page_on):
    live, _, _, page = page_on(small_scene())
    _wait_done(page, 4)
    before, version = _shown_pixels(page), live.version
    shown = page.get_attribute("#image", "src")
    page.locator("#exposure").fill("2")
    page.wait_for_function(
        "old => { const i = document.getElementById('image'); return i.getAttribute('src') !== old && i.complete; }",
        arg=shown,
    )
    after = _shown_pixels(page)
    assert live.display.exposure == 2.0 and live.version == version and live.session.samples_done == 4
    assert after.astype(int).sum() > before.astype(int).sum()  # brighter, from the same samples


def test_dragging_orbits_and_restarts_the_accumulation(page_on):
    live, _, client, page = page_on(small_scene())
    _wait_done(page, 4)
    origin = client.state()["parameters"]["camera.origin"]
    version = live.version
    box = page.locator("#image").bounding_box()
    page.mouse.move(box["x"] + box["width"] / 2, box["y"] + box["height"] / 2)
    page.mouse.down()
    page.mouse.move(box["x"] + box["width"] * 0.7, box["y"] + box["height"] / 2, steps=5)
    page.mouse.up()
    client.wait_for(lambda s: s["parameters"]["camera.origin"] != origin)
    assert live.version > version  # restarted: the accumulation began again from the new pose
    _wait_done(page, 4)


def test_clicking_the_red_wall_shows_a_spectrum_peaking_in_the_red(page_on):
    _, _, _, page = page_on(small_scene())
    _wait_done(page, 4)
    _click_pixel(page, 2, 12, 32, 24)
    page.wait_for_function("() => document.getElementById('pixel-text').dataset.peak !== undefined")
    assert float(page.get_attribute("#pixel-text", "data-peak")) > 600
    assert "XYZ" in page.inner_text("#pixel-text") and "xy" in page.inner_text("#pixel-text")
    # Averaged over 5 x 5 pixels: the same pixel again, its mean and a band of one standard error about it.
    band_pixels = "() => { const g = document.getElementById('spectrum').getContext('2d');"
    band_pixels += " const d = g.getImageData(0, 0, 360, 200).data; let n = 0;"
    band_pixels += " for (let i = 0; i < d.length; i += 4) if (d[i + 3] >= 36 && d[i + 3] <= 40) n++; return n; }"
    lines_only = page.evaluate(band_pixels)  # some of the lines' antialiased edges
    page.select_option("#average", "5")
    page.wait_for_function("() => document.getElementById('pixel-text').textContent.includes('mean of 25 pixels')")
    assert page.evaluate(band_pixels) > lines_only + 500  # the band: black at 15 % opacity


def test_switching_off_the_lcd_darkens_its_booth(page_on):
    live, _, client, page = page_on(small_scene("display_lcd_vs_led.toml", 48, 24, 2))
    _wait_done(page, 2)
    left = page.locator("#lights input[type=checkbox][data-key*='left']")
    assert page.locator("#lights input[type=checkbox]").count() == 2
    key = left.get_attribute("data-key")
    left.uncheck()
    state = client.wait_for(lambda s: s["lights"][key] == 0 and s["spp"] == 2)
    _wait_shown(page, state["version"])
    y = live.image().xyz[..., 1]
    assert y[:, :24].max() == 0.0 and y[:, 24:].max() > 0
    shown = _shown_pixels(page).reshape(24, 48, 4)[..., :3]
    assert shown[:, :24].max() == 0 and shown[:, 24:].max() > 0  # what the page shows: the left booth black


def test_save_writes_the_files(page_on):
    _, server, _, page = page_on(small_scene())
    _wait_done(page, 4)
    page.fill("#save-name", "shot.png")
    page.click("#save-image")
    page.wait_for_function("() => document.getElementById('saved').textContent === 'saved shot.png'")
    page.click("#save-scene")
    page.wait_for_function("() => document.getElementById('saved').textContent === 'saved shot.toml'")
    assert sorted(p.name for p in server.save_folder.iterdir()) == ["shot.png", "shot.toml"]


def test_a_bad_value_is_one_line_in_the_page_and_the_render_goes_on(page_on):
    live, _, client, page = page_on(small_scene(spp=6))
    page.fill("#white-balance", "no such white")
    page.press("#white-balance", "Enter")
    page.wait_for_function("() => document.getElementById('error').textContent.includes('white_balance')")
    assert "\n" not in page.inner_text("#error")
    _wait_done(page, 6)


def test_without_the_token_the_page_is_one_line(browser, tmp_path):
    live, server, client = _open(small_scene(), tmp_path)
    page = browser.new_page()
    try:
        page.goto(server.url.split("?")[0])
        text = page.inner_text("body").strip()
    finally:
        page.close()
        _close(live, server)
    assert text.startswith("403") and "token" in text and "\n" not in text


def test_the_page_shows_in_a_frame_of_a_local_page_as_in_a_notebook(browser, tmp_path):
    """The notebook shows the page in a frame of Jupyter's page, another origin: its navigation is let through (the
    token still asked), the page's own requests are then same-origin."""
    import threading
    from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer

    live, server, client = _open(small_scene(), tmp_path)

    class Notebook(BaseHTTPRequestHandler):
        def do_GET(self):  # noqa: N802
            body = f'<iframe id="view" src="{server.url}" width="900" height="600"></iframe>'.encode()
            self.send_response(200)
            self.send_header("Content-Type", "text/html")
            self.send_header("Content-Length", str(len(body)))
            self.end_headers()
            self.wfile.write(body)

        def log_message(self, *args):
            pass

    notebook = ThreadingHTTPServer(("127.0.0.1", 0), Notebook)
    threading.Thread(target=notebook.serve_forever, daemon=True).start()
    page = browser.new_page()
    try:
        page.goto(f"http://localhost:{notebook.server_address[1]}/")
        frame = page.frame_locator("#view")
        frame.locator("#status").filter(has_text="4/4 spp").wait_for(timeout=120_000)
        assert frame.locator("#image").get_attribute("data-spp") == "4"
    finally:
        page.close()
        notebook.shutdown()
        notebook.server_close()
        _close(live, server)


def test_the_wheel_zooms_and_shift_drag_pans(page_on):
    _, _, client, page = page_on(small_scene())
    _wait_done(page, 4)
    before = client.state()["parameters"]
    box = page.locator("#image").bounding_box()
    page.mouse.move(box["x"] + box["width"] / 2, box["y"] + box["height"] / 2)
    page.mouse.wheel(0, 120)  # away: the camera backs off by 1.1
    zoomed = client.wait_for(lambda s: s["parameters"]["camera.origin"] != before["camera.origin"])["parameters"]

    def distance(p):
        return np.linalg.norm(np.subtract(p["camera.origin"], p["camera.target"]))

    assert distance(zoomed) == pytest.approx(1.1 * distance(before), rel=1e-9)
    page.keyboard.down("Shift")
    page.mouse.down()
    page.mouse.move(box["x"] + box["width"] * 0.6, box["y"] + box["height"] / 2, steps=4)
    page.mouse.up()
    page.keyboard.up("Shift")
    panned = client.wait_for(lambda s: s["parameters"]["camera.target"] != zoomed["camera.target"])["parameters"]
    shift = np.subtract(panned["camera.target"], zoomed["camera.target"])
    assert np.allclose(np.subtract(panned["camera.origin"], zoomed["camera.origin"]), shift, atol=1e-12)


@pytest.mark.parametrize("space", ["display-p3", "rec2020"])
def test_a_wide_gamut_image_is_shown_as_its_colours_not_as_srgb(page_on, space):
    from spectrace.film.colour_output import ColourSpace, encode_for_display, xyz_to_output
    from spectrace.io.raster import quantise

    live, _, _, page = page_on(small_scene())
    _wait_done(page, 4)
    shown = page.get_attribute("#image", "src")
    page.select_option("#colour-space", space)
    page.wait_for_function(
        "old => { const i = document.getElementById('image'); return i.getAttribute('src') !== old && i.complete; }",
        arg=shown,
    )
    xyz, exposure = live.image().xyz, live.display.exposure

    def expected(colour_space: ColourSpace) -> np.ndarray:
        encoded = encode_for_display(xyz_to_output(xyz, colour_space, None, exposure), colour_space)
        return quantise(encoded, 8).astype(int)

    sent, srgb = expected(ColourSpace(space)), expected(ColourSpace.SRGB)
    as_srgb = _shown_pixels(page, "srgb").reshape(*xyz.shape[:2], 4)[..., :3].astype(int)
    if space == "display-p3":  # a canvas colour space of Chromium's (Rec.2020 is none)
        # Read back in Display P3, the pixels are the P3 values sent.
        as_p3 = _shown_pixels(page, "display-p3").reshape(*xyz.shape[:2], 4)[..., :3].astype(int)
        assert np.abs(as_p3 - sent).max() <= 1
    # Read back in sRGB, the colours inside sRGB's gamut are their sRGB values: the browser took the image for what
    # it is, not for sRGB, where the walls' values differ by far more than a rounding.
    inside = np.all((srgb > 0) & (srgb < 255), axis=-1)
    assert inside.sum() > xyz.shape[0] * xyz.shape[1] // 2
    assert np.abs(sent - srgb)[inside].max() > 10
    # Within 3 levels: the sent 8-bit values are rounded once in their space, where a level of the wider gamut (and
    # of Rec.2020's steeper curve near black) spans more than one sRGB level, and again in sRGB.
    assert np.abs(as_srgb - srgb)[inside].max() <= 3
