"""SPECTRACE_GENERAL_KERNELS=common (the suite's setting): the general kernels for the builds that most scenes share,
each scene's own kernels for a build with a film or polarisation define, whose general program few scenes would
share. Both give the same bits (the specialisation tests in test_scene_features.py)."""

import pytest

from spectrace.engine.renderer import Renderer, specialise_by_default
from spectrace.resources import scenes_dir
from spectrace.scene import load_scene


@pytest.mark.parametrize(
    ("value", "rare", "specialised"),
    [
        ("common", False, False),
        ("common", True, True),
        ("1", True, False),
        ("1", False, False),
        ("0", False, True),
        ("", True, True),
    ],
)
def test_the_setting_and_the_builds_variant_choose_the_kernels(monkeypatch, value, rare, specialised):
    monkeypatch.setenv("SPECTRACE_GENERAL_KERNELS", value)
    assert specialise_by_default(rare) is specialised


def test_under_common_a_film_with_aovs_gets_the_scenes_own_kernels_and_a_plain_film_the_general_ones(
    device, monkeypatch
):
    monkeypatch.setenv("SPECTRACE_GENERAL_KERNELS", "common")
    scene = load_scene(scenes_dir() / "cornell_box.toml").with_overrides(width=4, height=4, spp=1)
    plain = Renderer(scene, device)
    with_aovs = Renderer(scene.with_overrides(aovs=("albedo",)), device)
    assert plain.specialised is False and plain.feature_defines == {}
    assert with_aovs.specialised is True and with_aovs.feature_defines
    # An argument still wins over the setting.
    assert Renderer(scene, device, specialise=True).specialised is True
