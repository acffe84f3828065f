"""Mitsuba's `normalmap` holding a `rawconstant` texture: one tangent-space normal 2 c − 1 everywhere. The importer
writes it as a 1 x 1 float image beside the TOML (the unturned normal, c = (0.5, 0.5, 1), as no map at all), and a
panel wearing it renders as Mitsuba 3 renders the same XML."""

import numpy as np
import pytest

from replica_agreement import assert_replicas_agree, spectrace_replicas
from spectrace.engine.renderer import Renderer
from spectrace.errors import SpectraceError
from spectrace.interop.mitsuba import import_mitsuba, load_mitsuba_scene, mitsuba_scene_data
from spectrace.spectral import xyz_to_linear_srgb

SIZE = 32


def _xml(folder, value: str, shadowing_off: str = ""):
    """shadowing_off: Mitsuba's switch that turns its normalmap's shadowing term off (on by default, imported as
    `shadowing_function`: tests/interop/test_mitsuba_normal_map_convention.py)."""
    x, y, z = (v.strip() for v in value.split(","))
    path = folder / f"normal_{x}_{y}_{z}{'_off' if shadowing_off else ''}.xml"
    path.write_text(
        f"""<scene version="3.0.0">
  <integrator type="path"><integer name="max_depth" value="3"/></integrator>
  <sensor type="perspective"><float name="fov" value="40"/>
    <transform name="to_world"><lookat origin="0, 0, 3" target="0, 0, 0" up="0, 1, 0"/></transform>
    <film type="hdrfilm"><integer name="width" value="{SIZE}"/><integer name="height" value="{SIZE}"/>
      <rfilter type="box"/></film></sensor>
  <shape type="rectangle">
    <bsdf type="normalmap">{shadowing_off}<texture type="rawconstant" name="normalmap">
      <vector name="value" x="{x}" y="{y}" z="{z}"/></texture>
      <bsdf type="twosided"><bsdf type="diffuse"><rgb name="reflectance" value="0.7"/></bsdf></bsdf></bsdf>
  </shape>
  <emitter type="directional"><vector name="direction" x="-1" y="-0.4" z="-0.5"/><rgb name="irradiance" value="3"/>
  </emitter>
</scene>"""
    )
    return path


def test_a_constant_normal_map_is_a_one_texel_image(tmp_path):
    data, _ = mitsuba_scene_data(_xml(tmp_path, "0.5, 0.5, 1"))  # Mitsuba 3's vector value (older: rgb)
    assert "normal_map" not in next(iter(data["materials"].values()))  # the unturned normal
    notes = import_mitsuba(_xml(tmp_path, "0.8, 0.4, 0.9"), tmp_path / "tilted.toml")
    assert any("rawconstant normal map" in note for note in notes)
    assert (tmp_path / "tilted.normal_map_1.exr").is_file()
    normal_map = load_mitsuba_scene(_xml(tmp_path, "0.8, 0.4, 0.9")).shapes[0].material.detail.normal_map
    np.testing.assert_allclose(normal_map.values.reshape(3), [0.8, 0.4, 0.9], rtol=1e-6)
    with pytest.raises(SpectraceError, match="holds no direction"):
        mitsuba_scene_data(_xml(tmp_path, "0.5, 0.5, 0.5"))


@pytest.mark.peer
@pytest.mark.slow
def test_a_constant_normal_map_renders_as_in_mitsuba(tmp_path, device, mitsuba_scalar_spectral):
    """8 independent images from each renderer: 8 x 8-pixel block means and the image mean within 5 standard
    errors, the same XML (Mitsuba's default shadowing term on) on both sides; the panel without its normal map
    disagrees with Mitsuba's image."""
    mi = mitsuba_scalar_spectral
    replicas, replica_spp, block = 8, 4, 8
    tilted = _xml(tmp_path, "0.8, 0.4, 0.9")
    theirs = mi.load_file(str(tilted))
    by_mitsuba = np.stack([np.array(mi.render(theirs, spp=replica_spp, seed=seed)) for seed in range(replicas)])

    def ours(path) -> np.ndarray:
        return xyz_to_linear_srgb(spectrace_replicas(Renderer(load_mitsuba_scene(path), device), replicas, replica_spp))

    assert_replicas_agree(ours(tilted), by_mitsuba, block)
    with pytest.raises(AssertionError):
        assert_replicas_agree(ours(_xml(tmp_path, "0.5, 0.5, 1")), by_mitsuba, block)
