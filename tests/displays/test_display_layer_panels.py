"""The QD-LCD vs white-LED-LCD panel scene (scenes/display_qd_vs_wled.toml): its display files are the layer
models' primaries as tests/tooling/display_layer_panels.py writes them, and each panel's rendered white and primaries
have the chromaticity colour-science computes from those spectra (CIE 1931 2°), within the render's noise."""

import tomllib
from pathlib import Path

import numpy as np
import pytest

from spectrace.engine.renderer import Renderer
from spectrace.scene import load_scene
from spectrace.spectral.display_catalog import load_display_csv
from spectrace.spectral.grid import GRID_NM
from stats_toolkit import assert_within_standard_errors

colour = pytest.importorskip("colour")

ROOT = Path(__file__).resolve().parents[2]
SCENE = ROOT / "scenes" / "display_qd_vs_wled.toml"
WIDTH, HEIGHT, SPP, GROUPS = 64, 32, 128, 9


def _xy(xyz: np.ndarray) -> np.ndarray:
    return xyz[..., :2] / xyz.sum(axis=-1, keepdims=True)


def _expected_xy(display_file: str, rgb) -> np.ndarray:
    """colour-science's xy of r·R + g·G + b·B read from the display file (its own CSV parsing: only the numbers)."""
    lines = (SCENE.parent / display_file).read_text(encoding="utf-8").splitlines()
    table = np.loadtxt([line for line in lines if not line.startswith("#")][1:], delimiter=",")
    assert np.array_equal(table[:, 0], GRID_NM)
    spectrum = table[:, 1:] @ np.asarray(rgb, np.float64)
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"].copy().align(colour.SpectralShape(360, 830, 1))
    sd = colour.SpectralDistribution(dict(zip(GRID_NM, spectrum)))
    return np.asarray(colour.XYZ_to_xy(colour.sd_to_XYZ(sd, cmfs=cmfs, method="Integration")))


def _pixels_inside(shape: dict, camera: dict) -> tuple[slice, slice]:
    """The film's rows and columns wholly inside a rectangle (its transform a scale then a translation, facing the
    camera on its axis), one pixel kept clear of each edge for the pixel filter."""
    (scale,), (translate,) = ([t[k] for t in shape["transform"] if k in t] for k in ("scale", "translate"))
    distance = camera["origin"][2] - translate[2]
    half_width = distance * np.tan(np.radians(camera["fov"]) / 2)
    half_height = half_width * HEIGHT / WIDTH
    x0, x1 = (translate[0] + s * scale[0] for s in (-1, 1))
    y0, y1 = (translate[1] - camera["origin"][1] + s * scale[1] for s in (-1, 1))
    columns = ((np.array([x0, x1]) / half_width + 1) / 2 * WIDTH).astype(float)
    rows = ((1 - np.array([y1, y0]) / half_height) / 2 * HEIGHT).astype(float)
    return slice(int(np.ceil(rows[0])) + 1, int(np.floor(rows[1])) - 1), slice(
        int(np.ceil(columns[0])) + 1, int(np.floor(columns[1])) - 1
    )


def test_each_panel_shows_its_layer_models_chromaticities(device):
    data = tomllib.loads(SCENE.read_text(encoding="utf-8"))
    overrides = {"film.width": WIDTH, "film.height": HEIGHT, "sampler.spp": SPP, "sampler.type": "independent"}
    xyz = Renderer(load_scene(SCENE, overrides), device).render().xyz.astype(np.float64)
    found = {}
    for shape in data["shapes"]:
        radiance = shape["emitter"]["radiance"]
        rows, columns = _pixels_inside(shape, data["camera"])
        pixels = xyz[rows, columns].reshape(-1, 3)
        assert len(pixels) >= 18, shape["name"]
        # xy of the region's mean, its standard error from the spread of the xy of groups of pixels (a ratio's
        # error is not the pixels' own)
        groups = np.array([_xy(group.mean(axis=0)) for group in np.array_split(pixels, GROUPS)])
        error = groups.std(axis=0, ddof=1) / np.sqrt(GROUPS)
        expected = _expected_xy(radiance["display"], radiance["rgb"])
        assert_within_standard_errors(_xy(pixels.mean(axis=0)), expected, error, what=shape["name"])
        assert np.all(error < 0.003), (shape["name"], error)  # 4 of them well below the panels' primaries' distances
        found[shape["name"]] = expected
    # The scene shows what its comment says: the same white, the dots' green far more saturated.
    assert np.linalg.norm(found["left white"] - found["right white"]) < 0.002
    assert found["right green"][1] - found["left green"][1] > 0.08


def test_the_display_files_load_as_relative_lcds():
    for stem in ("wled_yag_lcd", "qd_cdse_lcd"):
        display = load_display_csv(SCENE.parent / "display_layers" / f"{stem}.csv")
        assert not display.absolute and display.technology.startswith("LCD")


@pytest.mark.slow
def test_the_display_files_are_what_their_writer_writes():
    """A hand edit to a file, or a changed layer model not written out, fails here, naming the command."""
    from tests.tooling.display_layer_panels import FOLDER, panel_texts

    for stem, text in panel_texts().items():
        written = (FOLDER / f"{stem}.csv").read_text(encoding="utf-8")
        assert written == text, f"run `python -m tests.tooling.display_layer_panels` ({stem})"
