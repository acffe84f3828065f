"""A Mitsuba sensor's far_clip: imported as the camera's far_clip (measured along the view axis, as Mitsuba's
perspective sensor sets each ray's maxt), exported back, and rendered as Mitsuba 3 renders the same XML: a wall
perpendicular to the view axis just inside the clip plane (its corners lie beyond the plane's distance along their
rays, so a clip along the ray would cut them), and a tilted panel the plane cuts in two, under a uniform sky."""

import numpy as np
import pytest

from replica_agreement import assert_replicas_agree, spectrace_replicas
from spectrace.engine.renderer import Renderer
from spectrace.errors import SpectraceError
from spectrace.interop.mitsuba import load_mitsuba_scene, mitsuba_scene_data
from spectrace.spectral import xyz_to_linear_srgb

SIZE = 32

SCENE = f"""<scene version="3.0.0">
  <integrator type="path"><integer name="max_depth" value="3"/></integrator>
  <sensor type="perspective"><float name="fov" value="60"/><float name="far_clip" value="$far"/>
    <transform name="to_world"><lookat origin="0, 0, 5" target="0, 0, 0" up="0, 1, 0"/></transform>
    <film type="hdrfilm"><integer name="width" value="{SIZE}"/><integer name="height" value="{SIZE}"/>
      <rfilter type="box"/></film></sensor>
  <shape type="rectangle"><transform name="to_world"><scale value="20"/></transform>
    <bsdf type="twosided"><bsdf type="diffuse"><rgb name="reflectance" value="0.6, 0.5, 0.4"/></bsdf></bsdf></shape>
  <shape type="rectangle">
    <transform name="to_world"><scale x="1.5" y="0.8"/><rotate y="1" angle="70"/><translate x="-0.6" z="1.5"/>
    </transform>
    <bsdf type="twosided"><bsdf type="diffuse"><rgb name="reflectance" value="0.2, 0.6, 0.7"/></bsdf></bsdf></shape>
  <emitter type="constant"><rgb name="radiance" value="0.5"/></emitter>
  <emitter type="point"><point name="position" x="0.5" y="1" z="3"/><rgb name="intensity" value="8"/></emitter>
</scene>"""


def _xml(tmp_path, far: str):
    path = tmp_path / f"far_{far}.xml"
    path.write_text(SCENE.replace("$far", far))
    return path


def test_far_clip_is_the_cameras(tmp_path):
    data, notes = mitsuba_scene_data(_xml(tmp_path, "4.2"))
    assert data["camera"]["far_clip"] == 4.2 and not any("far_clip" in note for note in notes)
    assert load_mitsuba_scene(_xml(tmp_path, "4.2")).camera.far_clip == 4.2
    with pytest.raises(SpectraceError, match="far_clip must be more than near_clip"):
        mitsuba_scene_data(_xml(tmp_path, "0"))


@pytest.mark.peer
def test_far_clip_is_exported(tmp_path, mitsuba_scalar_spectral):
    from spectrace.interop.mitsuba.export import scene_to_mitsuba_dict

    entry = scene_to_mitsuba_dict(load_mitsuba_scene(_xml(tmp_path, "4.2")), tmp_path)
    assert entry["sensor"]["far_clip"] == 4.2
    assert mitsuba_scalar_spectral.load_dict(entry) is not None  # Mitsuba takes the key


@pytest.mark.peer
@pytest.mark.slow
def test_far_clip_renders_as_in_mitsuba(tmp_path, device, mitsuba_scalar_spectral):
    """8 independent images from each renderer, of enough samples that the sky's colour noise (from sampling
    wavelengths) leaves the image mean's power under 5 %: 8 x 8-pixel block means and the image mean within 5
    standard errors (tests/replica_agreement.py). The plane at 5.2 keeps the whole wall (5 along the axis) and cuts
    the panel (3.5 to 6.5 along the axis); at 4.8 the wall is gone too."""
    mi = mitsuba_scalar_spectral
    replicas, replica_spp, block = 8, 160, 8
    corners = {}
    for far in ("5.2", "4.8"):
        path = _xml(tmp_path, far)
        theirs = mi.load_file(str(path))
        by_mitsuba = np.stack([np.array(mi.render(theirs, spp=replica_spp, seed=seed)) for seed in range(replicas)])
        ours = xyz_to_linear_srgb(spectrace_replicas(Renderer(load_mitsuba_scene(path), device), replicas, replica_spp))
        assert_replicas_agree(ours, by_mitsuba, block)
        corners[far] = by_mitsuba[:, :block, :block].mean()
    # Mitsuba keeps the wall's corners at 5.2 (a clip along the ray would show the sky there, as at 4.8).
    assert corners["4.8"] - corners["5.2"] > 0.1
