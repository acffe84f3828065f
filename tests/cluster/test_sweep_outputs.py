"""A render sweep's images are named by their parameters (safe characters, unique also where case is ignored) and
written in the formats the spec asks for, each holding the same render."""

import hashlib
import json
from types import SimpleNamespace

import numpy as np
from PIL import Image as PILImage

from cli_runner import run_in_process
from scene_text import emitting_screen
from spectrace.io.exr import read_exr
from spectrace.sweep import image_stems


def _items(*params: dict) -> list:
    return [SimpleNamespace(params=p, key=hashlib.sha256(json.dumps(p).encode()).hexdigest()) for p in params]


def test_image_names_are_the_parameters_made_safe_and_unique():
    stems = image_stems(_items({"sampler.spp": 64, "materials.red.roughness": 0.2}, {"sampler.spp": 64, "x": "a b"}))
    assert stems == ["sampler.spp=64_materials.red.roughness=0.2", "sampler.spp=64_x=a-b"]
    # "a/b" and "a-b" would be one file, and so would "A" and "a" on a file system that ignores case.
    clashing = image_stems(_items({"x": "a/b"}, {"x": "a-b"}, {"y": "A"}, {"y": "a"}, {"y": "c"}))
    assert len({stem.casefold() for stem in clashing}) == 5
    assert clashing[-1] == "y=c"
    assert all("/" not in stem and " " not in stem for stem in clashing)
    long = image_stems(_items({"table": {"value": "v" * 400}}))[0]
    assert len(long) < 150


def test_a_render_sweep_writes_each_format_under_the_parameters_name(tmp_path, monkeypatch, capsys):
    """The PNG is the EXR's linear sRGB encoded with the sRGB curve (IEC 61966-2-1, written out here)."""
    (tmp_path / "screen.toml").write_text(emitting_screen(radiance="value = 0.5"))
    spec = tmp_path / "sweep.toml"
    spec.write_text(
        '[sweep]\nkind = "render"\nscene = "screen.toml"\nformats = ["exr", "png"]\n'
        '[grid]\n"sampler.seed" = [1, 2]\n"sampler.spp" = [4]\n'
    )
    out = tmp_path / "results"
    status, err = run_in_process(monkeypatch, capsys, ["sweep", str(spec), "-o", str(out), "-q"])
    assert status == 0, err
    rows = json.loads((out / "results.json").read_text())
    assert [row["image"] for row in rows] == [f"images/sampler.seed={s}_sampler.spp=4-image.exr" for s in (1, 2)]
    for row in rows:
        assert row["image_png"] == row["image"].replace(".exr", ".png")
        channels, _ = read_exr(out / row["image"])
        linear = np.clip(channels["RGB"].astype(float), 0.0, 1.0)
        encoded = np.where(linear <= 0.0031308, 12.92 * linear, 1.055 * linear ** (1 / 2.4) - 0.055)
        with PILImage.open(out / row["image_png"]) as png:
            assert np.max(np.abs(np.asarray(png, float) - encoded * 255)) <= 0.51
    bad = spec.read_text().replace('["exr", "png"]', '["exr", "bmp"]')
    spec.write_text(bad)
    status, err = run_in_process(monkeypatch, capsys, ["sweep", str(spec), "-o", str(out), "-q"])
    assert status == 2 and "sweep.formats" in err and len(err.strip().splitlines()) == 1
