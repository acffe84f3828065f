"""Blender's Translucent BSDF (Lambertian transmission alone, Color/π to the other side) imported as the thin
principled sheet that transmits all of its diffuse part, and rendered against its closed form: a grey sheet of
colour c under a sun of S W/m² seen from below has radiance c S / π."""

from __future__ import annotations

import math

import numpy as np
import pytest
from tests.interop.test_blender_import import _import, needs_bpy

from replica_agreement import spectrace_replicas


@needs_bpy
@pytest.mark.subprocess
@pytest.mark.slow
def test_a_translucent_sheet_is_principledthin_and_transmits_c_s_over_pi(tmp_path, device):
    from spectrace.engine.renderer import Renderer
    from spectrace.scene import load_scene

    toml, data = _import(tmp_path, "translucent")
    assert data["materials"]["leaf"] == {
        "type": "principledthin",
        "base_color": {"rgb": [0.5, 0.5, 0.5]},
        "diff_trans": 2.0,
    }
    scene = load_scene(toml).with_overrides(max_depth=2)
    images = spectrace_replicas(Renderer(scene, device), 8, 16)
    h, w = images.shape[1:3]
    centre = images[:, h // 2 - 4 : h // 2 + 4, w // 2 - 4 : w // 2 + 4, 1].mean(axis=(1, 2))
    mean, error = centre.mean(), centre.std(ddof=1) / math.sqrt(len(centre))
    expected = 0.5 * 2.0 / math.pi  # the builder's grey 0.5 under a sun of 2 W/m²
    assert abs(mean - expected) <= 4.0 * error + 5e-3 * expected, (mean, error, expected)
    assert np.all(images[:, 0, 0, 1] == 0.0)  # around the sheet: the black world
