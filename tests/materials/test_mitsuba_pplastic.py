"""`pplastic` without polarisation renders as Mitsuba 3's unpolarised variants render Baek et al.'s polarised
plastic: a sphere of it (GGX and Beckmann, a tinted base) on a diffuse floor under a sky and a small lamp, exported
to Mitsuba 3 (scalar_spectral) and rendered by both, 8 replicas of 16 spp each, 8 x 8-pixel block means and the
image mean within 5 standard errors; the export imports back as the same material table."""

import numpy as np
import pytest

from replica_agreement import assert_replicas_agree, spectrace_replicas
from spectrace.engine.renderer import Renderer
from spectrace.interop.mitsuba.export import mitsuba_film_xyz, scene_to_mitsuba_dict
from spectrace.pixel_filters import BOX_FILTER
from spectrace.scene.loader import load_scene

SCENE = """
[camera]
origin = [0, 1, 4]
target = [0, 0.5, 0]
fov = 35

[film]
width = 16
height = 16

[integrator]
max_depth = 6

[materials.floor]
type = "diffuse"
reflectance = {{ value = 0.5 }}

[materials.black]
type = "diffuse"
reflectance = {{ value = 0 }}

[materials.ball]
type = "pplastic"
reflectance = {{ rgb = [0.7, 0.2, 0.1] }}
ior = 1.5
roughness = {alpha}
distribution = "{distribution}"

[[shapes]]
type = "rectangle"
material = "floor"
transform = [{{ scale = [5, 5, 1] }}, {{ rotate = {{ axis = [1, 0, 0], angle = -90 }} }}]

[[shapes]]
type = "sphere"
material = "ball"
transform = [{{ scale = 0.6 }}, {{ translate = [0, 0.6, 0] }}]

[[shapes]]
type = "sphere"
material = "black"
emitter = {{ radiance = {{ value = 6 }} }}
transform = [{{ scale = 0.4 }}, {{ translate = [1, 3, 1] }}]

[[lights]]
type = "constant"
radiance = {{ value = 1 }}
"""


@pytest.mark.peer
@pytest.mark.parametrize(("alpha", "distribution"), [(0.1, "ggx"), (0.3, "beckmann")])
def test_unpolarised_pplastic_renders_like_mitsuba(tmp_path, device, mitsuba_scalar_spectral, alpha, distribution):
    mi = mitsuba_scalar_spectral
    path = tmp_path / "scene.toml"
    path.write_text(SCENE.format(alpha=alpha, distribution=distribution))
    scene = load_scene(path).with_overrides(pixel_filter=BOX_FILTER)
    exported = scene_to_mitsuba_dict(scene, tmp_path, spp=16)
    mitsuba_scene = mi.load_dict(exported)
    by_mitsuba = np.stack([mitsuba_film_xyz(mi.render(mitsuba_scene, spp=16, seed=seed), mi) for seed in range(8)])
    assert_replicas_agree(spectrace_replicas(Renderer(scene, device), 8, 16), by_mitsuba, 8)
    assert by_mitsuba[..., 1].mean() > 0.05
