"""Cycles' pixel filters as spectrace's (spectrace.interop.blender.cameras.pixel_filter), without Blender: each
against Cycles' own filter functions and width conventions (intern/cycles/scene/film.cpp: the table of a Gaussian
spans 3 widths, of a Blackman-Harris 2), integrated here."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from spectrace.interop.blender.cameras import pixel_filter


def _scene(kind: str, width: float):
    return SimpleNamespace(cycles=SimpleNamespace(pixel_filter_type=kind, filter_width=width))


def _cycles(kind: str, width: float, x: np.ndarray) -> np.ndarray:
    """Cycles' filter of user width `width` at offsets x (pixels), zero outside its table's span."""
    if kind == "BOX":
        span = width
        f = np.ones_like(x)
    elif kind == "GAUSSIAN":
        span = 3.0 * width
        f = np.exp(-2.0 * (x * 6.0 / span) ** 2)
    else:
        span = 2.0 * width
        v = 2.0 * math.pi * (x / span + 0.5)
        f = 0.35875 - 0.48829 * np.cos(v) + 0.14128 * np.cos(2 * v) - 0.01168 * np.cos(3 * v)
    return np.where(np.abs(x) <= span / 2.0, f, 0.0)


def _ours(table: dict, x: np.ndarray) -> np.ndarray:
    radius = table["radius"]
    if table["type"] == "box":
        return np.where(np.abs(x) <= radius, 1.0, 0.0)
    s = table["stddev"]
    return np.where(np.abs(x) <= radius, np.exp(-(x**2) / (2 * s * s)) - math.exp(-(radius**2) / (2 * s * s)), 0.0)


@pytest.mark.parametrize("kind", ["BOX", "GAUSSIAN", "BLACKMAN_HARRIS"])
@pytest.mark.parametrize("width", [1.0, 1.5, 3.0])
def test_each_cycles_filter_keeps_its_support_and_spread(kind, width):
    table = pixel_filter(_scene(kind, width))
    x = np.linspace(-3.0 * width, 3.0 * width, 120001)
    theirs, ours = _cycles(kind, width, x), _ours(table, x)
    spread = [np.sqrt(np.sum(f * x * x) / np.sum(f)) for f in (theirs, ours)]
    assert spread[1] == pytest.approx(spread[0], rel=0.005)
    assert x[theirs > 1e-3].max() == pytest.approx(x[ours > 1e-3].max(), rel=0.05)
    # the shapes, each normalised: Blackman-Harris differs from a Gaussian by a few % of the peak
    peak = (theirs / theirs.sum()).max()
    assert np.abs(theirs / theirs.sum() - ours / ours.sum()).max() <= 0.03 * peak


def test_a_scene_without_cycles_settings_keeps_spectraces_default():
    assert pixel_filter(SimpleNamespace()) is None
