"""Mitsuba 3's bumpmap against spectrace's import of it, on a steep map: both take the exact gradient of the
bitmap's lookup (Mitsuba's bitmap `eval_1_grad`: the derivative of its bilinear interpolation, times the
resolution; zero for a nearest lookup, whose steps have no derivative) and tilt the frame by the same tangents
dp/du + scale · ∂h/∂u · n. Mitsuba's other default, `use_shadowing_function` (a darkening term of Conty Estevez et
al. 2019, docs/textures.md), is imported as spectrace's `shadowing_function`: both XML files are rendered as they
are, the term on (Mitsuba's default) and off; the camera looks
straight at the panel, so the viewer is never below the tilted planes (where Mitsuba's `flip_invalid_normals`
would mirror them)."""

import numpy as np
import pytest
from PIL import Image

from replica_agreement import assert_replicas_agree, spectrace_replicas
from spectrace.engine.renderer import Renderer
from spectrace.interop.mitsuba import load_mitsuba_scene
from spectrace.spectral import xyz_to_linear_srgb

SIZE = 32
SCENE = """<scene version="3.0.0">
  <integrator type="path"><integer name="max_depth" value="2"/></integrator>
  <sensor type="perspective"><float name="fov" value="40"/>
    <transform name="to_world"><lookat origin="0, 0, 3" target="0, 0, 0" up="0, 1, 0"/></transform>
    <film type="hdrfilm"><integer name="width" value="{size}"/><integer name="height" value="{size}"/>
      <rfilter type="box"/></film></sensor>
  <shape type="rectangle">
    <bsdf type="bumpmap"><texture type="bitmap" name="h"><string name="filename" value="heights.png"/>
      <boolean name="raw" value="true"/><string name="filter_type" value="{filter}"/></texture>
      <float name="scale" value="0.3"/>{switch}
      <bsdf type="diffuse"><rgb name="reflectance" value="0.7"/></bsdf></bsdf>
  </shape>
  <emitter type="directional"><vector name="direction" x="-1" y="-0.4" z="-0.5"/><rgb name="irradiance" value="3"/>
  </emitter>
</scene>"""
NO_SHADOWING = '<boolean name="use_shadowing_function" value="false"/>'


@pytest.mark.peer
@pytest.mark.parametrize(
    "filter_name, switch",
    [("bilinear", NO_SHADOWING), ("nearest", NO_SHADOWING), ("bilinear", "")],
    ids=["bilinear", "nearest", "bilinear, shadowing term"],
)
def test_a_steep_bump_map_renders_as_mitsuba_renders_it(tmp_path, device, mitsuba_scalar_spectral, filter_name, switch):
    """8 independent images each: 8 x 8-pixel block means and the image mean within 5 standard errors. The map is
    8 x 8 random 8-bit heights at scale 0.3 on the 2-unit panel: slopes up to about 50°. Forward differences over half
    a pixel (spectrace's rule before) tilted the nearest map's normals at its texel edges: about 5 % darker than
    Mitsuba's flat image of it. With Mitsuba's default shadowing term, its image is 3.5 % darker than without."""
    mi = mitsuba_scalar_spectral
    replicas, replica_spp, block = 8, 8, 8
    heights = np.random.default_rng(3).integers(0, 256, (8, 8)).astype(np.uint8)
    Image.fromarray(heights).save(tmp_path / "heights.png")
    path = tmp_path / "scene.xml"
    path.write_text(SCENE.format(size=SIZE, filter=filter_name, switch=switch))
    scene = mi.load_file(str(path))
    theirs = np.stack([np.array(mi.render(scene, spp=replica_spp, seed=seed)) for seed in range(replicas)])
    renderer = Renderer(load_mitsuba_scene(path), device)
    ours = xyz_to_linear_srgb(spectrace_replicas(renderer, replicas, replica_spp))
    assert_replicas_agree(ours, theirs, block)
