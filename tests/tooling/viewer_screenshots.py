"""Screenshots of `spectrace view`'s page for docs/viewer.md, taken the way the browser tests drive it: Debian's
chromium through Playwright, headless (the `viewer-test` extra; no browser download).

    python -m tests.tooling.viewer_screenshots [--chromium PATH] [--out docs/images]

writes viewer_cornell_box.png (the Cornell box at 48 spp, a red-wall pixel's spectrum shown with ΔE to a green-wall
pixel) and viewer_lcd_vs_led.png (the LCD/LED booths with the LCD's screen switched off)."""

from __future__ import annotations

import argparse
import shutil
import tempfile
from pathlib import Path

from tests.viewer.viewer_client import Client

from spectrace.resources import scenes_dir
from spectrace.scene import load_scene
from spectrace.viewer import start_view


def _view(page, scene, folder: Path):
    live, server = start_view(scene, save_folder=folder)
    client = Client(server.url)
    page.goto(server.url)
    return live, server, client


def _done(page, client: Client) -> None:
    state = client.wait_done(timeout=600)
    page.wait_for_function(
        "v => { const i = document.getElementById('image'); return i.src.includes('v=' + v + '%3A') && i.complete; }",
        arg=state["version"],
        timeout=600_000,
    )


def _click(page, x: int, y: int, width: int, height: int) -> None:
    box = page.locator("#image").bounding_box()
    page.mouse.click(box["x"] + (x + 0.5) * box["width"] / width, box["y"] + (y + 0.5) * box["height"] / height)


def main() -> None:
    from playwright.sync_api import sync_playwright

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--chromium", default=shutil.which("chromium") or shutil.which("chromium-browser"))
    parser.add_argument("--out", type=Path, default=Path("docs/images"))
    arguments = parser.parse_args()
    if arguments.chromium is None:
        raise SystemExit("no chromium found: apt-get install chromium, or pass --chromium PATH")
    folder = Path(tempfile.mkdtemp())
    with sync_playwright() as playwright:
        browser = playwright.chromium.launch(executable_path=arguments.chromium, headless=True, args=["--no-sandbox"])
        page = browser.new_page(viewport={"width": 1100, "height": 760})

        scene = load_scene(scenes_dir() / "cornell_box.toml").with_overrides(width=160, height=160, spp=48)
        live, server, client = _view(page, scene, folder)
        _done(page, client)
        _click(page, 150, 80, 160, 160)  # the green wall, the ΔE reference
        page.wait_for_function("() => document.getElementById('pixel-text').dataset.peak !== undefined")
        page.click("#reference")
        page.wait_for_function("() => document.getElementById('pixel-text').textContent.includes('ΔE2000')")
        _click(page, 10, 80, 160, 160)  # the red wall
        page.wait_for_function("() => document.getElementById('pixel-text').textContent.includes('(10, 80)')")
        page.screenshot(path=str(arguments.out / "viewer_cornell_box.png"))
        server.stop()
        live.close()

        scene = load_scene(scenes_dir() / "display_lcd_vs_led.toml").with_overrides(width=384, height=192, spp=16)
        live, server, client = _view(page, scene, folder)
        _done(page, client)
        page.locator("#lights input[type=checkbox][data-key*='left']").uncheck()
        client.wait_for(lambda s: any(v == 0 for v in s["lights"].values()) and s["spp"] == s["target_spp"], 600)
        _done(page, client)
        page.screenshot(path=str(arguments.out / "viewer_lcd_vs_led.png"))
        server.stop()
        live.close()
        browser.close()
    print(f"wrote {arguments.out / 'viewer_cornell_box.png'} and {arguments.out / 'viewer_lcd_vs_led.png'}")


if __name__ == "__main__":
    main()
