"""Mitsuba 3's defaults for what a scene leaves out: a shape without a bsdf reflects as `diffuse` 0.5, unless it
emits: then it reflects nothing (measured with Mitsuba 3: a lit emitter without a bsdf shows its emission alone)."""

import numpy as np
import pytest

from replica_agreement import assert_replicas_agree, spectrace_replicas
from spectrace.engine.renderer import Renderer
from spectrace.interop.mitsuba import load_mitsuba_scene, mitsuba_scene_data
from spectrace.spectral import xyz_to_linear_srgb

SIZE = 16

# Two squares without a bsdf facing the camera, the left one emitting, both lit by a point light before them.
SCENE = f"""<scene version="3.0.0">
  <integrator type="path"><integer name="max_depth" value="3"/></integrator>
  <sensor type="perspective"><float name="fov" value="40"/>
    <transform name="to_world"><lookat origin="0, 0, 5" target="0, 0, 0" up="0, 1, 0"/></transform>
    <film type="hdrfilm"><integer name="width" value="{SIZE}"/><integer name="height" value="{SIZE}"/>
      <rfilter type="box"/></film></sensor>
  <shape type="rectangle"><transform name="to_world"><scale value="0.7"/><translate x="-0.8"/></transform>
    <emitter type="area"><rgb name="radiance" value="0.2, 0.3, 0.4"/></emitter></shape>
  <shape type="rectangle"><transform name="to_world"><scale value="0.7"/><translate x="0.8"/></transform></shape>
  <emitter type="point"><point name="position" x="0" y="0" z="2"/><rgb name="intensity" value="4"/></emitter>
</scene>"""


def test_an_emitter_without_a_bsdf_is_black_and_other_shapes_diffuse(tmp_path):
    path = tmp_path / "defaults.xml"
    path.write_text(SCENE)
    data, _ = mitsuba_scene_data(path)
    emitting, plain = data["shapes"]
    assert "emitter" in emitting and "emitter" not in plain
    assert data["materials"][emitting["material"]] == {"type": "diffuse", "reflectance": {"value": 0.0}}
    # Mitsuba's default is its plain diffuse, black from the back.
    assert data["materials"][plain["material"]] == {
        "type": "diffuse",
        "reflectance": {"value": 0.5},
        "two_sided": False,
    }


@pytest.mark.peer
def test_shapes_without_a_bsdf_render_as_in_mitsuba(tmp_path, device, mitsuba_scalar_spectral):
    """REPLICAS independent images from each renderer: 8 x 8-pixel block means and the image mean within 5
    standard errors. Measured: largest block 1.4 standard errors; with the emitter reflecting as diffuse 0.5 (what
    the importer made of it before), 49."""
    mi = mitsuba_scalar_spectral
    replicas, replica_spp, block = 8, 8, 8
    path = tmp_path / "defaults.xml"
    path.write_text(SCENE)
    theirs = mi.load_file(str(path))
    by_mitsuba = np.stack([np.array(mi.render(theirs, spp=replica_spp, seed=seed)) for seed in range(replicas)])
    ours = xyz_to_linear_srgb(spectrace_replicas(Renderer(load_mitsuba_scene(path), device), replicas, replica_spp))
    assert_replicas_agree(ours, by_mitsuba, block)
