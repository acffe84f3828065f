"""Mitsuba 0.6's bdpt and photon mappers (imported as spectrace's bdpt and sppm, which estimate whole pixels) with
Mitsuba's default Gaussian film filter: the import takes the box filter with a note, so the scene renders, and its
bdpt image agrees with Mitsuba 3's path tracer (which has no bdpt) rendering the same scene with the box filter.
Mitsuba's unbounded max_depth (its default, -1), which spectrace's bdpt cannot keep, becomes its longest, 16."""

import numpy as np
import pytest

from replica_agreement import assert_replicas_agree, spectrace_replicas
from spectrace.interop.mitsuba import load_mitsuba_scene, mitsuba_scene_data
from spectrace.spectral import xyz_to_linear_srgb


def _xml(folder, size: int, rfilter: str = ""):
    path = folder / "whole_pixels.xml"
    path.write_text(
        f"""<scene version="3.0.0">
<default name="integrator" value="bdpt"/>
<default name="depth" value="-1"/>
<integrator type="$integrator"><integer name="max_depth" value="$depth"/></integrator>
<sensor type="perspective"><float name="fov" value="60"/>
  <transform name="to_world"><lookat origin="0, -1.5, 1.5" target="0, 0, 0" up="0, 0, 1"/></transform>
  <film type="hdrfilm"><integer name="width" value="{size}"/><integer name="height" value="{size}"/>{rfilter}
  </film></sensor>
<shape type="rectangle"><transform name="to_world"><scale value="0.3"/><translate value="0, 0, 1"/></transform>
  <bsdf type="diffuse"><rgb name="reflectance" value="0"/></bsdf>
  <emitter type="area"><rgb name="radiance" value="8, 7, 6"/></emitter></shape>
<shape type="rectangle"><transform name="to_world"><scale value="2"/></transform>
  <bsdf type="diffuse"><rgb name="reflectance" value="0.6, 0.5, 0.4"/></bsdf></shape>
</scene>
"""
    )
    return path


@pytest.mark.parametrize("integrator", ["bdpt", "sppm", "photonmapper"])
def test_gaussian_filter_becomes_the_box_with_a_note(tmp_path, integrator):
    path = _xml(tmp_path, 8)
    data, notes = mitsuba_scene_data(path, parameters={"integrator": integrator})
    assert data["film"]["filter"] == {"type": "box"}
    assert any("estimates whole pixels" in note and "gaussian" in note for note in notes), notes
    path_data, path_notes = mitsuba_scene_data(path, parameters={"integrator": "path"})
    assert path_data["film"]["filter"]["type"] == "gaussian"  # the path tracer keeps Mitsuba's filter
    assert not any("whole pixels" in note for note in path_notes)


@pytest.mark.parametrize("depth, expected", [("-1", 16), ("40", 16), ("16", 16), ("3", 3)])
def test_bdpt_depth_beyond_its_subpaths_becomes_the_longest_it_keeps(tmp_path, depth, expected):
    data, notes = mitsuba_scene_data(_xml(tmp_path, 8), parameters={"depth": depth})
    assert data["integrator"]["max_depth"] == expected
    assert any(f"max_depth {depth} imported with max_depth 16" in note for note in notes) == (depth in ("-1", "40"))
    path_data = mitsuba_scene_data(_xml(tmp_path, 8), parameters={"depth": depth, "integrator": "path"})[0]
    assert path_data["integrator"]["max_depth"] == int(depth)  # the path tracer keeps any depth


@pytest.mark.peer
def test_bdpt_import_renders_like_mitsubas_path_tracer(tmp_path, device, mitsuba_scalar_spectral):
    """REPLICAS independent images each; 8 x 8-pixel block means and the image mean agree within 5 standard errors
    (tests/replica_agreement.py)."""
    mi = mitsuba_scalar_spectral
    replicas, replica_spp, size, block = 8, 12, 32, 8
    scene = mi.load_file(str(_xml(tmp_path, size, '<rfilter type="box"/>')), integrator="path")
    by_mitsuba = np.stack([np.array(mi.render(scene, spp=replica_spp, seed=seed)) for seed in range(replicas)])

    from spectrace.engine.renderer import Renderer

    renderer = Renderer(load_mitsuba_scene(_xml(tmp_path, size)), device)  # max_depth -1 as Mitsuba's default
    assert (renderer.scene.integrator, renderer.scene.max_depth) == ("bdpt", 16)
    xyz_replicas = spectrace_replicas(renderer, replicas, replica_spp)
    assert_replicas_agree(xyz_to_linear_srgb(xyz_replicas), by_mitsuba, block)
    assert by_mitsuba.mean() > 0.02  # the comparison saw a lit image
