"""Blender's Specular IOR Level in the import (spectrace.interop.blender.materials): Cycles scales the dielectric
layer's F0 = ((IOR − 1)/(IOR + 1))² by 2 × level and uses the index of that F0; the principled material takes that
index as `eta`, or a level texture as its `specular` texture s = F0'/0.08. Checked here against that closed form;
the rendering against Cycles is test_blender_cycles.py's `specular_levels`. Skips where bpy is absent."""

from __future__ import annotations

import importlib.util
import math
import os
import subprocess
import sys
import tomllib
from pathlib import Path

import numpy as np
import pytest
from tests.cli_runner import run_spectrace

ROOT = Path(__file__).resolve().parents[2]
needs_bpy = pytest.mark.skipif(
    importlib.util.find_spec("bpy") is None,
    reason="bpy (Blender as a Python module, installed apart: pip install bpy) is absent",
)


def _f0(eta: float) -> float:
    return ((eta - 1.0) / (eta + 1.0)) ** 2


@needs_bpy
@pytest.mark.subprocess
@pytest.mark.slow
def test_specular_ior_level_gives_the_index_of_cycles_scaled_f0(tmp_path):
    from tests.interop.blender_comparisons import LEVELS

    blend, toml = tmp_path / "levels.blend", tmp_path / "levels.toml"
    env = os.environ.copy()
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(ROOT), env.get("PYTHONPATH")]))
    args = ["-m", "tests.interop.blender_comparisons", "specular_levels", str(blend), str(tmp_path / "c"), "1", "0"]
    built = subprocess.run([sys.executable, *args], capture_output=True, text=True, env=env, timeout=300, cwd=ROOT)
    assert built.returncode == 0, built.stderr[-2000:]
    done = run_spectrace("import-blend", str(blend), "-o", str(toml))
    assert done.returncode == 0, done.stderr
    assert "Specular IOR Level" not in done.stderr  # imported, not named as ignored
    materials = tomllib.loads(toml.read_text(encoding="utf-8"))["materials"]
    for i, level in enumerate(LEVELS):
        eta = materials[f"level{i}"]["eta"]
        if level == 0.0:
            assert eta == pytest.approx(1.0, abs=1e-3)  # no dielectric reflection: F0 below 1e-7
            assert _f0(eta) < 1e-7
        else:
            assert _f0(eta) == pytest.approx(2.0 * level * _f0(1.5), rel=1e-9)
    # the striped poster (IOR 1.45): its level image becomes s = 2 level F0(1.45) / 0.08 per texel, raw
    texture = materials["striped"]["specular"]
    assert "eta" not in materials["striped"] and texture["raw"] is True
    from PIL import Image

    with Image.open(toml.parent / texture["file"]) as image:
        codes = np.asarray(image.convert("L"), dtype=np.float64)[0]
    expected = [2.0 * level * _f0(1.45) / 0.08 for level in LEVELS]
    assert codes / 255.0 == pytest.approx(expected, abs=0.5 / 255.0)
    assert not math.isclose(expected[-1], LEVELS[-1])  # the IOR's F0 is part of the mapping
