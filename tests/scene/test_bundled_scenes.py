"""Every bundled scene loads and renders (tiny, 1 spp): finite, non-negative, and not black."""

import numpy as np
import pytest

from spectrace.engine.renderer import Renderer
from spectrace.resources import scenes_dir
from spectrace.scene import load_scene

SCENES = sorted(p.name for p in scenes_dir().glob("*.toml"))


def test_there_are_bundled_scenes():
    assert "cornell_box.toml" in SCENES


@pytest.mark.parametrize("name", SCENES)
def test_bundled_scene_renders(device, name):
    scene = load_scene(scenes_dir() / name).with_overrides(width=12, height=9, spp=2)
    image = Renderer(scene, device).render()
    assert np.all(np.isfinite(image.xyz)) and np.all(image.xyz >= 0)
    assert image.xyz[..., 1].mean() > 0
