"""The bundled Veach MIS scene (scenes/veach_mis.toml and .xml): both files describe the same scene, and its
export to Mitsuba 3 (rough conductors, analytic sphere lights) renders what spectrace renders."""

import numpy as np
import pytest

from replica_agreement import assert_replicas_agree, spectrace_replicas
from spectrace.engine.renderer import Renderer
from spectrace.interop.mitsuba import load_mitsuba_scene
from spectrace.interop.mitsuba.export import mitsuba_film_xyz, scene_to_mitsuba_dict
from spectrace.resources import scenes_dir
from spectrace.scene import load_scene


def test_the_xml_and_the_toml_render_the_same_bits(device):
    """The XML imported by spectrace is the TOML scene: same image bit for bit (48 x 32, 2 spp)."""
    toml = load_scene(scenes_dir() / "veach_mis.toml").with_overrides(width=48, height=32, spp=2)
    xml = load_mitsuba_scene(scenes_dir() / "veach_mis.xml").with_overrides(width=48, height=32, spp=2, max_depth=8)
    images = [Renderer(scene, device).render().xyz for scene in (toml, xml)]
    assert images[0].max() > 1.0  # the lights are in view
    assert np.array_equal(images[0], images[1])


def test_the_four_lights_emit_the_same_power():
    """Veach's lights: Φ = π · 4πr² · L equal for the four radii (within the published values' 6 digits)."""
    scene = load_scene(scenes_dir() / "veach_mis.toml")
    powers = [
        np.pi * 4 * np.pi * shape.analytic.to_world[0, 0] ** 2 * shape.emitter.radiance.values.mean()
        for shape in scene.shapes
        if shape.emitter is not None
    ]
    assert len(powers) == 4
    assert np.ptp(powers) <= 1e-3 * np.mean(powers)


@pytest.mark.peer
@pytest.mark.slow
def test_exported_veach_mis_renders_like_spectrace(tmp_path, device, mitsuba_scalar_spectral):
    """Direct light (max_depth 2) on rough and smooth aluminium plates from analytic sphere lights: REPLICAS
    independent images from each renderer, 8 x 8-pixel block means, the whole image and the plates (the rows below
    the lamps) within 5 standard errors. The export's roughconductor carries spectrace's η, k and α. The plates'
    mean is the quantity held to 5 %: the lamps seen directly are bright, few-pixel disks whose coverage noise says
    nothing about the plates' MIS estimates."""
    mi = mitsuba_scalar_spectral
    replicas, replica_spp, size, block = 16, 256, 32, 8
    scene = load_scene(scenes_dir() / "veach_mis.toml").with_overrides(width=size, height=size, max_depth=2)
    mitsuba_scene = mi.load_dict(scene_to_mitsuba_dict(scene, tmp_path, spp=replica_spp))
    by_mitsuba = np.stack(
        [mitsuba_film_xyz(mi.render(mitsuba_scene, spp=replica_spp, seed=seed), mi) for seed in range(replicas)]
    )
    by_spectrace = spectrace_replicas(Renderer(scene, device), replicas, replica_spp)
    plates = np.zeros((size, size), dtype=bool)
    plates[size * 3 // 8 :] = True
    assert_replicas_agree(by_spectrace, by_mitsuba, block, region=plates)
    assert by_mitsuba[..., 1].mean() > 0.05
